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

use super::lanes::{Lanes, Run, SLACK, pick_near_box, pick_near_point};
use crate::model::cells::sort_by_cell;
use crate::surface::{AtomSet, SurfaceParams};

/// The cell (0 to `cells - 1`) holding coordinate `v` (Å) along an axis whose cells start at
/// `origin` and are `edge` Å long; coordinates past either end get the end cell. Truncation is
/// the floor on the values kept (and needs no call to `floorf` on targets without SSE4.1); NaN
/// gives cell 0.
fn clamped_cell(v: f32, origin: f32, edge: f32, cells: i64) -> i64 {
    (((v - origin) / edge).max(0.0) as i64).min(cells - 1)
}

/// The cells of a [`CellList`] before any atom is binned: where they start, how long they are,
/// and the cubic cells points are grouped by ([`CellGrid::key`]). The plan needs only the atoms'
/// bounds and radii: points are grouped on it without the binned atoms.
#[derive(Clone)]
pub(crate) struct CellGrid {
    origin: Vec3,
    /// Cell edges along x, y and z (Å).
    cell: Vec3,
    /// Edge (Å) of the cubic cells points are grouped by ([`CellGrid::key`]), from `origin`.
    group: f32,
    /// Group cells along each axis.
    group_dims: [i64; 3],
    /// The longest cutoff `q alpha` in Å.
    reach: f32,
    /// Cells along each axis.
    dims: [i64; 3],
}

impl CellGrid {
    /// The cells for `atoms` (already validated, not empty) under `params`.
    pub(crate) fn plan(atoms: &AtomSet<'_>, params: &SurfaceParams) -> CellGrid {
        let n = atoms.len();
        let q = params.cutoff();
        let (widest, lo, hi) = atoms
            .positions
            .par_iter()
            .zip(atoms.radii)
            .fold(
                || {
                    (
                        0.0f32,
                        Vec3::splat(f32::INFINITY),
                        Vec3::splat(f32::NEG_INFINITY),
                    )
                },
                |(w, lo, hi), (p, r)| (w.max(r * params.radius_scale), lo.min(*p), hi.max(*p)),
            )
            .reduce(
                || {
                    (
                        0.0f32,
                        Vec3::splat(f32::INFINITY),
                        Vec3::splat(f32::NEG_INFINITY),
                    )
                },
                |a, b| (a.0.max(b.0), a.1.min(b.1), a.2.max(b.2)),
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
        let g = (extent / group).floor() + 1.0;
        CellGrid {
            origin: lo,
            cell,
            group,
            group_dims: [g.x as i64, g.y as i64, g.z as i64],
            reach,
            dims: [d.x as i64, d.y as i64, d.z as i64],
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

    /// The cell list of `atoms` (those the grid was planned for) on these cells.
    pub(crate) fn bin(&self, atoms: &AtomSet<'_>, params: &SurfaceParams) -> CellList {
        let alpha = |i: usize| atoms.radii[i] * params.radius_scale;
        let q = params.cutoff();
        let (lo, cell, dims) = (self.origin, self.cell, self.dims);
        let cell_of = |p: Vec3| {
            let c = |k: usize| clamped_cell(p[k], lo[k], cell[k], dims[k]);
            (c(0) + dims[0] * (c(1) + dims[1] * c(2))) as usize
        };
        let cells = (dims[0] * dims[1] * dims[2]) as usize;
        let of: Vec<usize> = atoms.positions.par_iter().map(|p| cell_of(*p)).collect();
        let (starts, index) = sort_by_cell(&of, cells);
        // The sorted atoms' values, in one pass over the order (each atom read once).
        let n = index.len();
        let (mut x, mut y, mut z) = (vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]);
        let (mut cutoff2, mut inv_two_alpha2) = (vec![0.0f32; n], vec![0.0f32; n]);
        for (k, &i) in index.iter().enumerate() {
            let (p, a) = (atoms.positions[i as usize], alpha(i as usize));
            (x[k], y[k], z[k]) = (p.x, p.y, p.z);
            cutoff2[k] = (q * a).powi(2);
            inv_two_alpha2[k] = 1.0 / (2.0 * a * a);
        }
        CellList {
            grid: self.clone(),
            starts,
            index,
            inv_two_alpha2,
            x,
            y,
            z,
            cutoff2,
            lanes: Lanes::detect(),
        }
    }
}

/// Atoms sorted into the cells of a [`CellGrid`].
pub(crate) struct CellList {
    grid: CellGrid,
    /// Start of each cell's run in the sorted arrays (one more entry than cells).
    starts: Vec<u32>,
    /// Sorted atoms: index into the atom set, and `1 / (2 alpha^2)` (Å⁻²).
    index: Vec<u32>,
    inv_two_alpha2: Vec<f32>,
    /// The sorted atoms' coordinates (Å) and squared cutoff `(q alpha)^2` (Å²).
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    cutoff2: Vec<f32>,
    /// The instruction set of the inner loops.
    lanes: Lanes,
}

impl CellList {
    /// The cell list of `atoms` (already validated, not empty) under `params`.
    pub(crate) fn new(atoms: &AtomSet<'_>, params: &SurfaceParams) -> CellList {
        CellGrid::plan(atoms, params).bin(atoms, params)
    }

    /// Fills `out` with the atoms whose cutoff sphere reaches the box `lo..hi` (Å; the bounds
    /// of the points asked about next, for example the vertices of one cell), in sorted order.
    #[inline(always)]
    pub(crate) fn gather(&self, lo: Vec3, hi: Vec3, out: &mut Batch) {
        let grid = &self.grid;
        // The cells from `lo - reach` to `hi + reach` along `axis`.
        let cell_of = |v: f32, axis: usize| {
            clamped_cell(v, grid.origin[axis], grid.cell[axis], grid.dims[axis])
        };
        let span = |axis: usize| {
            (
                cell_of(lo[axis] - grid.reach, axis),
                cell_of(hi[axis] + grid.reach, axis),
            )
        };
        let ((ys, ye), (zs, ze)) = (span(1), span(2));
        // Distance (Å) along `axis` from the box to cell `c`'s slab.
        let gap = |c: i64, axis: usize| {
            let start = grid.origin[axis] + c as f32 * grid.cell[axis];
            (start - hi[axis])
                .max(lo[axis] - start - grid.cell[axis])
                .max(0.0)
        };
        let reach2 = grid.reach * grid.reach;
        // First the sorted positions of the atoms that reach the box: every atom of a row is
        // written and the count advances past those that reach (no branch per atom).
        let mut n = 0;
        out.grow(0); // the picked positions' slack, even when no row is visited
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
                let row = grid.dims[0] * (y + grid.dims[1] * z);
                let start = self.starts[(row + xs) as usize] as usize;
                let end = self.starts[(row + xe + 1) as usize] as usize;
                out.grow(n + end - start);
                let run = Run {
                    x: &self.x[start..end],
                    y: &self.y[start..end],
                    z: &self.z[start..end],
                    cutoff2: &self.cutoff2[start..end],
                };
                n = pick_near_box(self.lanes, run, lo, hi, start as u32, &mut out.hits, n);
            }
        }
        // Then their values, in that order.
        out.len = n;
        out.lanes = self.lanes;
        for k in 0..n {
            let s = out.hits[k] as usize;
            out.index[k] = self.index[s];
            out.x[k] = self.x[s];
            out.y[k] = self.y[s];
            out.z[k] = self.z[s];
            out.cutoff2[k] = self.cutoff2[s];
            out.inv_two_alpha2[k] = self.inv_two_alpha2[s];
        }
    }
}

/// The atoms that may reach the points of one cell ([`CellList::gather`]), in separate arrays:
/// the first `len` entries of each; the arrays only grow, and are scratch past `len`.
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
    /// The instruction set of the inner loops.
    lanes: Lanes,
}

impl Default for Batch {
    fn default() -> Batch {
        Batch {
            len: 0,
            index: Vec::new(),
            x: Vec::new(),
            y: Vec::new(),
            z: Vec::new(),
            inv_two_alpha2: Vec::new(),
            cutoff2: Vec::new(),
            d2: Vec::new(),
            hits: Vec::new(),
            lanes: Lanes::Portable,
        }
    }
}

impl Batch {
    /// Makes every array at least `room` long (the picked positions [`SLACK`] longer).
    fn grow(&mut self, room: usize) {
        if self.hits.len() >= room + SLACK {
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
        self.hits.resize(room + SLACK, 0);
    }

    /// Number of gathered atoms.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Index in the atom set of gathered atom `k` (below [`Batch::len`]).
    pub(crate) fn atom(&self, k: usize) -> u32 {
        self.index[k]
    }

    /// The gathered atoms whose Gaussians reach `p` (a point of the gathered box): their
    /// positions below [`Batch::len`], ascending, in `hits[..m]` (`m` returned), each one's
    /// squared distance (Å²) in `d2`.
    #[inline(always)]
    fn pick(&mut self, p: Vec3) -> usize {
        let n = self.len;
        let run = Run {
            x: &self.x[..n],
            y: &self.y[..n],
            z: &self.z[..n],
            cutoff2: &self.cutoff2[..n],
        };
        pick_near_point(self.lanes, run, p, &mut self.d2, &mut self.hits)
    }

    /// The exponent of gathered atom `k`'s Gaussian at the point last picked,
    /// `-d^2 / (2 alpha^2)` (the Gaussian is its `exp`).
    #[inline(always)]
    fn exponent(&self, k: u32) -> f32 {
        -self.d2[k as usize] * self.inv_two_alpha2[k as usize]
    }

    /// Appends to `picked` the gathered atoms whose Gaussians reach `p` (a point of the
    /// gathered box; positions below [`Batch::len`], ascending) and to `exponents` the
    /// exponent of each Gaussian there (see [`Batch::exponent`]).
    #[inline(always)]
    pub(crate) fn reaching(&mut self, p: Vec3, picked: &mut Vec<u32>, exponents: &mut Vec<f32>) {
        let m = self.pick(p);
        let hits = &self.hits[..m];
        picked.extend_from_slice(hits);
        exponents.extend(hits.iter().map(|&k| self.exponent(k)));
    }

    /// Calls `visit(atom, weight)` for every gathered atom whose Gaussian reaches `p` (a point
    /// of the gathered box), with the Gaussian's value there, in gathered order.
    pub(crate) fn for_each_gaussian(&mut self, p: Vec3, mut visit: impl FnMut(u32, f32)) {
        let m = self.pick(p);
        for &k in &self.hits[..m] {
            visit(self.index[k as usize], self.exponent(k).exp());
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Atoms on a small jittered lattice, radii 1.5 to 2 Å.
    fn lattice() -> (Vec<Vec3>, Vec<f32>) {
        let mut positions = Vec::new();
        for i in 0..40 {
            let f = i as f32;
            positions.push(Vec3::new(
                (i % 4) as f32 * 1.7 + (f * 0.37).sin() * 0.3,
                (i / 4 % 5) as f32 * 1.6,
                (i / 20) as f32 * 1.8 + (f * 0.71).cos() * 0.2,
            ));
        }
        let radii = (0..40).map(|i| 1.5 + (i % 3) as f32 * 0.25).collect();
        (positions, radii)
    }

    #[test]
    fn gathered_gaussians_are_those_of_every_atom_within_its_cutoff() {
        let (positions, radii) = lattice();
        let atoms = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: None,
        };
        let params = SurfaceParams::default();
        let cells = CellList::new(&atoms, &params);
        let q = params.cutoff();
        for p in [
            Vec3::new(2.0, 3.0, 1.0),
            Vec3::new(-3.0, 0.5, 0.0),
            Vec3::new(500.0, -800.0, 90.0), // far off the grid: nothing, no panic
        ] {
            // A fresh batch each time: its arrays start empty.
            let mut batch = Batch::default();
            cells.gather(p, p, &mut batch);
            let mut got = Vec::new();
            batch.for_each_gaussian(p, |atom, w| got.push((atom, w)));
            got.sort_by_key(|g| g.0);
            let want: Vec<(u32, f32)> = (0..positions.len())
                .filter_map(|i| {
                    let alpha = radii[i] * params.radius_scale;
                    let d2 = (positions[i] - p).length_squared();
                    (d2 < (q * alpha).powi(2))
                        .then(|| (i as u32, (-d2 / (2.0 * alpha * alpha)).exp()))
                })
                .collect();
            assert_eq!(got.len(), want.len(), "at {p}");
            for ((a, w), (b, v)) in got.iter().zip(&want) {
                assert_eq!(a, b, "at {p}");
                assert!((w - v).abs() <= 1e-6 * v, "atom {a} at {p}: {w} vs {v}");
            }
        }
    }
}
