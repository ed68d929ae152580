//! The triangle mesh both engines produce: indexed, closed, one vertex per crossed grid edge,
//! with outward normals and per-vertex colours; plus its area, volume and topology checks.

use std::collections::HashMap;

use glam::Vec3;
use rayon::prelude::*;

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in Å.
    pub positions: Vec<Vec3>,
    /// Unit outward normals (`-grad rho`, normalised), one per vertex.
    pub normals: Vec<Vec3>,
    /// Linear RGB colours in 0..1, one per vertex.
    pub colours: Vec<[f32; 3]>,
    /// Triangles as three vertex indices, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Iterator over triangles as three vertex positions (Å).
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.indices.chunks_exact(3).map(|t| {
            [
                self.positions[t[0] as usize],
                self.positions[t[1] as usize],
                self.positions[t[2] as usize],
            ]
        })
    }

    /// Surface area in Å² (sum of triangle areas, accumulated in f64).
    pub fn area(&self) -> f64 {
        self.sum_over_triangles(|[a, b, c]| triangle_area(a, b, c))
    }

    /// Enclosed volume in Å³ (sum of `v0 . (v1 x v2) / 6`, accumulated in f64).
    pub fn volume(&self) -> f64 {
        self.sum_over_triangles(|[a, b, c]| signed_volume(a, b, c))
    }

    /// Area in Å² and enclosed volume in Å³ in one pass (same values as [`Mesh::area`] and
    /// [`Mesh::volume`]).
    pub fn area_and_volume(&self) -> (f64, f64) {
        const CHUNK: usize = 3 * MEASURE_CHUNK_TRIANGLES;
        let partial: Vec<(f64, f64)> = self
            .indices
            .par_chunks(CHUNK)
            .map(|chunk| {
                chunk.chunks_exact(3).fold((0.0, 0.0), |(a, v), t| {
                    let [p, q, r] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
                    (a + triangle_area(p, q, r), v + signed_volume(p, q, r))
                })
            })
            .collect();
        partial
            .iter()
            .fold((0.0, 0.0), |(a, v), (pa, pv)| (a + pa, v + pv))
    }

    /// Sum of `f` over the triangles in f64, in parallel over fixed chunks summed in order, so
    /// the result does not depend on the thread count.
    fn sum_over_triangles(&self, f: impl Fn([Vec3; 3]) -> f64 + Sync) -> f64 {
        const CHUNK: usize = 3 * MEASURE_CHUNK_TRIANGLES;
        let partial: Vec<f64> = self
            .indices
            .par_chunks(CHUNK)
            .map(|chunk| {
                chunk
                    .chunks_exact(3)
                    .map(|t| f([t[0], t[1], t[2]].map(|i| self.positions[i as usize])))
                    .sum()
            })
            .collect();
        partial.iter().sum()
    }

    /// Counts of undirected edges by how many triangles use them: `(edges used by exactly two,
    /// edges used otherwise)`. A closed manifold mesh has no edges of the second kind.
    pub fn edge_use_counts(&self) -> (usize, usize) {
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for t in self.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let two = uses.values().filter(|&&n| n == 2).count();
        (two, uses.len() - two)
    }

    /// True when every edge belongs to exactly two triangles.
    pub fn is_closed(&self) -> bool {
        !self.indices.is_empty() && self.edge_use_counts().1 == 0
    }

    /// Euler characteristic V - E + F over the vertices that triangles use
    /// (2 per sphere-like closed component).
    pub fn euler_characteristic(&self) -> i64 {
        let mut used = vec![false; self.positions.len()];
        for &i in &self.indices {
            used[i as usize] = true;
        }
        let v = used.iter().filter(|&&u| u).count() as i64;
        let (two, other) = self.edge_use_counts();
        let e = (two + other) as i64;
        v - e + self.triangle_count() as i64
    }

    /// Axis-aligned bounds of the vertices in Å, or `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }
}

/// Triangles per partial sum of area and volume: the sums are taken over fixed chunks in
/// triangle order and the partial sums added in order, so they do not depend on the thread
/// count (and [`super::marching_cubes::measure_slabs`] reproduces them without a merged mesh).
pub(super) const MEASURE_CHUNK_TRIANGLES: usize = 16384;

/// Area of triangle (a, b, c) in Å², in f64.
pub(super) fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length()
}

/// Signed volume `a . (b x c) / 6` of the tetrahedron (origin, a, b, c) in Å³, in f64.
pub(super) fn signed_volume(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0
}
