//! A membrane opens in side view (issue 30 section 3): when a frame has a lipid representation
//! (the default one, `lipid`) whose atoms lie in a layer, the camera turns so the layer's normal
//! is up on screen and looks along the layer, from the side the macromolecule sits on. The
//! window does it on its first surface and on Reset view, `mdsurf render` on its first frame.

use glam::{DMat3, DVec3, Vec3};

use super::worker::Computed;
use crate::render::Camera;
use crate::scene::defaults::{LIPID, MACROMOLECULE};

/// A layer is flat enough when its thinnest spread (standard deviation along the normal) is
/// at most this fraction of the next one (YiiP's membrane: about 0.4).
pub const FLATNESS: f64 = 0.6;

/// Lipid atoms needed before a layer is looked for.
const MIN_ATOMS: usize = 100;

/// The normal of the layer `points` form (Å): the direction of least spread (the covariance's
/// smallest eigenvector), or `None` when they form no layer (fewer than [`MIN_ATOMS`] points,
/// or a thinnest spread above [`FLATNESS`] times the next).
pub fn layer_normal(points: &[Vec3]) -> Option<Vec3> {
    let finite: Vec<DVec3> = points
        .iter()
        .filter(|p| p.is_finite())
        .map(|p| p.as_dvec3())
        .collect();
    if finite.len() < MIN_ATOMS {
        return None;
    }
    let n = finite.len() as f64;
    let mean = finite.iter().copied().sum::<DVec3>() / n;
    let mut c = DMat3::ZERO;
    for p in &finite {
        let d = *p - mean;
        c += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    c *= 1.0 / n;
    let (values, vectors) = symmetric_eigen(c);
    // values ascending: [thinnest, middle, widest].
    if values[0] < 0.0 || values[1] <= 0.0 || values[0].sqrt() > FLATNESS * values[1].sqrt() {
        return None;
    }
    Some(vectors[0].as_vec3().normalize())
}

/// Eigenvalues (ascending) and unit eigenvectors of a symmetric 3 x 3 matrix.
fn symmetric_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let (values, v) = crate::transform::fit::jacobi_eigen(m.to_cols_array_2d());
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    let vectors = order.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]).normalize());
    (order.map(|i| values[i]), vectors)
}

/// Turns `camera` to the side view of the membrane in `c`, when it has one; returns true when
/// it did. The macromolecule's side of the membrane faces the camera.
pub fn orient_to_membrane(camera: &mut Camera, c: &Computed) -> bool {
    let points = |selection: &str| -> Vec<Vec3> {
        c.layers
            .iter()
            .filter(|l| l.rep.selection == selection)
            .flat_map(|l| l.particles.positions.iter().copied())
            .collect()
    };
    orient_to_layer(camera, &points(LIPID), &points(MACROMOLECULE))
}

/// Turns `camera` to the side view of the layer the `lipids` (Å) form, from the side the
/// `protein` atoms (Å; may be empty) lie on; returns false, leaving the camera, when the lipids
/// form no layer ([`layer_normal`]). `mdsurf render` calls it with its layers' atoms.
pub fn orient_to_layer(camera: &mut Camera, lipids: &[Vec3], protein: &[Vec3]) -> bool {
    let Some(normal) = layer_normal(lipids) else {
        return false;
    };
    let centre = |points: &[Vec3]| points.iter().copied().sum::<Vec3>() / points.len() as f32;
    let front = if protein.is_empty() {
        Vec3::ZERO
    } else {
        centre(protein) - centre(lipids)
    };
    camera.side_view(normal, front);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_of_a_diagonal_and_a_rotated_matrix() {
        let (vals, vecs) = symmetric_eigen(DMat3::from_diagonal(DVec3::new(5.0, 1.0, 3.0)));
        assert!((vals[0] - 1.0).abs() < 1e-12 && (vals[2] - 5.0).abs() < 1e-12);
        assert!((vecs[0].dot(DVec3::Y).abs() - 1.0).abs() < 1e-9);
        // A slab 100 x 80 Å wide and 10 Å thick, tilted.
        let r = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 0.2);
        let mut points = Vec::new();
        for i in 0..20 {
            for j in 0..16 {
                for k in 0..3 {
                    let p = DVec3::new(i as f64 * 5.0, j as f64 * 5.0, k as f64 * 5.0);
                    points.push((r * p).as_vec3());
                }
            }
        }
        let n = layer_normal(&points).expect("a layer");
        let want = (r * DVec3::Z).as_vec3();
        assert!(n.dot(want).abs() > 0.999, "{n} vs {want}");
        // A cube is no layer.
        let cube: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32))
            .collect();
        assert!(layer_normal(&cube).is_none());
    }

    #[test]
    fn side_view_puts_the_normal_up_and_looks_from_the_front() {
        let mut cam = Camera::default();
        cam.side_view(Vec3::Z, Vec3::new(0.0, -3.0, 1.0));
        assert!(cam.up().dot(Vec3::Z) > 0.999, "up {}", cam.up());
        assert!(cam.back().dot(Vec3::Z).abs() < 1e-5);
        assert!(cam.back().dot(-Vec3::Y) > 0.999, "back {}", cam.back());
        // Orbiting turns about the normal.
        cam.orbit(0.5, 0.0);
        assert!(cam.back().dot(Vec3::Z).abs() < 1e-5);
        assert!(cam.up().dot(Vec3::Z) > 0.999);
    }
}
