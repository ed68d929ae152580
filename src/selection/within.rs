//! `within D of SEL`: which atoms lie within D Å of any source atom, with a cell grid.
//!
//! With a periodic box (orthorhombic or triclinic), every position is first wrapped into the
//! box (through fractional coordinates), and the atoms of the set that gets binned are copied
//! with each periodic image that lies within D of the box (a slab test per box axis, in
//! fractional coordinates; any box shape, and boxes narrower than D get several images). A
//! wrapped atom then finds every partner within D among those copies, so the search itself is a
//! plain Cartesian one: no minimum-image convention is needed.
//!
//! The smaller of the two sets (sources, targets) is binned into Cartesian cells D wide (the
//! counting sort of [`crate::model::cells`]), and
//! the cells some part of which lies within D of a binned atom are marked. Each atom of the
//! larger set (in parallel) is rejected by one look-up when its cell is unmarked, and otherwise
//! visits the 3 × 3 × 3 cells around its own, row by row, skipping cells whose nearest point
//! is farther than D. With few sources (`within 5 of protein` in water) each target looks for
//! any source around it, its own cell first; with few targets (`ion and within 5 of water`)
//! each source marks the targets around it.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{IVec3, Mat3, Mat3A, Vec3, Vec3A};
use rayon::prelude::*;

use crate::model::cells::sort_by_cell;

/// Atoms per parallel task.
const CHUNK: usize = 1024;

/// Cells per cutoff distance along each axis (so the reach is at most this many cells). Two
/// (cells D/2 wide) visits fewer points per atom but more rows; one measured faster.
const SPLIT: i32 = 1;

/// Atoms `i` with `targets[i]` that lie within `distance` Å (inclusive) of some atom in
/// `sources` in `positions`, counting periodic images when `cell` (box edge vectors a, b, c in
/// Å) is given. Indices past the end of `positions` are never selected.
pub(crate) fn within(
    positions: &[Vec3],
    cell: Option<&[Vec3; 3]>,
    sources: &[u32],
    targets: &[bool],
    distance: f32,
) -> Vec<bool> {
    let mut out = vec![false; targets.len()];
    let n = targets.len().min(positions.len());
    let sources: Vec<u32> = sources
        .iter()
        .copied()
        .filter(|&s| (s as usize) < n)
        .collect();
    let target_count = targets[..n].iter().filter(|t| **t).count();
    if sources.is_empty() || target_count == 0 || !distance.is_finite() || distance < 0.0 {
        return out;
    }
    let space = cell.and_then(Periodic::new);
    // Wrapped position of atom `i`, or `None` when it is not finite.
    let place = |i: usize| {
        let p = Vec3A::from(positions[i]);
        p.is_finite()
            .then(|| space.as_ref().map_or(p, |s| s.wrap(p)))
    };
    let binned = |atoms: &mut dyn Iterator<Item = usize>| {
        let points: Vec<(u32, Vec3A)> = atoms
            .filter_map(|i| place(i).map(|p| (i as u32, p)))
            .collect();
        let points = match &space {
            Some(s) => s.with_images(&points, distance),
            None => points,
        };
        let max_cells = (8 * points.len()).max(4096) as f64;
        Grid::new(&points, distance, max_cells)
    };
    let d2 = distance * distance;
    if target_count < sources.len() {
        // Few targets: bin them, and let each source near one mark the targets around it.
        let grid = binned(&mut (0..n).filter(|&i| targets[i]));
        let marks: Vec<AtomicBool> = (0..targets.len()).map(|_| AtomicBool::new(false)).collect();
        sources.par_chunks(CHUNK).for_each(|chunk| {
            for p in chunk.iter().filter_map(|&s| place(s as usize)) {
                grid.mark_within(p, d2, &marks);
            }
        });
        out.iter_mut()
            .zip(marks)
            .for_each(|(o, m)| *o = m.into_inner());
    } else {
        // Few sources: bin them, and let each target near one look for one. A target that is
        // itself a source (at a finite position) is at distance 0: no search.
        let grid = binned(&mut sources.iter().map(|&s| s as usize));
        let mut is_source = vec![false; n];
        for &s in &sources {
            is_source[s as usize] = positions[s as usize].is_finite();
        }
        out[..n]
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (j, o) in chunk.iter_mut().enumerate() {
                    let i = k * CHUNK + j;
                    *o = targets[i]
                        && (is_source[i] || place(i).is_some_and(|p| grid.any_within(p, d2)));
                }
            });
    }
    out
}

/// A periodic box: edge vectors, the map to fractional coordinates, and face-to-face widths.
struct Periodic {
    /// Box edge vectors a, b, c in Å.
    edges: [Vec3A; 3],
    /// Cartesian to fractional coordinates.
    to_fraction: Mat3A,
    /// Width of the box between the faces opposite each edge, in Å.
    widths: Vec3,
}

impl Periodic {
    /// The box with edges `e`, or `None` when it is degenerate.
    fn new(e: &[Vec3; 3]) -> Option<Periodic> {
        let volume = e[0].dot(e[1].cross(e[2])).abs();
        if !volume.is_finite() || volume < 1e-6 {
            return None;
        }
        let widths = Vec3::new(
            volume / e[1].cross(e[2]).length(),
            volume / e[2].cross(e[0]).length(),
            volume / e[0].cross(e[1]).length(),
        );
        // A placeholder box (`CRYST1 1 1 1`) is not periodic.
        if widths.min_element() < crate::model::MIN_BOX_WIDTH {
            return None;
        }
        Some(Periodic {
            edges: e.map(Vec3A::from),
            to_fraction: Mat3A::from(Mat3::from_cols(e[0], e[1], e[2]).inverse()),
            widths,
        })
    }

    /// The box translation `t.x a + t.y b + t.z c`.
    #[inline]
    fn shift(&self, t: Vec3A) -> Vec3A {
        t.x * self.edges[0] + t.y * self.edges[1] + t.z * self.edges[2]
    }

    /// `p` moved into the box (fractional coordinates in [0, 1)).
    #[inline]
    fn wrap(&self, p: Vec3A) -> Vec3A {
        p - self.shift((self.to_fraction * p).floor())
    }

    /// Wrapped `points` with every periodic image that lies within `distance` Å of the box.
    fn with_images(&self, points: &[(u32, Vec3A)], distance: f32) -> Vec<(u32, Vec3A)> {
        let margin = Vec3::splat(distance) / self.widths;
        let reach = margin.ceil().as_ivec3();
        let mut out = Vec::with_capacity(points.len() * 3 / 2);
        for &(i, p) in points {
            let f = self.to_fraction * p;
            // Image offsets along axis k whose slab stays within the margin of the box.
            let range = |k: usize| {
                let (m, r) = (margin[k], reach[k]);
                (-r..=r).filter(move |&t| {
                    let g = f[k] + t as f32;
                    t == 0 || (g >= -m && g <= 1.0 + m)
                })
            };
            for tz in range(2) {
                for ty in range(1) {
                    for tx in range(0) {
                        let t = Vec3A::new(tx as f32, ty as f32, tz as f32);
                        out.push((i, p + self.shift(t)));
                    }
                }
            }
        }
        out
    }
}

/// Binned points: a Cartesian grid over their bounding box, padded by the reach and one cell.
struct Grid {
    /// Corner of cell (0, 0, 0) in Å.
    origin: Vec3A,
    /// Cell edge in Å.
    side: f32,
    /// 1 / `side`.
    inv_side: f32,
    /// Cells along each axis.
    dims: IVec3,
    /// `dims` as floats.
    dims_f: Vec3A,
    /// Cells searched on each side of a cell (at most [`SPLIT`]).
    reach: i32,
    /// Points of cell `c` are `points[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    /// Positions, sorted by cell.
    points: Vec<Vec3A>,
    /// Atom index of each point.
    ids: Vec<u32>,
    /// True for cells some part of which lies within the cutoff of a point.
    near: Vec<bool>,
}

impl Grid {
    /// Bins `points` in cells about `distance / SPLIT` wide (wider when there would be more
    /// than `max_cells`) and marks the cells near a point.
    fn new(points: &[(u32, Vec3A)], distance: f32, max_cells: f64) -> Grid {
        let lo = points.iter().fold(Vec3A::INFINITY, |a, &(_, p)| a.min(p));
        let hi = points
            .iter()
            .fold(Vec3A::NEG_INFINITY, |a, &(_, p)| a.max(p));
        let extent = Vec3::from(hi - lo).max(Vec3::splat(1e-3));
        let mut side = (distance / SPLIT as f32).max(1e-3);
        let cells = |side: f32| (extent / side).floor() + 1.0;
        let count = cells(side);
        let total = count.x as f64 * count.y as f64 * count.z as f64;
        if total > max_cells {
            side *= (total / max_cells).cbrt() as f32 * 1.01;
        }
        let reach = ((distance / side).ceil() as i32).clamp(1, SPLIT);
        // The reach plus one spare cell (absorbing rounding) on every side.
        let pad = reach + 1;
        let dims = cells(side).as_ivec3() + 2 * pad;
        let mut grid = Grid {
            origin: lo - pad as f32 * side,
            dims_f: Vec3A::from(dims.as_vec3()),
            side,
            inv_side: side.recip(),
            dims,
            reach,
            start: Vec::new(),
            points: Vec::new(),
            ids: Vec::new(),
            near: Vec::new(),
        };
        grid.fill(points, distance * distance);
        grid
    }

    /// Flat index of in-range cell `c`.
    #[inline]
    fn flat(&self, c: IVec3) -> usize {
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize
    }

    /// The cell holding `p`, with `p`'s place inside it (0 to 1 per axis), when on the grid.
    #[inline]
    fn locate(&self, p: Vec3A) -> Option<(IVec3, Vec3A)> {
        let g = (p - self.origin) * self.inv_side;
        let inside = g.cmpge(Vec3A::ZERO).all() && g.cmplt(self.dims_f).all();
        inside.then(|| {
            let floor = g.floor();
            (floor.as_ivec3(), g - floor)
        })
    }

    /// Sorts the points into cells (counting sort) and marks the cells within √`d2` Å of them.
    fn fill(&mut self, points: &[(u32, Vec3A)], d2: f32) {
        let cells = (self.dims.x * self.dims.y * self.dims.z) as usize;
        let cell_of: Vec<usize> = points
            .iter()
            .map(|&(_, p)| self.locate(p).map_or(0, |(c, _)| self.flat(c)))
            .collect();
        let (start, order) = sort_by_cell(&cell_of, cells);
        let sorted: Vec<Vec3A> = order.iter().map(|&o| points[o as usize].1).collect();
        let ids: Vec<u32> = order.iter().map(|&o| points[o as usize].0).collect();
        // Cells that some part of lies within the cutoff of some point: a target outside them
        // is out of range of every point.
        let mut near = vec![false; cells];
        for &(_, p) in points {
            if let Some((c, u)) = self.locate(p) {
                self.rows(c, u, d2, |row, first, last| {
                    near[row + first..=row + last].fill(true);
                    false
                });
            }
        }
        self.near = near;
        self.start = start;
        self.points = sorted;
        self.ids = ids;
    }

    /// The points of cells `first..=last` (flat indices) and their atom indices.
    #[inline]
    fn span(&self, first: usize, last: usize) -> (&[Vec3A], &[u32]) {
        let (a, b) = (self.start[first] as usize, self.start[last + 1] as usize);
        (&self.points[a..b], &self.ids[a..b])
    }

    /// True when some binned point lies within √`d2` Å of `p`.
    #[inline]
    fn any_within(&self, p: Vec3A, d2: f32) -> bool {
        let Some((c, u)) = self.locate(p) else {
            return false;
        };
        let own = self.flat(c);
        if !self.near[own] {
            return false;
        }
        let close = |points: &[Vec3A]| points.iter().any(|s| s.distance_squared(p) <= d2);
        // The atom's own cell first: inside a dense selection that settles it.
        close(self.span(own, own).0) || self.visit(c, u, d2, |points, _| close(points))
    }

    /// Marks in `marks` (by atom index) every binned point within √`d2` Å of `p`.
    #[inline]
    fn mark_within(&self, p: Vec3A, d2: f32, marks: &[AtomicBool]) {
        let Some((c, u)) = self.locate(p) else {
            return;
        };
        if !self.near[self.flat(c)] {
            return;
        }
        self.visit(c, u, d2, |points, ids| {
            for (s, &i) in points.iter().zip(ids) {
                if s.distance_squared(p) <= d2 {
                    marks[i as usize].store(true, Ordering::Relaxed);
                }
            }
            false
        });
    }

    /// Calls `f(points, ids)` for the cells around cell `c` (where the atom sits at `u`, 0 to 1
    /// per axis) whose nearest point is within √`d2` Å of the atom, one run of consecutive
    /// cells along x at a time, until `f` returns true; returns whether it did.
    #[inline]
    fn visit(
        &self,
        c: IVec3,
        u: Vec3A,
        d2: f32,
        mut f: impl FnMut(&[Vec3A], &[u32]) -> bool,
    ) -> bool {
        self.rows(c, u, d2, |row, first, last| {
            let (points, ids) = self.span(row + first, row + last);
            !points.is_empty() && f(points, ids)
        })
    }

    /// Calls `f(row, first, last)` for each row of cells around cell `c` (where the atom sits
    /// at `u`, 0 to 1 per axis): cells `row + first..=row + last` (flat indices) are those of
    /// the row whose nearest point is within √`d2` Å of the atom, consecutive around the
    /// atom's column. Stops when `f` returns true and returns whether it did.
    #[inline]
    fn rows(
        &self,
        c: IVec3,
        u: Vec3A,
        d2: f32,
        mut f: impl FnMut(usize, usize, usize) -> bool,
    ) -> bool {
        let r = self.reach;
        // Squared gap in Å² from the atom to the cells at each offset, per axis.
        let mut gaps = [[0.0f32; 2 * SPLIT as usize + 1]; 3];
        for (k, row) in gaps.iter_mut().enumerate() {
            for o in -r..=r {
                let gap = match o {
                    0 => 0.0,
                    o if o > 0 => (o as f32 - u[k]) * self.side,
                    o => (-o as f32 - 1.0 + u[k]) * self.side,
                };
                row[(o + r) as usize] = gap * gap;
            }
        }
        let (x0, x1) = ((c.x - r).max(0), (c.x + r).min(self.dims.x - 1));
        for z in (c.z - r).max(0)..=(c.z + r).min(self.dims.z - 1) {
            let gz = gaps[2][(z - c.z + r) as usize];
            if gz > d2 {
                continue;
            }
            for y in (c.y - r).max(0)..=(c.y + r).min(self.dims.y - 1) {
                let gy = gz + gaps[1][(y - c.y + r) as usize];
                if gy > d2 {
                    continue;
                }
                // Gaps grow away from the atom's own column (gap 0), so the cells in range
                // are consecutive.
                let fits = |x: i32| gy + gaps[0][(x - c.x + r) as usize] <= d2;
                let (mut first, mut last) = (c.x, c.x);
                while first > x0 && fits(first - 1) {
                    first -= 1;
                }
                while last < x1 && fits(last + 1) {
                    last += 1;
                }
                let row = ((z * self.dims.y + y) * self.dims.x) as usize;
                if f(row, first as usize, last as usize) {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over the 729 nearest images (enough for the points and boxes below).
    fn brute(positions: &[Vec3], cell: Option<&[Vec3; 3]>, sources: &[u32], d: f32) -> Vec<bool> {
        let shifts: Vec<Vec3> = match cell {
            Some(e) => {
                let mut v = Vec::new();
                for i in -4..=4 {
                    for j in -4..=4 {
                        for k in -4..=4 {
                            v.push(i as f32 * e[0] + j as f32 * e[1] + k as f32 * e[2]);
                        }
                    }
                }
                v
            }
            None => vec![Vec3::ZERO],
        };
        positions
            .iter()
            .map(|p| {
                sources.iter().any(|&s| {
                    shifts
                        .iter()
                        .any(|t| (positions[s as usize] + *t).distance_squared(*p) <= d * d)
                })
            })
            .collect()
    }

    fn points(n: usize, scale: f32) -> Vec<Vec3> {
        // A deterministic scatter (golden-ratio sequences), partly outside the box.
        (0..n)
            .map(|i| {
                let f = |a: f32| ((i as f32 * a).fract() * 1.4 - 0.2) * scale;
                Vec3::new(f(0.618_034), f(0.754_878), f(0.569_840))
            })
            .collect()
    }

    #[test]
    fn grid_matches_brute_force() {
        let boxes = [
            None,
            Some([Vec3::X * 20.0, Vec3::Y * 20.0, Vec3::Z * 20.0]),
            Some([
                Vec3::new(20.0, 0.0, 0.0),
                Vec3::new(8.0, 18.0, 0.0),
                Vec3::new(-6.0, 7.0, 16.0),
            ]),
            // Narrower than three cutoffs: images of the same cell are searched.
            Some([Vec3::X * 9.0, Vec3::new(3.0, 8.0, 0.0), Vec3::Z * 30.0]),
        ];
        let positions = points(600, 20.0);
        let all = vec![true; positions.len()];
        let few: Vec<bool> = (0..600).map(|i| i % 29 == 0).collect();
        let many: Vec<u32> = (0..600).filter(|i| i % 5 != 0).collect();
        let sparse: Vec<u32> = (0..600).step_by(37).collect();
        for cell in &boxes {
            for d in [0.0, 1.5, 4.0, 7.5] {
                // Few sources (targets binned), then few targets (sources binned).
                for (sources, targets) in [(&sparse, &all), (&many, &few)] {
                    let got = within(&positions, cell.as_ref(), sources, targets, d);
                    let want: Vec<bool> = brute(&positions, cell.as_ref(), sources, d)
                        .into_iter()
                        .zip(targets.iter())
                        .map(|(w, t)| w && *t)
                        .collect();
                    assert_eq!(got, want, "box {cell:?} d {d}");
                }
            }
        }
    }
}
