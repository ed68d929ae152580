//! Triclinic periodic cells (issue 30): the cell of a frame as `--periodic` uses it, either
//! the rectangular box of the original engine ([`PeriodicBox`], kept bit for bit) or a general
//! cell spanned by three edge vectors a, b, c ([`TriclinicCell`]: rhombic dodecahedra,
//! truncated octahedra, rotated boxes).
//!
//! Data flow: a frame's cell rows (Å) -> [`PeriodicCell::from_cell`] -> the rectangular
//! engine ([`super::PeriodicEngine::compute`]) or the triclinic one ([`super::triclinic`]).
//!
//! A triclinic cell is sampled along its edge vectors: `N_a = ceil(|a| / H)` samples along a
//! (likewise b, c), sample `(i, j, k)` at `origin + i/N_a a + j/N_b b + k/N_c c`. "Index
//! space" below is the space of `(i, j, k)` as real numbers; the affine map
//! [`TriclinicCell::to_cartesian`] takes it to Å.

use glam::{DMat3, DVec3, Vec3};

use super::{BoxError, MIN_BOX, PeriodicBox};

/// A periodic cell: `origin + s_a a + s_b b + s_c c` for fractional coordinates `s` in
/// `[0, 1)` (edge vectors in Å). Any three independent vectors are allowed (left-handed ones
/// too) as long as opposite faces are at least [`MIN_BOX`] apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriclinicCell {
    /// The corner of the cell at fractional coordinates (0, 0, 0) (Å).
    pub origin: Vec3,
    /// Edge vectors a, b, c (Å), as rows (the layout of [`crate::model::Frame::cell`]).
    pub rows: [Vec3; 3],
}

impl TriclinicCell {
    /// The cell with edge vectors `rows` (Å) at the origin. Refuses non-finite or flat cells
    /// (distance between opposite faces under [`MIN_BOX`], e.g. a placeholder `1 1 1` box).
    pub fn new(rows: [Vec3; 3]) -> Result<TriclinicCell, BoxError> {
        let cell = TriclinicCell {
            origin: Vec3::ZERO,
            rows,
        };
        let widths = cell.widths();
        if !(rows.iter().all(|r| r.is_finite()) && widths.min_element() >= MIN_BOX as f64) {
            return Err(BoxError::Thin {
                widths: widths.as_vec3(),
            });
        }
        Ok(cell)
    }

    /// The cell matrix (columns a, b, c; Å): fractional to Cartesian, `x = origin + M s`.
    pub fn matrix(&self) -> DMat3 {
        let [a, b, c] = self.rows.map(|r| r.as_dvec3());
        DMat3::from_cols(a, b, c)
    }

    /// Signed volume `a . (b x c)` (Å³); negative for a left-handed cell.
    pub fn signed_volume(&self) -> f64 {
        self.matrix().determinant()
    }

    /// Distances between the opposite faces, `|V| / |b x c|` and so on (Å).
    pub fn widths(&self) -> DVec3 {
        let [a, b, c] = self.rows.map(|r| r.as_dvec3());
        let v = self.signed_volume().abs();
        DVec3::new(
            v / b.cross(c).length(),
            v / c.cross(a).length(),
            v / a.cross(b).length(),
        )
    }

    /// Samples along a, b and c for grid spacing `h` (Å): `ceil(|edge| / h)`, at least 2.
    pub fn samples(&self, h: f32) -> [u32; 3] {
        self.rows
            .map(|r| ((r.length() / h).ceil() as u64).clamp(2, u32::MAX as u64 / 4) as u32)
    }

    /// Spacing along each edge vector, `|edge| / N` (Å), for `dims` samples.
    pub fn spacing(&self, dims: [u32; 3]) -> Vec3 {
        Vec3::new(
            self.rows[0].length() / dims[0] as f32,
            self.rows[1].length() / dims[1] as f32,
            self.rows[2].length() / dims[2] as f32,
        )
    }

    /// The Jacobian of index space to Cartesian for `dims` samples: columns `a / N_a`,
    /// `b / N_b`, `c / N_c` (Å per sample).
    pub fn index_matrix(&self, dims: [u32; 3]) -> DMat3 {
        let m = self.matrix();
        DMat3::from_cols(
            m.x_axis / dims[0] as f64,
            m.y_axis / dims[1] as f64,
            m.z_axis / dims[2] as f64,
        )
    }

    /// Fractional coordinates of `p` (Å), not wrapped.
    pub fn to_fractional(&self, p: Vec3) -> DVec3 {
        self.matrix().inverse() * (p - self.origin).as_dvec3()
    }

    /// The Cartesian position (Å) of index-space point `g` on a grid of `dims` samples.
    pub fn to_cartesian(&self, g: Vec3, dims: [u32; 3]) -> Vec3 {
        (self.index_matrix(dims) * g.as_dvec3()).as_vec3() + self.origin
    }
}

/// The fractional positions (in cell vectors) of the images of a point whose fractional
/// coordinates are `s` (any values; wrapped into [0, 1) first) that reach the cell when the
/// point reaches `reach[a]` (fractions of the cell) along each axis: every lattice shift `n`
/// with `s + n - reach <= 1` and `s + n + reach >= 0` per axis, z slowest, x fastest.
pub fn images_reaching_cell(s: DVec3, reach: [f64; 3]) -> impl Iterator<Item = DVec3> {
    let mut s = s - s.floor();
    for a in 0..3 {
        // `x - floor(x)` rounds up to 1 for tiny negative x.
        if s[a] >= 1.0 {
            s[a] = 0.0;
        }
    }
    let shifts = move |a: usize| {
        let m = reach[a].ceil() as i64 + 1;
        (-m..=m)
            .map(|n| n as f64)
            .filter(move |&n| s[a] + n + reach[a] >= 0.0 && s[a] + n - reach[a] <= 1.0)
    };
    shifts(2).flat_map(move |nz| {
        shifts(1).flat_map(move |ny| shifts(0).map(move |nx| s + DVec3::new(nx, ny, nz)))
    })
}

/// The cell `--periodic` computes in: a rectangular box along x, y, z (the original engine,
/// unchanged) or any other cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodicCell {
    /// Edges along x, y and z (relative tolerance 1e-5, as [`PeriodicBox::from_cell`]).
    Rectangular(PeriodicBox),
    /// Any other cell, rotated rectangular boxes included.
    Triclinic(TriclinicCell),
}

impl PeriodicCell {
    /// The cell of a frame (rows a, b, c in Å, as [`crate::model::Frame::cell`] holds them):
    /// rectangular when its edges are along x, y and z, else triclinic. Refuses flat or
    /// non-finite cells with a one-line error.
    pub fn from_cell(rows: &[Vec3; 3]) -> Result<PeriodicCell, BoxError> {
        match PeriodicBox::from_cell(rows) {
            Ok(b) => Ok(PeriodicCell::Rectangular(b)),
            Err(BoxError::Triclinic { rows }) => {
                TriclinicCell::new(rows).map(PeriodicCell::Triclinic)
            }
            Err(e) => Err(e),
        }
    }

    /// Volume of the cell (Å³).
    pub fn volume(&self) -> f64 {
        match self {
            PeriodicCell::Rectangular(b) => {
                b.lengths.x as f64 * b.lengths.y as f64 * b.lengths.z as f64
            }
            PeriodicCell::Triclinic(c) => c.signed_volume().abs(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dodecahedron(d: f32) -> [Vec3; 3] {
        [
            Vec3::new(d, 0.0, 0.0),
            Vec3::new(0.0, d, 0.0),
            Vec3::new(0.5 * d, 0.5 * d, 0.5 * std::f32::consts::SQRT_2 * d),
        ]
    }

    #[test]
    fn periodic_cells_are_classified_and_flat_ones_refused() {
        let rect = [Vec3::X * 30.0, Vec3::Y * 40.0, Vec3::Z * 50.0];
        assert!(matches!(
            PeriodicCell::from_cell(&rect),
            Ok(PeriodicCell::Rectangular(_))
        ));
        let rd = dodecahedron(80.0);
        let Ok(PeriodicCell::Triclinic(cell)) = PeriodicCell::from_cell(&rd) else {
            panic!("a rhombic dodecahedron is triclinic");
        };
        // V = d^3 / sqrt(2); widths: 80 between the faces of the square, 80 sin 60 ... > 4.
        let v = 80.0f64.powi(3) / 2f64.sqrt();
        assert!((cell.signed_volume() - v).abs() < 1e-6 * v);
        assert!(cell.widths().min_element() > 50.0);
        assert_eq!(cell.samples(1.0), [80, 80, 80]);
        let flat = [Vec3::X * 30.0, Vec3::Y * 40.0, Vec3::new(10.0, 10.0, 1.0)];
        let err = PeriodicCell::from_cell(&flat).unwrap_err().to_string();
        assert!(err.contains("1.000") && !err.contains('\n'), "{err}");
        let nan = [Vec3::X * 30.0, Vec3::new(f32::NAN, 1.0, 0.0), Vec3::Z];
        assert!(PeriodicCell::from_cell(&nan).is_err());
        let singular = [
            Vec3::X * 30.0,
            Vec3::X * 20.0 + Vec3::Y * 1e-9,
            Vec3::Z * 30.0,
        ];
        assert!(PeriodicCell::from_cell(&singular).is_err());
    }

    #[test]
    fn index_space_maps_onto_the_cell_vectors() {
        let cell = TriclinicCell::new(dodecahedron(40.0)).expect("cell");
        let dims = [40, 40, 40];
        let c = cell.to_cartesian(Vec3::new(0.0, 0.0, 40.0), dims);
        assert!((c - cell.rows[2]).length() < 1e-4, "{c}");
        let s = cell.to_fractional(cell.to_cartesian(Vec3::new(10.0, 20.0, 30.0), dims));
        assert!((s - DVec3::new(0.25, 0.5, 0.75)).length() < 1e-6, "{s}");
    }
}
