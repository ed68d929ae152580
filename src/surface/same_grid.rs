//! Two surfaces on one grid (an interface's side and its complex): which vertex of one lies on
//! the grid edge a vertex of the other lies on ([`EdgeTable`]), and which atoms' terms differ
//! between their sums ([`ChangedAtoms`]), so that work one did can stand for the other's where
//! no such atom reaches ([`super::analytic::RefinedReuse`] for refined vertices,
//! [`crate::measure`]'s per-atom weighing).
//!
//! A Marching Cubes vertex lies on a grid edge: two of its coordinates are exactly on sample
//! planes (the arithmetic of [`GridSpec::point`]; interpolated and refined positions alike move
//! only along the edge), the third strictly between the edge's ends. A vertex on a sample (all
//! three on planes) or moved off its edge (the refinement's rare fallback) has no edge.

use glam::Vec3;

use super::GridSpec;

/// Clearance beyond the rules' distances that a changed atom must keep (Å): covers the f32
/// rounding of the distances and cutoffs compared.
pub(crate) const CLEARANCE_SLACK: f32 = 0.01;

/// The vertices of a mesh by the grid edge they lie on: an open-addressing table from edge
/// keys (`3 * sample index + axis`) to vertex indices.
#[derive(Debug)]
pub struct EdgeTable {
    /// Edge keys, `u64::MAX` where empty; length a power of two.
    keys: Vec<u64>,
    /// Vertex index of each key.
    slots: Vec<u32>,
}

impl EdgeTable {
    /// Bytes the table of `vertices` vertices takes.
    pub fn bytes_for(vertices: usize) -> u64 {
        (Self::capacity_for(vertices) * 12) as u64
    }

    fn capacity_for(vertices: usize) -> usize {
        (2 * vertices).next_power_of_two().max(16)
    }

    /// The vertices at `positions` (Å) on `grid` that lie strictly inside a grid edge, by edge.
    pub fn new(positions: &[Vec3], grid: &GridSpec) -> EdgeTable {
        let capacity = Self::capacity_for(positions.len());
        let mut table = EdgeTable {
            keys: vec![u64::MAX; capacity],
            slots: vec![0; capacity],
        };
        for (i, p) in positions.iter().enumerate() {
            if let Some(key) = edge_key(grid, *p) {
                table.insert(key, i as u32);
            }
        }
        table
    }

    /// The vertex on the edge from sample `start` (linear index) along `axis`.
    pub fn on_edge(&self, start: usize, axis: usize) -> Option<usize> {
        self.get(3 * start as u64 + axis as u64)
    }

    fn home(&self, key: u64) -> usize {
        // Fibonacci hashing into the power-of-two table.
        let shift = 64 - self.keys.len().trailing_zeros();
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize
    }

    fn insert(&mut self, key: u64, vertex: u32) {
        let mask = self.keys.len() - 1;
        let mut at = self.home(key);
        loop {
            if self.keys[at] == u64::MAX || self.keys[at] == key {
                // A key seen twice (two vertices on one edge cannot come from Marching Cubes)
                // keeps its first vertex.
                if self.keys[at] == u64::MAX {
                    self.keys[at] = key;
                    self.slots[at] = vertex;
                }
                return;
            }
            at = (at + 1) & mask;
        }
    }

    /// The vertex with edge key `key`.
    pub fn get(&self, key: u64) -> Option<usize> {
        let mask = self.keys.len() - 1;
        let mut at = self.home(key);
        loop {
            match self.keys[at] {
                k if k == key => return Some(self.slots[at] as usize),
                u64::MAX => return None,
                _ => at = (at + 1) & mask,
            }
        }
    }
}

/// The key of the grid edge `p` (Å) lies strictly inside, when two of its coordinates are
/// exactly on sample planes and the third between two samples.
pub(crate) fn edge_key(grid: &GridSpec, p: Vec3) -> Option<u64> {
    let (o, h) = (grid.origin, grid.spacing);
    let mut index = [0u32; 3];
    let mut along = None;
    for axis in 0..3 {
        let n = grid.dims[axis];
        let f = (p[axis] - o[axis]) / h;
        if !f.is_finite() || f < 0.0 || f > (n - 1) as f32 {
            return None;
        }
        // f >= 0, so truncation is floor (and needs no libm call without SSE4.1).
        let nearest = (f + 0.5) as u32;
        if o[axis] + h * nearest as f32 == p[axis] {
            index[axis] = nearest;
            continue;
        }
        if along.is_some() {
            return None;
        }
        // The edge's start: the last sample plane at or below p (f rounded may be off by one).
        let mut start = (f as u32).min(n.saturating_sub(2));
        if o[axis] + h * start as f32 > p[axis] {
            start = start.checked_sub(1)?;
        } else if o[axis] + h * (start + 1) as f32 <= p[axis] {
            start += 1;
        }
        let (lo, hi) = (o[axis] + h * start as f32, o[axis] + h * (start + 1) as f32);
        if !(lo < p[axis] && p[axis] < hi) || start + 1 >= n {
            return None;
        }
        index[axis] = start;
        along = Some(axis);
    }
    let axis = along?;
    Some(3 * grid.index(index[0], index[1], index[2]) as u64 + axis as u64)
}

/// Atoms whose terms differ between two surfaces on one grid, binned by position, to tell the
/// points none of them reaches.
#[derive(Debug)]
pub(crate) struct ChangedAtoms {
    origin: Vec3,
    /// Cell edge (Å): at least every atom's cutoff plus the largest clearance asked, so a
    /// point's 27 cells hold every atom that can reach it.
    cell: f32,
    dims: [i32; 3],
    /// `start[c]..start[c + 1]` are cell `c`'s atoms in `atoms`.
    start: Vec<u32>,
    /// Position (Å) and cutoff plus [`CLEARANCE_SLACK`] (Å) of each atom, by cell.
    atoms: Vec<(Vec3, f32)>,
}

impl ChangedAtoms {
    /// `atoms` (position and cutoff, Å) binned for tests at up to `extra` Å beyond a cutoff.
    pub(crate) fn new(grid: &GridSpec, atoms: &[(Vec3, f32)], extra: f32) -> ChangedAtoms {
        let cell = atoms
            .iter()
            .map(|&(_, cut)| cut + extra + CLEARANCE_SLACK)
            .fold(grid.spacing, f32::max);
        let extent = grid.spacing * Vec3::from(grid.dims.map(|d| d as f32));
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as i32).clamp(1, 1024));
        let mut changed = ChangedAtoms {
            origin: grid.origin,
            cell,
            dims,
            start: vec![0; (dims[0] * dims[1] * dims[2]) as usize + 1],
            atoms: vec![(Vec3::ZERO, 0.0); atoms.len()],
        };
        let cells: Vec<usize> = atoms.iter().map(|(p, _)| changed.cell_of(*p)).collect();
        for &c in &cells {
            changed.start[c + 1] += 1;
        }
        for c in 1..changed.start.len() {
            changed.start[c] += changed.start[c - 1];
        }
        let mut fill = changed.start.clone();
        for (&(p, cut), &c) in atoms.iter().zip(&cells) {
            changed.atoms[fill[c] as usize] = (p, cut + CLEARANCE_SLACK);
            fill[c] += 1;
        }
        changed
    }

    fn cell_coords(&self, p: Vec3) -> [i32; 3] {
        let c = (p - self.origin) / self.cell;
        // Cells past the grid hold the atoms beyond it (they are clamped in).
        [0, 1, 2].map(|a| (c[a].floor() as i32).clamp(0, self.dims[a] - 1))
    }

    fn cell_of(&self, p: Vec3) -> usize {
        let [x, y, z] = self.cell_coords(p);
        (x + self.dims[0] * (y + self.dims[1] * z)) as usize
    }

    /// True when some atom is closer to `mid` (Å) than its cutoff plus `extra` (Å, at most the
    /// `extra` the atoms were binned for) plus [`CLEARANCE_SLACK`].
    pub(crate) fn near(&self, mid: Vec3, extra: f32) -> bool {
        let [cx, cy, cz] = self.cell_coords(mid);
        let [nx, ny, nz] = self.dims;
        for z in (cz - 1).max(0)..=(cz + 1).min(nz - 1) {
            for y in (cy - 1).max(0)..=(cy + 1).min(ny - 1) {
                let row = nx * (y + ny * z);
                let first = (row + (cx - 1).max(0)) as usize;
                let last = (row + (cx + 1).min(nx - 1)) as usize;
                let run = self.start[first] as usize..self.start[last + 1] as usize;
                if self.atoms[run].iter().any(|(p, cut)| {
                    let r = cut + extra;
                    (mid - *p).length_squared() < r * r
                }) {
                    return true;
                }
            }
        }
        false
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small grid off the origin, with a spacing that is not a power of two (shared with the
    /// tests of [`crate::surface::analytic::RefinedReuse`]).
    pub(crate) fn grid() -> GridSpec {
        GridSpec {
            origin: Vec3::new(-3.7, 1.3, 10.1),
            spacing: 0.7,
            dims: [9, 8, 7],
        }
    }

    #[test]
    fn a_vertex_inside_an_edge_finds_that_edge_and_no_other_point_does() {
        let g = grid();
        for (i, j, k, axis) in [(0, 0, 0, 0), (3, 4, 5, 1), (7, 6, 5, 2), (2, 7, 0, 0)] {
            let a = g.point(i, j, k);
            let mut b_idx = [i, j, k];
            b_idx[axis] += 1;
            let b = g.point(b_idx[0], b_idx[1], b_idx[2]);
            for t in [1e-3, 0.25, 0.5, 0.999] {
                let p = a + t * (b - a);
                let key = edge_key(&g, p).expect("a point inside an edge");
                assert_eq!(key, 3 * g.index(i, j, k) as u64 + axis as u64, "t = {t}");
            }
            // On a sample: ambiguous, left out.
            assert_eq!(edge_key(&g, a), None);
        }
        // Off every edge, or outside the grid.
        assert_eq!(
            edge_key(&g, g.point(2, 2, 2) + Vec3::new(0.1, 0.1, 0.0)),
            None
        );
        assert_eq!(
            edge_key(&g, g.point(0, 0, 0) - Vec3::new(0.2, 0.0, 0.0)),
            None
        );
    }

    #[test]
    fn a_table_finds_each_vertex_by_its_edge_and_a_changed_atom_by_its_reach() {
        let g = grid();
        let (a, b) = (g.point(4, 4, 3), g.point(4, 5, 3));
        let positions = [0.3 * a + 0.7 * b, g.point(1, 1, 1)];
        let table = EdgeTable::new(&positions, &g);
        assert_eq!(table.on_edge(g.index(4, 4, 3), 1), Some(0));
        assert_eq!(table.on_edge(g.index(4, 4, 3), 0), None);
        assert_eq!(
            table.on_edge(g.index(1, 1, 1), 0),
            None,
            "a vertex on a sample"
        );
        let changed = ChangedAtoms::new(&g, &[(Vec3::new(5.0, 5.0, 12.0), 2.0)], 1.0);
        assert!(changed.near(Vec3::new(5.0, 7.9, 12.0), 1.0));
        assert!(!changed.near(Vec3::new(5.0, 7.9, 12.0), 0.0));
        assert!(changed.near(Vec3::new(5.0, 6.99, 12.0), 0.0));
        assert!(!changed.near(Vec3::new(5.0, 8.05, 12.0), 1.0));
    }
}
