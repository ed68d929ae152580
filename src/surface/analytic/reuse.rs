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
//! The complex's vertices are found by the grid edge they lie on
//! ([`crate::surface::same_grid::EdgeTable`]); one on a sample or off its edge is left out and
//! the side solves it itself.
//!
//! Cost: one table entry per vertex of the complex (a few hundred microseconds on a 30,000-
//! vertex frame) and, per crossed edge of a side, one lookup and a test against the changed
//! atoms of the 27 cells around it; a hit saves the gather and the Newton steps, most of a
//! refined surface's time.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;

use super::super::curved::SharpTriangles;
use super::super::memory::memory_for;
use super::super::same_grid::{ChangedAtoms, EdgeTable};
use super::super::{GridSpec, Mesh};

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
    /// The vertices by grid edge.
    table: EdgeTable,
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
        let sharp_count = sharp.map_or(0, |s| s.triangles.len());
        let bytes = EdgeTable::bytes_for(mesh.positions.len())
            + (mesh.positions.len() * 24 + sharp_count * 64) as u64;
        if bytes.saturating_mul(MEMORY_SHARE) > memory_for(bytes, None) {
            return None;
        }
        let by_corners = sharp.map_or_else(HashMap::new, |s| {
            s.triangles
                .iter()
                .map(|t| (corner_bits(t.corners), (t.area, t.volume)))
                .collect()
        });
        Some(ReusableSurface {
            grid: *grid,
            iso,
            sharp: by_corners,
            centre: sharp.map(|s| s.centre),
            table: EdgeTable::new(&mesh.positions, grid),
            positions: mesh.positions.clone(),
            normals: mesh.normals.clone(),
        })
    }

    /// The grid and isovalue the vertices were refined on.
    pub fn fits(&self, grid: &GridSpec, iso: f32) -> bool {
        self.grid == *grid && self.iso.to_bits() == iso.to_bits()
    }
}

/// The bits of a triangle's corners, in order.
fn corner_bits(corners: [Vec3; 3]) -> [u32; 9] {
    let c = corners.map(|p| p.to_array().map(f32::to_bits));
    [
        c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2],
    ]
}

/// What a side of an interface may take from the complex: its vertices by edge and the atoms
/// that differ. Counts the vertices taken.
#[derive(Debug)]
pub struct RefinedReuse {
    surface: Arc<ReusableSurface>,
    changed: ChangedAtoms,
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
        let sharp_reach = SHARP_REACH_SPACINGS * surface.grid.spacing;
        let changed = ChangedAtoms::new(&surface.grid, changed, sharp_reach);
        RefinedReuse {
            surface,
            changed,
            taken: AtomicUsize::new(0),
            taken_sharp: AtomicUsize::new(0),
        }
    }

    /// The grid spacing H (Å).
    fn spacing(&self) -> f32 {
        self.surface.grid.spacing
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
        let binned = reach.is_finite() && reach <= SHARP_REACH_SPACINGS * self.spacing();
        if !binned || self.changed.near(centroid, reach) {
            return None;
        }
        self.taken_sharp.fetch_add(1, Ordering::Relaxed);
        Some(found)
    }

    /// The complex's vertex (position in Å, unit normal) on the edge from sample `start`
    /// (linear index, at `pa`) along `axis` to `pb`, when the rule of the module docs allows.
    pub fn vertex(&self, start: usize, axis: usize, pa: Vec3, pb: Vec3) -> Option<(Vec3, Vec3)> {
        let found = self.surface.table.on_edge(start, axis)?;
        if self.changed.near(0.5 * (pa + pb), self.spacing()) {
            return None;
        }
        self.taken.fetch_add(1, Ordering::Relaxed);
        Some((self.surface.positions[found], self.surface.normals[found]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::same_grid::tests::grid;

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
