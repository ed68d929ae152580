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
    from_columns(matrix_of(lengths, angles))
}

/// The box matrix of `lengths` (Å) and `angles` (degrees), box vectors as its columns, as
/// chemfiles builds it (no checks; angles within [`ROUGHLY_RIGHT`] of 90° all made 90°).
fn matrix_of(lengths: [f64; 3], angles: [f64; 3]) -> DMat3 {
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
    DMat3::from_cols(
        DVec3::new(a, 0.0, 0.0),
        DVec3::new(cos(gamma) * b, sin(gamma) * b, 0.0),
        DVec3::new(cx * c, cy * c, cz * c),
    )
}

/// The box of a PDB `CRYST1` record or an mmCIF `_cell` (lengths in Å, angles in degrees) as
/// rows a, b, c, exactly as the chemfiles path turned such a record into a box: refused (the
/// reason) for negative lengths or 0°, negative or ≥ 180° angles, left-handed vectors, or
/// degenerate vectors at right angles that are not along the axes; `None` (no box) for an
/// all-zero box and for a box whose rows are not finite (NaN or infinite numbers, or angles no
/// box can have together), where chemfiles kept an unusable cell.
pub(crate) fn from_record(
    lengths: [f64; 3],
    angles: [f64; 3],
) -> Result<Option<[Vec3; 3]>, CellError> {
    // Comparisons false for NaN: a NaN passes these checks, as in chemfiles.
    if lengths.iter().any(|l| *l < 0.0) {
        return Err(CellError::NegativeLength(lengths));
    }
    if angles
        .iter()
        .any(|a| *a < 0.0 || a.abs() < ROUGHLY_ZERO || *a >= 180.0)
    {
        return Err(CellError::BadAngle(angles));
    }
    // In chemfiles' order; a NaN entry passes the first two checks and makes the rows unusable.
    let matrix = matrix_of(lengths, angles);
    if matrix.determinant() < 0.0 {
        return Err(CellError::LeftHanded);
    }
    if looks_orthorhombic_but_is_not_diagonal(matrix) {
        return Err(CellError::BadAngle(angles));
    }
    let zero = |v: f64| v.abs() < ROUGHLY_ZERO;
    let [x, y, z] = [matrix.x_axis, matrix.y_axis, matrix.z_axis];
    let diagonal = is_diagonal(matrix);
    if diagonal && zero(x.x) && zero(y.y) && zero(z.z) {
        return Ok(None);
    }
    let rows = [x, y, z].map(|v| v.as_vec3());
    Ok(rows.iter().all(|r| r.is_finite()).then_some(rows))
}

/// True when every off-diagonal element of `matrix` is (roughly) zero.
fn is_diagonal(matrix: DMat3) -> bool {
    let zero = |v: f64| v.abs() < ROUGHLY_ZERO;
    let [x, y, z] = [matrix.x_axis, matrix.y_axis, matrix.z_axis];
    zero(x.y) && zero(x.z) && zero(y.x) && zero(y.z) && zero(z.x) && zero(z.y)
}

/// chemfiles' last refusal: box vectors (the columns of `matrix`, Å) whose angles are all
/// (roughly) 90°, or undefined next to a zero-length vector, in a matrix that is not diagonal
/// (a box with degenerate, nearly zero vectors).
fn looks_orthorhombic_but_is_not_diagonal(matrix: DMat3) -> bool {
    let zero = |v: f64| v.abs() < ROUGHLY_ZERO;
    let [x, y, z] = [matrix.x_axis, matrix.y_axis, matrix.z_axis];
    let diagonal = is_diagonal(matrix);
    if diagonal || [x, y, z].iter().all(|v| zero(v.length())) {
        return false;
    }
    // The angle between two vectors in degrees, NaN when one has zero length.
    let angle = |u: DVec3, v: DVec3| (u.dot(v) / (u.length() * v.length())).acos().to_degrees();
    [angle(y, z), angle(x, z), angle(x, y)]
        .iter()
        .all(|a| a.is_nan() || (a - 90.0).abs() < ROUGHLY_RIGHT)
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
    let diagonal = is_diagonal(matrix);
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

    /// `from_record` against chemfiles' `UnitCell::triclinic` (the CRYST1 and `_cell` path it
    /// replaces): the same rows bit for bit, `None` where chemfiles has no usable box, and a
    /// refusal where chemfiles throws (a panic in its binding).
    #[cfg(feature = "chemfiles")]
    #[test]
    fn records_give_the_boxes_chemfiles_gives() {
        let lengths = [0.0, 1e-6, 3.5, 10.0, 57.3, -1.0, f64::NAN, f64::INFINITY];
        let angles = [
            90.0,
            89.9995,
            60.0,
            100.0,
            120.0,
            179.9,
            0.0,
            -5.0,
            180.0,
            f64::NAN,
        ];
        let mut compared = 0;
        for &a in &lengths {
            for &b in &lengths[1..5] {
                for &alpha in &angles {
                    for &gamma in &angles[..6] {
                        let (lengths, angles) = ([a, b, 12.0], [alpha, 75.0, gamma]);
                        let theirs = crate::io::quiet::silenced(|| {
                            let cell = chemfiles::UnitCell::triclinic(lengths, angles);
                            if cell.shape() == chemfiles::CellShape::Infinite {
                                return None;
                            }
                            let m = cell.matrix();
                            let column = |j: usize| {
                                Vec3::new(m[0][j] as f32, m[1][j] as f32, m[2][j] as f32)
                            };
                            let rows = [column(0), column(1), column(2)];
                            rows.iter().all(|r| r.is_finite()).then_some(rows)
                        });
                        let ours = from_record(lengths, angles);
                        match (theirs, ours) {
                            (Ok(theirs), Ok(ours)) => {
                                assert_eq!(ours, theirs, "{lengths:?} {angles:?}")
                            }
                            (Err(()), Err(_)) => {}
                            (theirs, ours) => {
                                panic!(
                                    "{lengths:?} {angles:?}: chemfiles {theirs:?}, ours {ours:?}"
                                )
                            }
                        }
                        compared += 1;
                    }
                }
            }
        }
        assert_eq!(compared, 8 * 4 * 10 * 6);
    }
}
