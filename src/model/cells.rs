//! One cell list for every neighbour search in the crate: points binned by a counting sort into
//! cubic cells of a given edge (Å) over a box, so that the points near a place are read from the
//! few cells around it. Bond guessing ([`super::bonds`]), exposure counts
//! ([`super::exposure`]) and radius fitting ([`super::sizing`]) read [`CellList`] cell by cell;
//! `within D of SEL` selections (`crate::selection::within`) ask a [`CutoffCells`] (a cell list
//! with one cutoff and the cells it reaches marked) for the points within D of each atom.
//! Periodic callers bin wrapped points (and their images) or their own cell keys with
//! [`sort_by_cell`].

use glam::{IVec3, Vec3, Vec3A};

/// Sorts items into cells by counting: `keys[i]` is item `i`'s cell (below `cells`), or
/// `usize::MAX` to leave it out. Returns `(start, order)`: the items of cell `k` are
/// `order[start[k]..start[k + 1]]`, ascending.
pub fn sort_by_cell(keys: &[usize], cells: usize) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; cells + 1];
    for &k in keys.iter().filter(|&&k| k != usize::MAX) {
        start[k + 1] += 1;
    }
    for k in 0..cells {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut order = vec![0u32; start[cells] as usize];
    for (i, &k) in keys.iter().enumerate().filter(|(_, k)| **k != usize::MAX) {
        order[fill[k] as usize] = i as u32;
        fill[k] += 1;
    }
    (start, order)
}

/// Points binned into cubic cells of [`CellList::edge`] Å; cell `c` (integer coordinates from
/// 0 to `dims - 1`) spans `origin + c * edge` to `origin + (c + 1) * edge`.
#[derive(Debug, Clone)]
pub struct CellList {
    /// Corner of cell (0, 0, 0) in Å.
    origin: Vec3,
    /// Cell edge in Å.
    edge: f32,
    /// Cells along each axis.
    dims: IVec3,
    /// The points of flat cell `k` are `points[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    /// Positions in Å, sorted by cell.
    points: Vec<Vec3>,
    /// The caller's id of each sorted point.
    ids: Vec<u32>,
}

impl CellList {
    /// Bins `items` (id, position in Å) into `dims` cells of `edge` Å from `origin`. Points that
    /// are not finite are left out; points outside the cells go to the nearest cell.
    pub fn new(items: &[(u32, Vec3)], origin: Vec3, edge: f32, dims: IVec3) -> CellList {
        let dims = dims.max(IVec3::ONE);
        let mut list = CellList {
            origin,
            edge,
            dims,
            start: Vec::new(),
            points: Vec::new(),
            ids: Vec::new(),
        };
        let cells = (dims.x as usize) * (dims.y as usize) * (dims.z as usize);
        let keys: Vec<usize> = items
            .iter()
            .map(|&(_, p)| {
                if p.is_finite() {
                    list.flat(list.cell_of(p).clamp(IVec3::ZERO, dims - 1))
                } else {
                    usize::MAX
                }
            })
            .collect();
        let (start, order) = sort_by_cell(&keys, cells);
        list.points = order.iter().map(|&o| items[o as usize].1).collect();
        list.ids = order.iter().map(|&o| items[o as usize].0).collect();
        list.start = start;
        list
    }

    /// Bins `items` into cells of at least `edge` Å over the bounding box of their finite
    /// positions, with `pad` spare cells on every side. The edge grows (by factors of 1.25)
    /// while there would be more than eight cells per item (and 4096 in all), so that a few far
    /// apart points need no huge list.
    pub fn covering(items: &[(u32, Vec3)], edge: f32, pad: i32) -> CellList {
        let (lo, hi) = bounds(items.iter().map(|&(_, p)| p));
        let extent = (hi - lo).max(Vec3::ZERO).as_dvec3();
        let dims_for = |edge: f32| (extent / edge as f64).floor() + 1.0 + 2.0 * pad as f64;
        let limit = (8 * items.len()).max(1 << 12) as f64;
        let mut edge = edge.max(1e-3);
        while dims_for(edge).element_product() > limit {
            edge *= 1.25;
        }
        CellList::new(
            items,
            lo - pad as f32 * edge,
            edge,
            dims_for(edge).as_ivec3(),
        )
    }

    /// The cell holding position `p` (Å); outside `0..dims` when `p` is off the cells.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) / self.edge).floor().as_ivec3()
    }

    /// Flat index of in-range cell `c`.
    #[inline]
    pub fn flat(&self, c: IVec3) -> usize {
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize
    }

    /// True when cell `c` lies on the list.
    #[inline]
    pub fn contains(&self, c: IVec3) -> bool {
        c.cmpge(IVec3::ZERO).all() && c.cmplt(self.dims).all()
    }

    /// The positions (Å) and ids of the points in flat cells `first..=last`.
    #[inline]
    pub fn span(&self, first: usize, last: usize) -> (&[Vec3], &[u32]) {
        let (a, b) = (self.start[first] as usize, self.start[last + 1] as usize);
        (&self.points[a..b], &self.ids[a..b])
    }

    /// The positions (Å) and ids of the points in cell `c` (none when `c` is off the list).
    #[inline]
    pub fn cell(&self, c: IVec3) -> (&[Vec3], &[u32]) {
        if self.contains(c) {
            let k = self.flat(c);
            self.span(k, k)
        } else {
            (&[], &[])
        }
    }

    /// The low and high corners of cell `c` in Å.
    #[inline]
    pub fn cell_box(&self, c: IVec3) -> (Vec3, Vec3) {
        let lo = self.origin + c.as_vec3() * self.edge;
        (lo, lo + self.edge)
    }

    /// Where `p` (Å) lies on the list, or `None` when it is off the cells (or not finite).
    #[inline]
    pub fn locate(&self, p: Vec3) -> Option<Spot> {
        // The arithmetic of `cell_of` (lane by lane), so that a point is found in the cell it
        // was put in.
        let g = (Vec3A::from(p) - Vec3A::from(self.origin)) / self.edge;
        let inside = g.cmpge(Vec3A::ZERO).all() && g.cmplt(self.dims.as_vec3a()).all();
        inside.then(|| {
            let floor = g.floor();
            let cell = floor.as_ivec3();
            Spot {
                cell,
                flat: self.flat(cell),
                inside: (g - floor).into(),
            }
        })
    }

    /// Calls `f(first, last)` for each row (along x) of cells around `at` whose nearest point
    /// lies within √`d2` Å of the position at `at`: flat cells `first..=last`, consecutive
    /// around the position's column. Stops when `f` returns true and returns whether it did.
    #[inline]
    pub fn runs_within(&self, at: &Spot, d2: f32, f: impl FnMut(usize, usize) -> bool) -> bool {
        let (u, edge) = (at.inside, self.edge);
        // Squared gap in Å² from the position to the cells at offset `o` along axis `k`.
        let gap = move |k: usize, o: i32| {
            let g = match o {
                0 => 0.0,
                o if o > 0 => (o as f32 - u[k]) * edge,
                o => (-o as f32 - 1.0 + u[k]) * edge,
            };
            g * g
        };
        if d2 <= edge * edge {
            // The cells next to the position's own are as far as it reaches: gaps tabulated.
            let mut gaps = [[0.0f32; 3]; 3];
            for (k, row) in gaps.iter_mut().enumerate() {
                *row = [gap(k, -1), 0.0, gap(k, 1)];
            }
            self.runs(at.cell, 1, d2, |k, o| gaps[k][(o + 1) as usize], f)
        } else {
            let reach = (d2.sqrt() / edge).ceil() as i32;
            self.runs(at.cell, reach, d2, gap, f)
        }
    }

    /// [`CellList::runs_within`] for the cells up to `r` from cell `c`, with `gap(k, o)` the
    /// squared gap to the cells at offset `o` along axis `k`.
    #[inline(always)]
    fn runs(
        &self,
        c: IVec3,
        r: i32,
        d2: f32,
        gap: impl Fn(usize, i32) -> f32,
        mut f: impl FnMut(usize, usize) -> bool,
    ) -> bool {
        let (x0, x1) = ((c.x - r).max(0), (c.x + r).min(self.dims.x - 1));
        for z in (c.z - r).max(0)..=(c.z + r).min(self.dims.z - 1) {
            let gz = gap(2, z - c.z);
            if gz > d2 {
                continue;
            }
            for y in (c.y - r).max(0)..=(c.y + r).min(self.dims.y - 1) {
                let gy = gz + gap(1, y - c.y);
                if gy > d2 {
                    continue;
                }
                // Gaps grow away from the position's own column (gap 0), so the cells in
                // range are consecutive.
                let fits = |x: i32| gy + gap(0, x - c.x) <= d2;
                let (mut first, mut last) = (c.x, c.x);
                while first > x0 && fits(first - 1) {
                    first -= 1;
                }
                while last < x1 && fits(last + 1) {
                    last += 1;
                }
                let row = ((z * self.dims.y + y) * self.dims.x) as usize;
                if f(row + first as usize, row + last as usize) {
                    return true;
                }
            }
        }
        false
    }

    /// Calls `f(i, p_i, j, p_j)` once for every pair of points in the same or in touching cells
    /// (ids and positions in Å): every pair closer than [`CellList::edge`] among them. The
    /// caller applies its exact distance test.
    pub fn for_each_close_pair(&self, mut f: impl FnMut(u32, Vec3, u32, Vec3)) {
        // Of two touching cells exactly one is the other's neighbour at one of these 13
        // offsets (the other 13 are their opposites).
        let mut forward = Vec::with_capacity(13);
        for z in -1..=1 {
            for y in -1..=1 {
                for x in -1..=1 {
                    if (z, y, x) > (0, 0, 0) {
                        forward.push(IVec3::new(x, y, z));
                    }
                }
            }
        }
        for z in 0..self.dims.z {
            for y in 0..self.dims.y {
                for x in 0..self.dims.x {
                    let c = IVec3::new(x, y, z);
                    let (points, ids) = self.cell(c);
                    for (a, (&p, &i)) in points.iter().zip(ids).enumerate() {
                        for (&q, &j) in points[a + 1..].iter().zip(&ids[a + 1..]) {
                            f(i, p, j, q);
                        }
                    }
                    if points.is_empty() {
                        continue;
                    }
                    for &o in &forward {
                        let (others, other_ids) = self.cell(c + o);
                        for (&p, &i) in points.iter().zip(ids) {
                            for (&q, &j) in others.iter().zip(other_ids) {
                                f(i, p, j, q);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Where a position lies on a [`CellList`] ([`CellList::locate`]).
#[derive(Debug, Clone, Copy)]
pub struct Spot {
    /// The cell holding the position.
    pub cell: IVec3,
    /// Its flat index.
    pub flat: usize,
    /// The position's place inside the cell, 0 to 1 per axis.
    pub inside: Vec3,
}

/// A [`CellList`] for one cutoff distance: which binned points lie within it of a position.
/// The cells some part of which lies within the cutoff of a point are marked, so that a
/// position far from every point is rejected by one look-up; otherwise the rows of cells
/// around it are read, skipping cells whose nearest point is beyond the cutoff.
#[derive(Debug, Clone)]
pub struct CutoffCells {
    cells: CellList,
    /// The list's positions (Å) in its order, 16-byte aligned: the distance tests of the
    /// queries run on these (SIMD lanes), not on the list's packed copies.
    aligned: Vec<Vec3A>,
    /// The cutoff squared, Å².
    d2: f32,
    /// True for the cells that some part of lies within the cutoff of a point.
    reached: Vec<bool>,
}

impl CutoffCells {
    /// Bins `items` (id, position in Å; those not finite left out) in cells `cutoff` Å wide
    /// over their bounding box, padded by two cells, and marks the cells within `cutoff` of a
    /// point. The cells are made wider (all alike) where the box would need more than eight
    /// cells per item and 4096 in all, so that a few far apart points need no huge list.
    pub fn new(items: &[(u32, Vec3)], cutoff: f32) -> CutoffCells {
        let (lo, hi) = bounds(items.iter().map(|&(_, p)| p));
        let extent = (hi - lo).max(Vec3::splat(1e-3));
        let max_cells = (8 * items.len()).max(1 << 12) as f64;
        let mut edge = cutoff.max(1e-3);
        let dims_for = |edge: f32| (extent / edge).floor() + 1.0;
        let total = dims_for(edge).as_dvec3().element_product();
        if total > max_cells {
            edge *= (total / max_cells).cbrt() as f32 * 1.01;
        }
        // One cell of reach plus one spare (absorbing rounding) on every side.
        let pad = 2;
        let dims = dims_for(edge).as_ivec3() + 2 * pad;
        let cells = CellList::new(items, lo - pad as f32 * edge, edge, dims);
        let d2 = cutoff * cutoff;
        let mut reached = vec![false; cells.start.len() - 1];
        for &p in &cells.points {
            if let Some(at) = cells.locate(p) {
                cells.runs_within(&at, d2, |first, last| {
                    reached[first..=last].fill(true);
                    false
                });
            }
        }
        let aligned = cells.points.iter().map(|&p| Vec3A::from(p)).collect();
        CutoffCells {
            cells,
            aligned,
            d2,
            reached,
        }
    }

    /// The aligned positions (Å) of the points in flat cells `first..=last`, with their ids.
    #[inline]
    fn span(&self, first: usize, last: usize) -> (&[Vec3A], &[u32]) {
        let start = &self.cells.start;
        let (a, b) = (start[first] as usize, start[last + 1] as usize);
        (&self.aligned[a..b], &self.cells.ids[a..b])
    }

    /// Where `p` lies, when in a cell that some point reaches.
    #[inline]
    fn reached(&self, p: Vec3A) -> Option<Spot> {
        self.cells
            .locate(p.into())
            .filter(|at| self.reached[at.flat])
    }

    /// True when some binned point lies within the cutoff (inclusive) of `p` (Å).
    #[inline]
    pub fn any_within(&self, p: Vec3A) -> bool {
        let Some(at) = self.reached(p) else {
            return false;
        };
        let d2 = self.d2;
        let close = |points: &[Vec3A]| points.iter().any(|q| q.distance_squared(p) <= d2);
        // The position's own cell first: inside a dense set that settles it.
        close(self.span(at.flat, at.flat).0)
            || self
                .cells
                .runs_within(&at, d2, |first, last| close(self.span(first, last).0))
    }

    /// Calls `f(id)` for every binned point within the cutoff (inclusive) of `p` (Å).
    #[inline]
    pub fn for_each_within(&self, p: Vec3A, mut f: impl FnMut(u32)) {
        let Some(at) = self.reached(p) else {
            return;
        };
        let d2 = self.d2;
        self.cells.runs_within(&at, d2, |first, last| {
            let (points, ids) = self.span(first, last);
            for (q, &i) in points.iter().zip(ids) {
                if q.distance_squared(p) <= d2 {
                    f(i);
                }
            }
            false
        });
    }
}

/// The low and high corners (Å) of the bounding box of the finite `points`; a box around the
/// origin of zero size when there are none.
pub fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let (lo, hi) = points
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    if lo.is_finite() {
        (lo, hi)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

#[cfg(test)]
mod tests;
