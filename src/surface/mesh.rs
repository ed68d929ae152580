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
            .map(|chunk| accumulate_area_volume((0.0, 0.0), chunk, |i| self.positions[i as usize]))
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

/// Triangles per batch of [`accumulate_area_volume`].
const BATCH: usize = 64;

/// `sums` plus the area (Å²) and signed volume (Å³) of each triangle of `indices` (vertex
/// triples, `position` giving each vertex), added in triangle order: bitwise the fold of
/// [`triangle_area`] and [`signed_volume`]. Triangles go in batches whose terms are computed
/// independently of each other (the compiler vectorises them: two f64 lanes, one square root
/// and one division per lane) before the in-order sums, which the plain fold spends most of
/// its time waiting on.
pub(super) fn accumulate_area_volume(
    sums: (f64, f64),
    indices: &[u32],
    position: impl Fn(u32) -> Vec3,
) -> (f64, f64) {
    let (mut area, mut volume) = sums;
    // Per batch: the first vertex and the two edges from it, as f64, one array per coordinate.
    let mut a = [[0.0f64; BATCH]; 3];
    let mut e1 = [[0.0f64; BATCH]; 3];
    let mut e2 = [[0.0f64; BATCH]; 3];
    let mut b = [[0.0f64; BATCH]; 3];
    let mut c = [[0.0f64; BATCH]; 3];
    let mut terms = [[0.0f64; BATCH]; 2];
    for batch in indices.chunks(3 * BATCH) {
        let n = batch.len() / 3;
        for (t, tri) in batch.chunks_exact(3).enumerate() {
            let [p, q, r] = [tri[0], tri[1], tri[2]].map(&position);
            // The edges are differences in f32, as in `triangle_area`.
            let (d1, d2) = (q - p, r - p);
            for k in 0..3 {
                a[k][t] = f64::from(p[k]);
                b[k][t] = f64::from(q[k]);
                c[k][t] = f64::from(r[k]);
                e1[k][t] = f64::from(d1[k]);
                e2[k][t] = f64::from(d2[k]);
            }
        }
        let [area_terms, volume_terms] = &mut terms;
        for t in 0..n {
            // `triangle_area`: 0.5 |e1 x e2|, glam's operation order.
            let x = e1[1][t] * e2[2][t] - e2[1][t] * e1[2][t];
            let y = e1[2][t] * e2[0][t] - e2[2][t] * e1[0][t];
            let z = e1[0][t] * e2[1][t] - e2[0][t] * e1[1][t];
            area_terms[t] = 0.5 * (x * x + y * y + z * z).sqrt();
            // `signed_volume`: a . (b x c) / 6.
            let x = b[1][t] * c[2][t] - c[1][t] * b[2][t];
            let y = b[2][t] * c[0][t] - c[2][t] * b[0][t];
            let z = b[0][t] * c[1][t] - c[0][t] * b[1][t];
            volume_terms[t] = (a[0][t] * x + a[1][t] * y + a[2][t] * z) / 6.0;
        }
        for t in 0..n {
            area += area_terms[t];
            volume += volume_terms[t];
        }
    }
    (area, volume)
}

/// Area of triangle (a, b, c) in Å², in f64.
pub(super) fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length()
}

/// Signed volume `a . (b x c) / 6` of the tetrahedron (origin, a, b, c) in Å³, in f64.
pub(super) fn signed_volume(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The batched sums must be bitwise the plain in-order fold, for any triangle count (full
    /// batches, a partial last batch, none) and any starting sums.
    #[test]
    fn batched_sums_are_bitwise_the_plain_fold() {
        // A small deterministic generator of awkward coordinates (mixed magnitudes and signs).
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let unit = (state >> 40) as f32 / (1u64 << 24) as f32;
            (unit - 0.3) * [1.0, 37.5, 1234.0][(state % 3) as usize]
        };
        let positions: Vec<Vec3> = (0..500)
            .map(|_| Vec3::new(next(), next(), next()))
            .collect();
        let indices: Vec<u32> = (0..3 * 389).map(|k| ((k * 7919) % 500) as u32).collect();
        for triangles in [0, 1, BATCH - 1, BATCH, BATCH + 1, 389] {
            let tris = &indices[..3 * triangles];
            let start = (0.25, -3.5);
            let plain = tris.chunks_exact(3).fold(start, |(a, v), t| {
                let [p, q, r] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
                (a + triangle_area(p, q, r), v + signed_volume(p, q, r))
            });
            let batched = accumulate_area_volume(start, tris, |i| positions[i as usize]);
            assert_eq!(
                batched.0.to_bits(),
                plain.0.to_bits(),
                "area, {triangles} triangles"
            );
            assert_eq!(
                batched.1.to_bits(),
                plain.1.to_bits(),
                "volume, {triangles} triangles"
            );
        }
    }
}
