//! Refined vertices taken from another surface on the same grid instead of solved again: the
//! sides of an interface ([`crate::measure::interface_on`]) are computed on the complex's grid,
//! and away from the other side a side's Gaussian sum is the complex's, term for term, so its
//! root on a grid edge is the complex's vertex there.
//!
//! Rule: a side's vertex on the grid edge from sample `a` along `axis` is the complex's vertex
//! on that edge when (1) the complex has one there, and (2) no *changed* atom reaches any point
//! the refinement of that edge evaluates, i.e. every changed atom `j` is at least
//! `cut_j + H + 0.01 Å` from the edge's midpoint (the search gathers the atoms reaching within
//! half an edge of it, its fallback projection within a whole edge; `cut_j` is the atom's
//! cutoff, `q alpha`, in Å). The changed atoms are those of the other side and those of this
//! side whose radius differs in the complex (radii that follow exposure), each with the longer
//! of its cutoffs. Where (2) holds the side's samples at the edge's ends are the complex's too
//! (they lie within the edge), so the edge is crossed in both, from the same linear estimate.
//! The result is the side's own vertex to the rounding of the Gaussians' summation order
//! (both sum the same atoms in canonical order, so in practice the same bits).
//!
//! Sharp triangles ([`crate::surface::curved`]) are measured on the sum alone, from their
//! corners: points of the triangle are projected onto the sum at most the triangle's longest
//! edge, with the atoms that reach within its radius plus that edge of its centroid. A side's
//! sharp triangle whose corners are, bit for bit, those of a sharp triangle the complex
//! measured ([`crate::surface::curved::SharpTriangles`]) takes the complex's area and volume
//! when every changed atom is at least `cut_j + radius + longest edge + 0.01 Å` from its
//! centroid (a Marching Cubes triangle lies in one grid cell, so that is at most
//! `cut_j + 2 sqrt(3) H`). The side's volumes are then taken about the complex's centre, so
//! that the two sum alike (its area moves by the rounding of the coordinates relative to
//! that centre, about 1e-8).
//!
//! The complex's vertices are found by position: a vertex on a grid edge has its two other
//! coordinates exactly on the grid's sample planes ([`GridSpec::point`]'s arithmetic), the
//! third strictly between the edge's ends. A vertex on a sample (all three on planes) or moved
//! off its edge (the refinement's rare fallback) is left out; the side solves those itself.
//!
//! Cost: one table entry per vertex of the complex (a few hundred microseconds on a 30,000-
//! vertex frame) and, per crossed edge of a side, one lookup and a test against the changed
//! atoms of the 27 cells around it; a hit saves the gather and the Newton steps, most of a
//! refined surface's time.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use std::collections::HashMap;

use glam::Vec3;

use super::super::curved::SharpTriangles;
use super::super::memory::memory_for;
use super::super::{GridSpec, Mesh};

/// Clearance beyond the rule's distances that a changed atom must keep (Å): covers the f32
/// rounding of the distances and cutoffs compared.
const CLEARANCE_SLACK: f32 = 0.01;

/// The tables of a [`ReusableSurface`] may take at most one part in this many of the memory
/// available (a side that takes nothing is only slower).
pub const MEMORY_SHARE: u64 = 16;

/// A sharp triangle's reach beyond its centroid, in grid spacings: its radius plus its longest
/// edge, each at most a cell's diagonal (`sqrt(3) H`).
const SHARP_REACH_SPACINGS: f32 = 2.0 * 1.732_051;

/// What a refined surface offers other surfaces on its grid: its vertices by grid edge (an
/// open-addressing table from edge keys, `3 * sample index + axis`, to vertex indices) and its
/// sharp triangles by corners.
#[derive(Debug)]
pub struct ReusableSurface {
    grid: GridSpec,
    /// Isovalue the vertices lie on (dimensionless).
    iso: f32,
    /// Area (Å²) and volume about `centre` (Å³) of each sharp triangle, by the bits of its
    /// corners in order.
    sharp: HashMap<[u32; 9], (f64, f64)>,
    /// The point the sharp triangles' volumes are about (Å); `None` without them.
    centre: Option<Vec3>,
    /// Edge keys, `u64::MAX` where empty; length a power of two.
    keys: Vec<u64>,
    /// Vertex index of each key.
    slots: Vec<u32>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
}

impl ReusableSurface {
    /// The vertices of `mesh` (refined on `grid` at isovalue `iso`, with unit normals) that lie
    /// strictly inside a grid edge, by edge, and its `sharp` triangles as its measure recorded
    /// them. `None` when the mesh has no normal per vertex, or when the tables would take more
    /// than a [`MEMORY_SHARE`] of the memory available (then every vertex is solved).
    pub fn new(
        mesh: &Mesh,
        sharp: Option<&SharpTriangles>,
        grid: &GridSpec,
        iso: f32,
    ) -> Option<ReusableSurface> {
        if mesh.normals.len() != mesh.positions.len() {
            return None;
        }
        let capacity = (2 * mesh.positions.len()).next_power_of_two().max(16);
        let sharp_count = sharp.map_or(0, |s| s.triangles.len());
        let bytes = (capacity * 12 + mesh.positions.len() * 24 + sharp_count * 64) as u64;
        if bytes.saturating_mul(MEMORY_SHARE) > memory_for(bytes, None) {
            return None;
        }
        let by_corners = sharp.map_or_else(HashMap::new, |s| {
            s.triangles
                .iter()
                .map(|t| (corner_bits(t.corners), (t.area, t.volume)))
                .collect()
        });
        let mut table = ReusableSurface {
            grid: *grid,
            iso,
            sharp: by_corners,
            centre: sharp.map(|s| s.centre),
            keys: vec![u64::MAX; capacity],
            slots: vec![0; capacity],
            positions: mesh.positions.clone(),
            normals: mesh.normals.clone(),
        };
        for (i, p) in mesh.positions.iter().enumerate() {
            if let Some(key) = edge_key(grid, *p) {
                table.insert(key, i as u32);
            }
        }
        Some(table)
    }

    /// The grid and isovalue the vertices were refined on.
    pub fn fits(&self, grid: &GridSpec, iso: f32) -> bool {
        self.grid == *grid && self.iso.to_bits() == iso.to_bits()
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

    fn get(&self, key: u64) -> Option<usize> {
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

/// The bits of a triangle's corners, in order.
fn corner_bits(corners: [Vec3; 3]) -> [u32; 9] {
    let c = corners.map(|p| p.to_array().map(f32::to_bits));
    [
        c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2],
    ]
}

/// The key of the grid edge `p` (Å) lies strictly inside, when two of its coordinates are
/// exactly on sample planes and the third between two samples.
fn edge_key(grid: &GridSpec, p: Vec3) -> Option<u64> {
    let (o, h) = (grid.origin, grid.spacing);
    let mut index = [0u32; 3];
    let mut along = None;
    for axis in 0..3 {
        let n = grid.dims[axis];
        let f = (p[axis] - o[axis]) / h;
        if !f.is_finite() || f < 0.0 || f > (n - 1) as f32 {
            return None;
        }
        let nearest = f.round() as u32;
        if o[axis] + h * nearest as f32 == p[axis] {
            index[axis] = nearest;
            continue;
        }
        if along.is_some() {
            return None;
        }
        // The edge's start: the last sample plane at or below p (f rounded may be off by one).
        let mut start = (f.floor() as u32).min(n.saturating_sub(2));
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

/// Atoms whose terms differ between a side and the complex, binned by position for the test of
/// the module docs.
#[derive(Debug)]
struct ChangedAtoms {
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
    fn new(grid: &GridSpec, atoms: &[(Vec3, f32)], extra: f32) -> ChangedAtoms {
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
    fn near(&self, mid: Vec3, extra: f32) -> bool {
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

/// What a side of an interface may take from the complex: its vertices by edge and the atoms
/// that differ. Counts the vertices taken.
#[derive(Debug)]
pub struct RefinedReuse {
    surface: Arc<ReusableSurface>,
    changed: ChangedAtoms,
    /// Grid spacing H (Å).
    spacing: f32,
    /// Vertices taken.
    taken: AtomicUsize,
    /// Sharp triangles taken.
    taken_sharp: AtomicUsize,
}

impl RefinedReuse {
    /// Reuse of `vertices` for a surface whose terms differ from theirs only by `changed`
    /// atoms: position (Å) and cutoff (Å, the longer of the two surfaces' where an atom is in
    /// both).
    pub fn new(surface: Arc<ReusableSurface>, changed: &[(Vec3, f32)]) -> RefinedReuse {
        let spacing = surface.grid.spacing;
        let changed = ChangedAtoms::new(&surface.grid, changed, SHARP_REACH_SPACINGS * spacing);
        RefinedReuse {
            surface,
            changed,
            spacing,
            taken: AtomicUsize::new(0),
            taken_sharp: AtomicUsize::new(0),
        }
    }

    /// True when the surface was refined on `grid` at isovalue `iso`.
    pub fn fits(&self, grid: &GridSpec, iso: f32) -> bool {
        self.surface.fits(grid, iso)
    }

    /// Vertices and sharp triangles taken so far.
    pub fn taken(&self) -> (usize, usize) {
        (
            self.taken.load(Ordering::Relaxed),
            self.taken_sharp.load(Ordering::Relaxed),
        )
    }

    /// The point the other surface's sharp volumes are about (Å), when it recorded them.
    pub fn centre(&self) -> Option<Vec3> {
        self.surface.centre
    }

    /// Area (Å²) and volume about [`RefinedReuse::centre`] (Å³) of the other surface's sharp
    /// triangle with these `corners` (Å, in order), when the rule of the module docs allows.
    pub fn sharp(&self, corners: [Vec3; 3]) -> Option<(f64, f64)> {
        if self.surface.sharp.is_empty() {
            return None;
        }
        let found = *self.surface.sharp.get(&corner_bits(corners))?;
        // The measure projects points of the triangle at most its longest edge, summing the
        // atoms that reach within its radius plus that of its centroid.
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners
            .map(|p| (p - centroid).length())
            .into_iter()
            .fold(0.0, f32::max);
        let [a, b, c] = corners;
        let longest = [b - a, c - b, a - c]
            .map(|e| e.length())
            .into_iter()
            .fold(0.0, f32::max);
        let reach = radius + longest;
        // Past the reach the changed atoms were binned for (not a Marching Cubes triangle), or
        // not finite: measured again.
        let binned = reach.is_finite() && reach <= SHARP_REACH_SPACINGS * self.spacing;
        if !binned || self.changed.near(centroid, reach) {
            return None;
        }
        self.taken_sharp.fetch_add(1, Ordering::Relaxed);
        Some(found)
    }

    /// The complex's vertex (position in Å, unit normal) on the edge from sample `start`
    /// (linear index, at `pa`) along `axis` to `pb`, when the rule of the module docs allows.
    pub fn vertex(&self, start: usize, axis: usize, pa: Vec3, pb: Vec3) -> Option<(Vec3, Vec3)> {
        let found = self.surface.get(3 * start as u64 + axis as u64)?;
        if self.changed.near(0.5 * (pa + pb), self.spacing) {
            return None;
        }
        self.taken.fetch_add(1, Ordering::Relaxed);
        Some((self.surface.positions[found], self.surface.normals[found]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> GridSpec {
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
    fn a_changed_atom_blocks_the_edges_it_can_reach() {
        let g = grid();
        let a = g.point(4, 4, 3);
        let b = g.point(5, 4, 3);
        let mesh = Mesh {
            positions: vec![0.5 * (a + b)],
            normals: vec![Vec3::X],
            ..Mesh::default()
        };
        let vertices = Arc::new(ReusableSurface::new(&mesh, None, &g, 0.5).unwrap());
        let start = g.index(4, 4, 3);
        let mid = 0.5 * (a + b);
        // Cutoff 2 Å: blocked within 2 + 0.7 + slack of the midpoint, free beyond.
        for (distance, blocked) in [(2.6, true), (2.75, false), (1.0, true), (6.0, false)] {
            let atom = mid + Vec3::new(0.0, distance, 0.0);
            let reuse = RefinedReuse::new(Arc::clone(&vertices), &[(atom, 2.0)]);
            let got = reuse.vertex(start, 0, a, b);
            assert_eq!(got.is_none(), blocked, "an atom {distance} Å away");
            assert_eq!(reuse.taken(), (usize::from(!blocked), 0));
        }
        // Another edge, or another axis, has no vertex.
        let reuse = RefinedReuse::new(Arc::clone(&vertices), &[]);
        assert!(reuse.vertex(start, 1, a, g.point(4, 5, 3)).is_none());
        assert!(reuse.vertex(start + 1, 0, b, g.point(6, 4, 3)).is_none());
        assert!(reuse.fits(&g, 0.5) && !reuse.fits(&g, 0.25));
    }

    #[test]
    fn a_changed_atom_blocks_the_sharp_triangles_it_can_reach() {
        use crate::surface::curved::{SharpTriangle, SharpTriangles};
        let g = grid();
        // A triangle in cell (4, 4, 3) with its corners on three of the cell's edges.
        let corners = [
            g.point(4, 4, 3) + Vec3::new(0.3, 0.0, 0.0),
            g.point(4, 4, 3) + Vec3::new(0.0, 0.4, 0.0),
            g.point(4, 4, 3) + Vec3::new(0.0, 0.0, 0.5),
        ];
        let sharp = SharpTriangles {
            centre: Vec3::new(1.0, 2.0, 3.0),
            triangles: vec![SharpTriangle {
                corners,
                area: 0.25,
                volume: -0.125,
            }],
        };
        let mesh = Mesh {
            positions: corners.to_vec(),
            normals: vec![Vec3::X; 3],
            ..Mesh::default()
        };
        let surface = Arc::new(ReusableSurface::new(&mesh, Some(&sharp), &g, 0.5).unwrap());
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners
            .map(|p| (p - centroid).length())
            .into_iter()
            .fold(0.0, f32::max);
        let longest = (corners[1] - corners[2]).length();
        // Cutoff 2 Å: blocked within 2 + radius + longest edge (+ slack) of the centroid.
        let edge = 2.0 + radius + longest;
        for (distance, blocked) in [(edge - 0.005, true), (edge + 0.02, false), (1.0, true)] {
            let atom = centroid + Vec3::new(distance, 0.0, 0.0);
            let reuse = RefinedReuse::new(Arc::clone(&surface), &[(atom, 2.0)]);
            assert_eq!(reuse.centre(), Some(sharp.centre));
            let got = reuse.sharp(corners);
            assert_eq!(got.is_none(), blocked, "an atom {distance} Å away");
            if !blocked {
                assert_eq!(got, Some((0.25, -0.125)));
                assert_eq!(reuse.taken(), (0, 1));
            }
        }
        // Other corners, or the same in another order, were not measured.
        let reuse = RefinedReuse::new(Arc::clone(&surface), &[]);
        let moved = [
            corners[0] + Vec3::new(1e-4, 0.0, 0.0),
            corners[1],
            corners[2],
        ];
        assert!(reuse.sharp(moved).is_none());
        assert!(reuse.sharp([corners[1], corners[0], corners[2]]).is_none());
    }
}
