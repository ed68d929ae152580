//! A cell list over atoms for the per-vertex question of [`super`]: which atoms' Gaussians
//! reach a point, and with what weight (binned by the crate's counting sort,
//! [`crate::model::cells::sort_by_cell`]; the atoms' Gaussian terms kept beside them). Cells are
//! half the longest cutoff long along x and one cutoff along y and z, and the grid reaches one
//! cutoff beyond the atoms; atoms are stored sorted by cell, x fastest, so the cells of a row
//! along x are one contiguous run (tall cells make fewer rows to visit per question). Points are
//! asked about in groups: points are grouped by cubes one cutoff wide ([`CellList::key`]),
//! [`CellList::gather`] collects once the atoms that reach the box of a group's points (of one
//! point, for a single question) and [`Batch::for_each_gaussian`] tests each point against them.

use glam::Vec3;
use rayon::prelude::*;

use crate::model::cells::sort_by_cell;
use crate::surface::{AtomSet, SurfaceParams};

/// The cell (0 to `cells - 1`) holding coordinate `v` (Å) along an axis whose cells start at
/// `origin` and are `edge` Å long; coordinates past either end get the end cell. Truncation is
/// the floor on the values kept (and needs no call to `floorf` on targets without SSE4.1); NaN
/// gives cell 0.
fn clamped_cell(v: f32, origin: f32, edge: f32, cells: i64) -> i64 {
    (((v - origin) / edge).max(0.0) as i64).min(cells - 1)
}

/// Atoms sorted into cells, and the cubic cells points are grouped by.
pub(crate) struct CellList {
    origin: Vec3,
    /// Cell edges along x, y and z (Å).
    cell: Vec3,
    /// Edge (Å) of the cubic cells points are grouped by ([`CellList::key`]), from `origin`.
    group: f32,
    /// Group cells along each axis.
    group_dims: [i64; 3],
    /// The longest cutoff `q alpha` in Å.
    reach: f32,
    dims: [i64; 3],
    /// Start of each cell's run in the sorted arrays (one more entry than cells).
    starts: Vec<u32>,
    /// Sorted atoms: index into the atom set, and `1 / (2 alpha^2)` (Å⁻²).
    index: Vec<u32>,
    inv_two_alpha2: Vec<f32>,
    /// The sorted atoms' coordinates (Å) and squared cutoff `(q alpha)^2` (Å²) side by side,
    /// `[x, y, z, cutoff2]`.
    packed: Vec<[f32; 4]>,
}

impl CellList {
    /// The cell list of `atoms` (already validated, not empty) under `params`.
    pub(crate) fn new(atoms: &AtomSet<'_>, params: &SurfaceParams) -> CellList {
        let n = atoms.len();
        let alpha = |i: usize| atoms.radii[i] * params.radius_scale;
        let q = params.cutoff();
        let widest = (0..n).fold(0.0f32, |m, i| m.max(alpha(i)));
        let (lo, hi) = atoms.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        // The grid reaches one cutoff beyond the atoms: a point outside it has no contributor.
        let reach = widest * q;
        let (lo, hi) = (lo - reach, hi + reach);
        let extent = (hi - lo).max(Vec3::splat(1e-3));
        let count = |cell: Vec3| {
            let d = (extent / cell).floor() + 1.0;
            (d.x as f64) * (d.y as f64) * (d.z as f64)
        };
        // Cells half the longest cutoff along x and one cutoff along y and z (fewer rows per
        // gather), points grouped by cubes of one cutoff; not many more cells than atoms.
        let mut cell = (reach * Vec3::new(0.5, 1.0, 1.0)).max(Vec3::splat(1e-3));
        while count(cell) > (8 * n + 512) as f64 {
            cell *= 1.25;
        }
        let mut group = reach.max(1e-3);
        while count(Vec3::splat(group)) > (8 * n + 512) as f64 {
            group *= 1.25;
        }
        let d = (extent / cell).floor() + 1.0;
        let dims = [d.x as i64, d.y as i64, d.z as i64];
        let g = (extent / group).floor() + 1.0;
        let group_dims = [g.x as i64, g.y as i64, g.z as i64];
        let cell_of = |p: Vec3| {
            let c = |k: usize| clamped_cell(p[k], lo[k], cell[k], dims[k]);
            (c(0) + dims[0] * (c(1) + dims[1] * c(2))) as usize
        };
        let cells = (dims[0] * dims[1] * dims[2]) as usize;
        let of: Vec<usize> = atoms.positions.par_iter().map(|p| cell_of(*p)).collect();
        let (starts, index) = sort_by_cell(&of, cells);
        let packed = index
            .par_iter()
            .map(|&i| {
                let (p, a) = (atoms.positions[i as usize], alpha(i as usize));
                [p.x, p.y, p.z, (q * a).powi(2)]
            })
            .collect();
        CellList {
            group,
            group_dims,
            packed,
            origin: lo,
            cell,
            reach,
            dims,
            inv_two_alpha2: index
                .par_iter()
                .map(|&i| 1.0 / (2.0 * alpha(i as usize) * alpha(i as usize)))
                .collect(),
            starts,
            index,
        }
    }

    /// Number of point groups (keys run from 0 to this, exclusive).
    pub(crate) fn len(&self) -> usize {
        (self.group_dims[0] * self.group_dims[1] * self.group_dims[2]) as usize
    }

    /// The group cell holding `p`, or `None` when `p` is off the grid (no atom reaches it).
    pub(crate) fn key(&self, p: Vec3) -> Option<u32> {
        let c = (p - self.origin) / self.group;
        let c = [c.x, c.y, c.z];
        let dims = self.group_dims;
        // Truncation is the floor on the non-negative values kept (and needs no call to
        // `floorf` on targets without SSE4.1).
        if (0..3).any(|k| !(c[k] >= 0.0 && (c[k] as i64) < dims[k])) {
            return None;
        }
        let [x, y, z] = c.map(|v| v as i64);
        Some((x + dims[0] * (y + dims[1] * z)) as u32)
    }

    /// Fills `out` with the atoms whose cutoff sphere reaches the box `lo..hi` (Å; the bounds
    /// of the points asked about next, for example the vertices of one cell), in sorted order.
    #[inline(always)]
    pub(crate) fn gather(&self, lo: Vec3, hi: Vec3, out: &mut Batch) {
        // The cells from `lo - reach` to `hi + reach` along `axis`.
        let cell_of = |v: f32, axis: usize| {
            clamped_cell(v, self.origin[axis], self.cell[axis], self.dims[axis])
        };
        let span = |axis: usize| {
            (
                cell_of(lo[axis] - self.reach, axis),
                cell_of(hi[axis] + self.reach, axis),
            )
        };
        let ((ys, ye), (zs, ze)) = (span(1), span(2));
        // Distance (Å) along `axis` from the box to cell `c`'s slab.
        let gap = |c: i64, axis: usize| {
            let start = self.origin[axis] + c as f32 * self.cell[axis];
            (start - hi[axis])
                .max(lo[axis] - start - self.cell[axis])
                .max(0.0)
        };
        let reach2 = self.reach * self.reach;
        // First the sorted positions of the atoms that reach the box: every atom of a row is
        // written and the count advances past those that reach (no branch per atom).
        let mut n = 0;
        for z in zs..=ze {
            let gz2 = gap(z, 2).powi(2);
            for y in ys..=ye {
                let left2 = reach2 - gap(y, 1).powi(2) - gz2;
                if left2 <= 0.0 {
                    continue;
                }
                // The cells of this row that the longest cutoff still reaches along x.
                let left = left2.sqrt();
                let (xs, xe) = (cell_of(lo.x - left, 0), cell_of(hi.x + left, 0));
                let row = self.dims[0] * (y + self.dims[1] * z);
                let start = self.starts[(row + xs) as usize] as usize;
                let end = self.starts[(row + xe + 1) as usize] as usize;
                out.grow(n + end - start);
                for (s, a) in self.packed[start..end].iter().enumerate() {
                    let [x, y, z, cut2] = *a;
                    let dx = (lo.x - x).max(x - hi.x).max(0.0);
                    let dy = (lo.y - y).max(y - hi.y).max(0.0);
                    let dz = (lo.z - z).max(z - hi.z).max(0.0);
                    out.hits[n] = (start + s) as u32;
                    n += usize::from(dx * dx + dy * dy + dz * dz < cut2);
                }
            }
        }
        // Then their values, in that order.
        out.len = n;
        for k in 0..n {
            let s = out.hits[k] as usize;
            let [x, y, z, cut2] = self.packed[s];
            out.index[k] = self.index[s];
            out.x[k] = x;
            out.y[k] = y;
            out.z[k] = z;
            out.cutoff2[k] = cut2;
            out.inv_two_alpha2[k] = self.inv_two_alpha2[s];
        }
    }
}

/// The atoms that may reach the points of one cell ([`CellList::gather`]), in separate arrays:
/// the first `len` entries of each; the arrays only grow, and are scratch past `len`.
#[derive(Default)]
pub(crate) struct Batch {
    len: usize,
    index: Vec<u32>,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    inv_two_alpha2: Vec<f32>,
    cutoff2: Vec<f32>,
    d2: Vec<f32>,
    /// Positions in the arrays above of the atoms that reach the current point.
    hits: Vec<u32>,
}

impl Batch {
    /// Makes every array at least `room` long.
    fn grow(&mut self, room: usize) {
        if self.index.len() >= room {
            return;
        }
        for v in [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.inv_two_alpha2,
            &mut self.cutoff2,
            &mut self.d2,
        ] {
            v.resize(room, 0.0);
        }
        self.index.resize(room, 0);
        self.hits.resize(room, 0);
    }

    /// Calls `visit(atom, weight)` for every gathered atom whose Gaussian reaches `p` (a point
    /// of the gathered cell), with the Gaussian's value there. The distances are computed in
    /// one loop the compiler vectorises, the reaching atoms picked without a branch per atom.
    #[inline(always)]
    pub(crate) fn for_each_gaussian(&mut self, p: Vec3, mut visit: impl FnMut(u32, f32)) {
        let n = self.len;
        let (x, y, z, d2) = (&self.x[..n], &self.y[..n], &self.z[..n], &mut self.d2[..n]);
        for k in 0..n {
            d2[k] = (x[k] - p.x).powi(2) + (y[k] - p.y).powi(2) + (z[k] - p.z).powi(2);
        }
        let (cut, hits) = (&self.cutoff2[..n], &mut self.hits[..n]);
        let mut m = 0;
        for k in 0..n {
            hits[m] = k as u32;
            m += usize::from(d2[k] < cut[k]);
        }
        for &k in &hits[..m] {
            let k = k as usize;
            visit(self.index[k], (-d2[k] * self.inv_two_alpha2[k]).exp());
        }
    }
}

/// Index of the atom of `positions` nearest `p` (the first of equals); `positions` not empty.
pub(crate) fn nearest(positions: &[Vec3], p: Vec3) -> u32 {
    let mut best = (f32::INFINITY, 0u32);
    for (i, q) in positions.iter().enumerate() {
        let d = q.distance_squared(p);
        if d < best.0 {
            best = (d, i as u32);
        }
    }
    best.1
}
