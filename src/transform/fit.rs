//! Least-squares fitting: each frame is turned and moved so that a selection lies as close as
//! possible (weighted RMSD) to the same atoms of a reference frame.
//!
//! The rotation comes from Horn's quaternion method (J. Opt. Soc. Am. A 4, 629, 1987): the
//! best rotation is the unit quaternion of the largest eigenvalue of a symmetric 4x4 matrix
//! built from the 3x3 correlation matrix. It is chosen over Kabsch's SVD because glam has no
//! SVD, a 4x4 symmetric eigenproblem is easy to solve robustly (Jacobi rotations, in f64), and
//! the quaternion is always a proper rotation (Kabsch needs a reflection fix-up).

use glam::{DMat3, DQuat, DVec3, Mat3, Vec3};

/// A reference for fitting: its selected atoms (centred) and their weights.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Atoms fitted (sorted 0-based indices).
    indices: Vec<u32>,
    /// Weight of each fitted atom (masses, or 1).
    weights: Vec<f64>,
    /// The reference positions of the fitted atoms minus their centre (Å).
    reference: Vec<DVec3>,
    /// The weighted centre of the reference selection (Å).
    centre: DVec3,
}

impl Fit {
    /// A fit of atoms `indices` onto their positions in `reference` (Å); `masses` (amu, one
    /// per atom) weigh the fit when every fitted atom has a positive mass. `None` when
    /// `indices` is empty or names atoms `reference` lacks.
    pub fn new(indices: Vec<u32>, reference: &[Vec3], masses: &[f32]) -> Option<Fit> {
        if indices.is_empty() || indices.iter().any(|&i| i as usize >= reference.len()) {
            return None;
        }
        let weighted =
            masses.len() == reference.len() && indices.iter().all(|&i| masses[i as usize] > 0.0);
        let weights: Vec<f64> = indices
            .iter()
            .map(|&i| {
                if weighted {
                    masses[i as usize] as f64
                } else {
                    1.0
                }
            })
            .collect();
        let centre = weighted_centre(reference, &indices, &weights);
        let reference = indices
            .iter()
            .map(|&i| reference[i as usize].as_dvec3() - centre)
            .collect();
        Some(Fit {
            indices,
            weights,
            reference,
            centre,
        })
    }

    /// The rotation `R` and the centre `c` of the fitted atoms in `positions` such that
    /// `R (p - c) + reference centre` superposes them on the reference.
    pub fn superposition(&self, positions: &[Vec3]) -> (DMat3, DVec3) {
        let centre = weighted_centre(positions, &self.indices, &self.weights);
        // Correlation S_ab = sum w x_a y_b (x: this frame, y: the reference).
        let mut s = [[0.0f64; 3]; 3];
        for ((&i, &w), y) in self.indices.iter().zip(&self.weights).zip(&self.reference) {
            let x = positions[i as usize].as_dvec3() - centre;
            let (x, y) = (x.to_array(), y.to_array());
            for a in 0..3 {
                for b in 0..3 {
                    s[a][b] += w * x[a] * y[b];
                }
            }
        }
        (rotation_from_correlation(&s), centre)
    }

    /// Turns and moves all `positions` (Å) so that the fitted atoms lie on the reference;
    /// `cell` (the box) turns with them. Returns the rotation applied.
    pub fn apply(&self, positions: &mut [Vec3], cell: Option<&mut [Vec3; 3]>) -> Mat3 {
        let (r, centre) = self.superposition(positions);
        let rf = r.as_mat3();
        let (c, t) = (centre.as_vec3(), self.centre.as_vec3());
        for p in positions.iter_mut() {
            *p = rf * (*p - c) + t;
        }
        if let Some(cell) = cell {
            for v in cell.iter_mut() {
                *v = rf * *v;
            }
        }
        rf
    }
}

fn weighted_centre(positions: &[Vec3], indices: &[u32], weights: &[f64]) -> DVec3 {
    let (mut sum, mut total) = (DVec3::ZERO, 0.0);
    for (&i, &w) in indices.iter().zip(weights) {
        sum += positions[i as usize].as_dvec3() * w;
        total += w;
    }
    sum / total
}

/// The rotation minimising `sum w |R x - y|²` from the correlation `s[a][b] = sum w x_a y_b`
/// of centred point sets (Horn 1987).
pub fn rotation_from_correlation(s: &[[f64; 3]; 3]) -> DMat3 {
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = *s;
    let n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (values, vectors) = jacobi_eigen(n);
    let best = (0..4)
        .max_by(|&a, &b| values[a].total_cmp(&values[b]))
        .unwrap_or(0);
    let q = [
        vectors[0][best],
        vectors[1][best],
        vectors[2][best],
        vectors[3][best],
    ];
    let quat = DQuat::from_xyzw(q[1], q[2], q[3], q[0]);
    if !quat.is_finite() || quat.length_squared() < 1e-24 {
        return DMat3::IDENTITY;
    }
    DMat3::from_quat(quat.normalize())
}

/// Eigenvalues and eigenvectors (columns of the returned matrix: `v[k][i]` is component k of
/// vector i) of a symmetric N x N matrix, by cyclic Jacobi rotations. Unordered.
pub(crate) fn jacobi_eigen<const N: usize>(mut a: [[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut v = [[0.0f64; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..N)
            .flat_map(|p| (p + 1..N).map(move |q| (p, q)))
            .map(|(p, q)| a[p][q] * a[p][q])
            .sum();
        let scale: f64 = (0..N).map(|i| a[i][i] * a[i][i]).sum::<f64>() + off;
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for (k, (apk, aqk)) in row_p.into_iter().zip(row_q).enumerate() {
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    (std::array::from_fn(|i| a[i][i]), v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_rigid_motion() {
        let reference: Vec<Vec3> = (0..40)
            .map(|i| {
                let t = i as f32 * 0.7;
                Vec3::new(10.0 * t.cos(), 8.0 * (1.3 * t).sin(), 0.5 * t)
            })
            .collect();
        let rot = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 2.4);
        let moved: Vec<Vec3> = reference
            .iter()
            .map(|&p| rot * p + Vec3::new(30.0, -4.0, 12.0))
            .collect();
        let masses: Vec<f32> = (0..40).map(|i| 1.0 + (i % 3) as f32 * 5.0).collect();
        let fit = Fit::new((0..40).collect(), &reference, &masses).expect("fit");
        let mut p = moved.clone();
        let mut cell = [Vec3::X * 50.0, Vec3::Y * 50.0, Vec3::Z * 50.0];
        fit.apply(&mut p, Some(&mut cell));
        for (a, b) in p.iter().zip(&reference) {
            assert!((*a - *b).length() < 1e-4, "{a} {b}");
        }
        assert!((cell[0] - rot.inverse() * Vec3::X * 50.0).length() < 1e-3);
    }

    #[test]
    fn a_half_turn_is_found() {
        // A 180° turn makes the largest eigenvalue's quaternion have q0 = 0.
        let reference = vec![
            Vec3::X,
            Vec3::Y * 2.0,
            Vec3::Z * 3.0,
            Vec3::new(1.0, 1.0, 1.0),
        ];
        let rot = glam::Quat::from_rotation_z(std::f32::consts::PI);
        let moved: Vec<Vec3> = reference.iter().map(|&p| rot * p).collect();
        let fit = Fit::new(vec![0, 1, 2, 3], &reference, &[]).expect("fit");
        let mut p = moved;
        fit.apply(&mut p, None);
        for (a, b) in p.iter().zip(&reference) {
            assert!((*a - *b).length() < 1e-5, "{a} {b}");
        }
    }
}
