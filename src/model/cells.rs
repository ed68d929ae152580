//! One cell list for every neighbour search in the crate: points binned by a counting sort into
//! cubic cells of a given edge (Å) over a box, so that the points near a place are read from the
//! few cells around it. Bond guessing ([`super::bonds`]), exposure counts
//! ([`super::exposure`]), radius fitting ([`super::sizing`]) and `within` selections build on
//! it; periodic callers bin wrapped points (and their images) or their own cell keys with
//! [`sort_by_cell`].

use glam::{IVec3, Vec3};

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

    /// Corner of cell (0, 0, 0) in Å.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Cell edge in Å.
    pub fn edge(&self) -> f32 {
        self.edge
    }

    /// Cells along each axis.
    pub fn dims(&self) -> IVec3 {
        self.dims
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
