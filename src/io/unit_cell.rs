//! Periodic boxes given as three lengths (Å) and three angles (degrees), as DCD and Amber
//! NetCDF files store them, turned into box rows the way chemfiles builds its `UnitCell`: `a`
//! along x, `b` in the xy plane, and the same tolerances (an all-zero box is no box, angles
//! within 0.001° of 90 are exactly 90) and the same refusals (negative lengths, 0° or ≥ 180°
//! angles), so our readers and chemfiles agree on every file.

use glam::{DMat3, DVec3, Vec3};

/// Below this a length or matrix entry counts as zero (chemfiles' tolerance).
const ROUGHLY_ZERO: f64 = 1e-5;

/// Within this of 90° an angle counts as right (degrees; chemfiles' tolerance).
const ROUGHLY_RIGHT: f64 = 1e-3;

/// Lengths, angles or vectors no periodic box can have.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CellError {
    /// A negative (or NaN) edge length (Å).
    #[error("the box has a negative length {0:?}")]
    NegativeLength([f64; 3]),
    /// An angle of 0°, 180° or more, negative or NaN (degrees).
    #[error("the box has an angle no box can have {0:?} (degrees)")]
    BadAngle([f64; 3]),
    /// Box vectors with a negative determinant.
    #[error("the box vectors are left-handed (negative determinant)")]
    LeftHanded,
    /// A box row that is not finite.
    #[error("the box has a non-finite length or angle")]
    NonFinite,
}

/// The box with edge lengths `lengths` (Å) and angles `angles` (degrees: alpha between b and
/// c, beta between a and c, gamma between a and b) as rows a, b, c in Å; `None` when every
/// length is (roughly) zero, the files' way of saying "no box". Fails with the reason for
/// lengths or angles no box can have.
pub(crate) fn from_lengths_angles(
    lengths: [f64; 3],
    angles: [f64; 3],
) -> Result<Option<[Vec3; 3]>, CellError> {
    if lengths.iter().any(|l| l.is_nan() || *l < 0.0) {
        return Err(CellError::NegativeLength(lengths));
    }
    if angles
        .iter()
        .any(|a| a.is_nan() || *a < 0.0 || a.abs() < ROUGHLY_ZERO || *a >= 180.0)
    {
        return Err(CellError::BadAngle(angles));
    }
    let angles = if angles.iter().all(|a| (a - 90.0).abs() < ROUGHLY_RIGHT) {
        [90.0; 3]
    } else {
        angles
    };
    let [a, b, c] = lengths;
    // Radians as chemfiles computes them (`x × π / 180`), so the f32 rows match bit for bit.
    let radians = |deg: f64| deg * std::f64::consts::PI / 180.0;
    let cos = |deg: f64| radians(deg).cos();
    let sin = |deg: f64| radians(deg).sin();
    let [alpha, beta, gamma] = angles;
    let cx = cos(beta);
    let cy = (cos(alpha) - cos(beta) * cos(gamma)) / sin(gamma);
    let cz = (1.0 - cx * cx - cy * cy).sqrt();
    // Columns are the box vectors, as chemfiles holds them.
    let matrix = DMat3::from_cols(
        DVec3::new(a, 0.0, 0.0),
        DVec3::new(cos(gamma) * b, sin(gamma) * b, 0.0),
        DVec3::new(cx * c, cy * c, cz * c),
    );
    from_columns(matrix)
}

/// The box whose vectors are the columns of `matrix` (Å) as rows a, b, c, with chemfiles'
/// checks: a negative determinant is refused, a diagonal matrix with a zero diagonal is no box.
pub(crate) fn from_columns(matrix: DMat3) -> Result<Option<[Vec3; 3]>, CellError> {
    let determinant = matrix.determinant();
    if determinant.is_nan() || determinant < 0.0 {
        return Err(CellError::LeftHanded);
    }
    let zero = |v: f64| v.abs() < ROUGHLY_ZERO;
    let [x, y, z] = [matrix.x_axis, matrix.y_axis, matrix.z_axis];
    let diagonal = zero(x.y) && zero(x.z) && zero(y.x) && zero(y.z) && zero(z.x) && zero(z.y);
    if diagonal && zero(x.x) && zero(y.y) && zero(z.z) {
        return Ok(None);
    }
    let rows = [x, y, z].map(|v| v.as_vec3());
    if rows.iter().any(|r| !r.is_finite()) {
        return Err(CellError::NonFinite);
    }
    Ok(Some(rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_boxes_are_diagonal_and_zero_boxes_are_none() {
        let rows = from_lengths_angles([10.0, 20.0, 30.0], [90.0, 90.0, 90.0])
            .expect("valid")
            .expect("a box");
        assert_eq!(rows[0], Vec3::new(10.0, 0.0, 0.0));
        assert!(rows[1].x.abs() < 1e-5 && (rows[1].y - 20.0).abs() < 1e-5);
        assert!((rows[2].z - 30.0).abs() < 1e-5);
        assert_eq!(from_lengths_angles([0.0; 3], [90.0; 3]), Ok(None));
        assert_eq!(
            from_lengths_angles([1.0; 3], [0.0, 90.0, 90.0]),
            Err(CellError::BadAngle([0.0, 90.0, 90.0]))
        );
        assert_eq!(
            from_lengths_angles([-1.0, 1.0, 1.0], [90.0; 3]),
            Err(CellError::NegativeLength([-1.0, 1.0, 1.0]))
        );
    }

    #[test]
    fn triclinic_box_keeps_its_lengths_and_angles() {
        let rows = from_lengths_angles([10.0, 11.0, 12.0], [70.0, 80.0, 100.0])
            .expect("valid")
            .expect("a box");
        let [a, b, c] = rows.map(|r| r.as_dvec3());
        assert!((b.length() - 11.0).abs() < 1e-4 && (c.length() - 12.0).abs() < 1e-4);
        let angle = |u: DVec3, v: DVec3| u.angle_between(v).to_degrees();
        assert!((angle(b, c) - 70.0).abs() < 1e-3);
        assert!((angle(a, c) - 80.0).abs() < 1e-3);
        assert!((angle(a, b) - 100.0).abs() < 1e-3);
    }
}
