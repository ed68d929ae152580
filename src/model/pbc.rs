//! Periodic-cell arithmetic shared by the transforms and the bond guesser: fractional coordinates, minimum images
//! and lattice shifts for orthorhombic and triclinic boxes (rows a, b, c in Å, as
//! [`crate::model::Frame::cell`] holds them).

use glam::{Mat3, Vec3};

/// Boxes narrower than this (Å) in any direction are not treated as periodic boxes (the
/// model's [`crate::model::MIN_BOX_WIDTH`], which `within` selections use too).
pub const MIN_WIDTH: f32 = crate::model::MIN_BOX_WIDTH;

/// A periodic box with its inverse, for converting between Cartesian (Å) and fractional
/// coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PbcCell {
    /// Columns are the edge vectors a, b, c (Å).
    m: Mat3,
    /// Inverse of `m`: Cartesian to fractional.
    inv: Mat3,
}

impl PbcCell {
    /// The cell with edge vectors `rows` (a, b, c in Å); `None` when they are not finite, span
    /// no volume (a zero or flat box), or the box is narrower than [`MIN_WIDTH`] in some
    /// direction (a placeholder such as PDB's `CRYST1 1 1 1`, not a simulation box).
    pub fn new(rows: &[Vec3; 3]) -> Option<PbcCell> {
        let m = Mat3::from_cols(rows[0], rows[1], rows[2]);
        let det = m.determinant();
        let scale = rows[0].length() * rows[1].length() * rows[2].length();
        if !det.is_finite() || scale <= 0.0 || det.abs() <= 1e-6 * scale {
            return None;
        }
        let cell = PbcCell {
            m,
            inv: m.inverse(),
        };
        (cell.widths().min_element() >= MIN_WIDTH).then_some(cell)
    }

    /// The cell of `frame`, if it has a usable one.
    pub fn of(frame: &crate::model::Frame) -> Option<PbcCell> {
        frame.cell.as_ref().and_then(PbcCell::new)
    }

    /// Fractional coordinates of `p` (Å).
    #[inline]
    pub fn fractional(&self, p: Vec3) -> Vec3 {
        self.inv * p
    }

    /// The Cartesian vector (Å) of fractional (or integer lattice) coordinates `f`.
    #[inline]
    pub fn cartesian(&self, f: Vec3) -> Vec3 {
        self.m * f
    }

    /// The lattice vector (in cell units, whole numbers) nearest to `d` (Å): `d` minus its
    /// cartesian is the minimum image of `d` for displacements well inside the cell.
    #[inline]
    pub fn nearest_lattice(&self, d: Vec3) -> Vec3 {
        self.fractional(d).round()
    }

    /// The minimum image of displacement `d` (Å).
    #[inline]
    pub fn min_image(&self, d: Vec3) -> Vec3 {
        d - self.cartesian(self.nearest_lattice(d))
    }

    /// The centre of the box, (a + b + c) / 2 (Å).
    pub fn centre(&self) -> Vec3 {
        self.cartesian(Vec3::splat(0.5))
    }

    /// Width of the box perpendicular to each pair of the other two edges (Å): the distance
    /// between opposite faces, along a, b and c.
    pub fn widths(&self) -> Vec3 {
        let [a, b, c] = [self.m.x_axis, self.m.y_axis, self.m.z_axis];
        let volume = self.m.determinant().abs();
        Vec3::new(
            volume / b.cross(c).length(),
            volume / c.cross(a).length(),
            volume / a.cross(b).length(),
        )
    }

    /// The same cell turned by `rotation`.
    pub fn rotated(&self, rotation: Mat3) -> PbcCell {
        let m = rotation * self.m;
        PbcCell {
            m,
            inv: m.inverse(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triclinic_min_image_and_widths() {
        let rows = [
            Vec3::new(50.0, 0.0, 0.0),
            Vec3::new(10.0, 45.0, 0.0),
            Vec3::new(5.0, 8.0, 40.0),
        ];
        let cell = PbcCell::new(&rows).expect("cell");
        let d = Vec3::new(1.0, -0.5, 0.7);
        let shifted = d + rows[0] - 2.0 * rows[1] + rows[2];
        assert!((cell.min_image(shifted) - d).length() < 1e-4);
        let w = cell.widths();
        assert!((w.z - 40.0).abs() < 1e-4, "{w}");
        assert!((cell.centre() - (rows[0] + rows[1] + rows[2]) / 2.0).length() < 1e-4);
        assert!(PbcCell::new(&[Vec3::ZERO; 3]).is_none());
    }
}
