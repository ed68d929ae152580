//! A cell list over atoms for the per-vertex question of [`super`]: which atoms' Gaussians
//! reach a point, and with what weight (binned by the crate's counting sort,
//! [`crate::model::cells::sort_by_cell`]; the atoms' Gaussian terms kept beside them). Cells are half the longest cutoff wide and the grid
//! reaches one cutoff beyond the atoms; atoms are stored sorted by cell, x fastest, coordinates
//! in separate arrays, so the cells of a row along x are one contiguous run. Points are either
//! asked about one at a time ([`CellList::for_each_gaussian`], rows beyond the cutoff skipped)
//! or by cell: [`CellList::gather`] collects once the atoms that reach a cell's box and
//! [`Batch::for_each_gaussian`] tests each point of the cell against them.

use glam::Vec3;

use crate::model::cells::sort_by_cell;
use crate::surface::{AtomSet, SurfaceParams};

/// Atoms sorted into cubic cells.
pub(crate) struct CellList {
    origin: Vec3,
    cell: f32,
    /// The longest cutoff `q alpha` in Å.
    reach: f32,
    dims: [i64; 3],
    /// Start of each cell's run in the sorted arrays (one more entry than cells).
    starts: Vec<u32>,
    /// Sorted atoms: index into the atom set, coordinates, `1 / (2 alpha^2)`, squared cutoff
    /// `(q alpha)^2`.
    index: Vec<u32>,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    inv_two_alpha2: Vec<f32>,
    cutoff2: Vec<f32>,
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
        // Cells half as wide as the longest cutoff, and not many more cells than atoms.
        let mut cell = (reach / 2.0).max(1e-3);
        let count = |cell: f32| {
            let d = (extent / cell).floor() + 1.0;
            (d.x as f64) * (d.y as f64) * (d.z as f64)
        };
        while count(cell) > (8 * n + 512) as f64 {
            cell *= 1.25;
        }
        let d = (extent / cell).floor() + 1.0;
        let dims = [d.x as i64, d.y as i64, d.z as i64];
        let cell_of = |p: Vec3| {
            let c = ((p - lo) / cell).floor();
            let clamp = |v: f32, d: i64| (v as i64).clamp(0, d - 1);
            (clamp(c.x, dims[0]) + dims[0] * (clamp(c.y, dims[1]) + dims[1] * clamp(c.z, dims[2])))
                as usize
        };
        let cells = (dims[0] * dims[1] * dims[2]) as usize;
        let of: Vec<usize> = atoms.positions.iter().map(|p| cell_of(*p)).collect();
        let (starts, index) = sort_by_cell(&of, cells);
        let pick = |f: &dyn Fn(usize) -> f32| index.iter().map(|&i| f(i as usize)).collect();
        CellList {
            origin: lo,
            cell,
            reach,
            dims,
            x: pick(&|i| atoms.positions[i].x),
            y: pick(&|i| atoms.positions[i].y),
            z: pick(&|i| atoms.positions[i].z),
            inv_two_alpha2: pick(&|i| 1.0 / (2.0 * alpha(i) * alpha(i))),
            cutoff2: pick(&|i| (q * alpha(i)).powi(2)),
            starts,
            index,
        }
    }

    /// Calls `visit(run start, run end)` for the runs of sorted atoms that may lie within the
    /// longest cutoff of `p`.
    fn runs(&self, p: Vec3, mut visit: impl FnMut(usize, usize)) {
        let lo = ((p - self.reach - self.origin) / self.cell).floor();
        let hi = ((p + self.reach - self.origin) / self.cell).floor();
        let range = |k: usize| {
            let d = self.dims[k] - 1;
            ((lo[k] as i64).max(0), (hi[k] as i64).min(d))
        };
        let ((xs, xe), (ys, ye), (zs, ze)) = (range(0), range(1), range(2));
        if xs > xe {
            return;
        }
        // Distance from `v` to the slab [start, start + cell) of cell `c` along axis `k`.
        let gap = |v: f32, k: usize, c: i64| {
            let start = self.origin[k] + c as f32 * self.cell;
            (start - v).max(v - start - self.cell).max(0.0)
        };
        let reach2 = self.reach * self.reach;
        for z in zs..=ze {
            let gz = gap(p.z, 2, z);
            for y in ys..=ye {
                let gy = gap(p.y, 1, y);
                if gy * gy + gz * gz >= reach2 {
                    continue;
                }
                let row = self.dims[0] * (y + self.dims[1] * z);
                let start = self.starts[(row + xs) as usize] as usize;
                let end = self.starts[(row + xe + 1) as usize] as usize;
                if start < end {
                    visit(start, end);
                }
            }
        }
    }

    /// Calls `visit(atom, weight)` for every atom whose Gaussian reaches `p` (within its
    /// cutoff), with the Gaussian's value there.
    pub(crate) fn for_each_gaussian(&self, p: Vec3, mut visit: impl FnMut(u32, f32)) {
        const BATCH: usize = 32;
        let mut d2 = [0.0f32; BATCH];
        self.runs(p, |start, end| {
            let mut s = start;
            while s < end {
                let n = BATCH.min(end - s);
                let (x, y, z) = (&self.x[s..s + n], &self.y[s..s + n], &self.z[s..s + n]);
                for k in 0..n {
                    d2[k] = (x[k] - p.x).powi(2) + (y[k] - p.y).powi(2) + (z[k] - p.z).powi(2);
                }
                let cut = &self.cutoff2[s..s + n];
                for k in 0..n {
                    if d2[k] < cut[k] {
                        visit(
                            self.index[s + k],
                            (-d2[k] * self.inv_two_alpha2[s + k]).exp(),
                        );
                    }
                }
                s += n;
            }
        });
    }
}

impl CellList {
    /// The cell holding `p`, or `None` when `p` is off the grid (no atom reaches it).
    pub(crate) fn key(&self, p: Vec3) -> Option<u32> {
        let c = ((p - self.origin) / self.cell).floor();
        let c = [c.x, c.y, c.z];
        if (0..3).any(|k| !(c[k] >= 0.0 && (c[k] as i64) < self.dims[k])) {
            return None;
        }
        let [x, y, z] = c.map(|v| v as i64);
        Some((x + self.dims[0] * (y + self.dims[1] * z)) as u32)
    }

    /// Fills `out` with the atoms whose cutoff sphere reaches cell `key`'s box (a key from
    /// [`CellList::key`]), for the points of that cell.
    pub(crate) fn gather(&self, key: u32, out: &mut Batch) {
        out.clear();
        let key = key as i64;
        let c = [
            key % self.dims[0],
            (key / self.dims[0]) % self.dims[1],
            key / (self.dims[0] * self.dims[1]),
        ];
        let box_lo = self.origin + self.cell * Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        let box_hi = box_lo + self.cell;
        let k = (self.reach / self.cell).ceil() as i64;
        let range = |a: usize| ((c[a] - k).max(0), (c[a] + k).min(self.dims[a] - 1));
        let ((xs, xe), (ys, ye), (zs, ze)) = (range(0), range(1), range(2));
        let gap = |d: i64| ((d.abs() - 1).max(0) as f32) * self.cell;
        let reach2 = self.reach * self.reach;
        for z in zs..=ze {
            for y in ys..=ye {
                if gap(y - c[1]).powi(2) + gap(z - c[2]).powi(2) >= reach2 {
                    continue;
                }
                let row = self.dims[0] * (y + self.dims[1] * z);
                let start = self.starts[(row + xs) as usize] as usize;
                let end = self.starts[(row + xe + 1) as usize] as usize;
                for s in start..end {
                    let a = Vec3::new(self.x[s], self.y[s], self.z[s]);
                    let d = (box_lo - a).max(a - box_hi).max(Vec3::ZERO);
                    if d.length_squared() < self.cutoff2[s] {
                        out.index.push(self.index[s]);
                        out.x.push(a.x);
                        out.y.push(a.y);
                        out.z.push(a.z);
                        out.inv_two_alpha2.push(self.inv_two_alpha2[s]);
                        out.cutoff2.push(self.cutoff2[s]);
                    }
                }
            }
        }
        out.d2.resize(out.index.len(), 0.0);
    }
}

/// The atoms that may reach the points of one cell ([`CellList::gather`]), in separate arrays.
#[derive(Default)]
pub(crate) struct Batch {
    index: Vec<u32>,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    inv_two_alpha2: Vec<f32>,
    cutoff2: Vec<f32>,
    d2: Vec<f32>,
}

impl Batch {
    fn clear(&mut self) {
        for v in [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.inv_two_alpha2,
            &mut self.cutoff2,
        ] {
            v.clear();
        }
        self.index.clear();
    }

    /// Calls `visit(atom, weight)` for every gathered atom whose Gaussian reaches `p` (a point
    /// of the gathered cell), with the Gaussian's value there. The distances are computed in
    /// one loop the compiler vectorises, then filtered.
    pub(crate) fn for_each_gaussian(&mut self, p: Vec3, mut visit: impl FnMut(u32, f32)) {
        let n = self.index.len();
        let (x, y, z, d2) = (&self.x[..n], &self.y[..n], &self.z[..n], &mut self.d2[..n]);
        for k in 0..n {
            d2[k] = (x[k] - p.x).powi(2) + (y[k] - p.y).powi(2) + (z[k] - p.z).powi(2);
        }
        let hits = d2
            .iter()
            .zip(&self.cutoff2[..n])
            .enumerate()
            .filter(|(_, (d, c))| d < c);
        for (k, (&d, _)) in hits {
            visit(self.index[k], (-d * self.inv_two_alpha2[k]).exp());
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
