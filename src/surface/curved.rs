//! Area and volume of the analytic surface from a Marching Cubes mesh whose vertices lie on it
//! with analytic normals (refined vertices, [`super::analytic`]), accounting for curvature: flat
//! triangles cut chords across the curved surface, so their area and volume fall short by a term
//! that shrinks as the square of the triangle size (one atom, H = alpha/2: -4.1 % in area).
//!
//! Method (for the measurement only; the mesh is not changed): every triangle is split once into
//! four by its edge midpoints, each lifted onto the surface by cubic Hermite interpolation along
//! its edge from the two end points and their normals: for an edge `p -> q` with unit normals
//! `n_p`, `n_q`, the surface's height over the chord's midpoint is
//! `s = (n_q - n_p) . (q - p) / (8 cos²(θ/4))`, θ the angle between the normals (the cubic
//! Hermite height `(n_q - n_p) . (q - p) / 8` with the factor that makes it exact on a sphere),
//! taken along `(n_p + n_q) / |n_p + n_q|` and capped at [`MAX_LIFT`] times the edge
//! length (where the normals turn too fast for the cubic to hold, e.g. across a crease). With
//! `A0` the flat area of a triangle and `A1` that of its four children, Richardson extrapolation
//! over the two levels, `A = A1 + (A1 - A0) / 3`, cancels the leading `h²` term of the chord
//! error (halving the edges quarters it). The same holds for the signed volume
//! `sum (a - c) . ((b - c) x (d - c)) / 6` about the mesh centre `c`. A midpoint depends only on
//! its edge (end points in index order), so the two triangles that share an edge get the same
//! point and the subdivided surface stays closed.
//!
//! Why this rather than projecting midpoints onto the Gaussian sum: the normals are already
//! exact (computed while refining), so the lift costs a few flops per edge and no evaluation of
//! the sum (a projection costs two or three, each over about a hundred atoms), and it needs
//! nothing but the mesh, so the GPU measures the same way in its reduction
//! (`shaders/measure.wgsl`). On the one-atom sphere and on 1hpv it agrees with projected
//! midpoints to better than 0.01 % (tests/it/surface_refine.rs).
//!
//! Sharp triangles: where a triangle's normals turn by more than 60° ([`SHARP_COS`]), across the
//! narrow creases between atoms of a sharp surface (the SES preset) or over a
//! feature smaller than the triangle, the lift is capped or wrong and such triangles came out
//! 12 % short on 1hpv's SES-preset surface at H = 1 Å (9 % of its triangles; the whole surface
//! 1.2 % short of its converged area; measured with the preset's first radii). With the field at hand ([`OnField`]), they are measured
//! on the Gaussian sum itself instead ([`sharp_area_volume`]): split 4 x 4, every point moved
//! onto the surface by Newton steps along the gradient, Richardson over that split and the 2 x 2
//! one. That brings the same surface within 0.5 % of its converged area at H = 1 Å and within
//! 0.04 % at 0.5 Å (tests/it/surface_refine.rs). At the default R and I (1hpv, quality high)
//! it moves the area at H = 2 Å from 0.9 % to 0.36 % below the converged one (H -> 0), and
//! at H = 1 Å by 0.04 %.
//!
//! Cost: about 100 flops per triangle, in parallel over fixed chunks of 256 triangles summed in
//! order (the result does not depend on the thread count; chunks this small spread the sharp
//! triangles, which cluster, over the threads); a sharp triangle costs 12 projections (its
//! corners are on the surface already), each a few evaluations of the sum over the atoms
//! gathered once for the triangle.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::Mesh;
use super::analytic::AnalyticField;

/// Largest lift of an edge midpoint, in units of the edge's length (a semicircle's).
pub const MAX_LIFT: f32 = 0.5;

/// The point of the surface over the midpoint of edge `p -> q` (Å) with unit normals `np`, `nq`
/// (the lift of the module docs).
#[inline]
pub fn lifted_midpoint(p: Vec3, q: Vec3, np: Vec3, nq: Vec3) -> Vec3 {
    let d = q - p;
    // Cubic Hermite height, then the circular-arc factor 1 / cos²(θ/4) (θ the angle between
    // the normals), which makes the lift exact on a sphere.
    let c2 = (0.5 * (1.0 + np.dot(nq))).max(0.0).sqrt();
    let s = (nq - np).dot(d) / 8.0 / (0.5 * (1.0 + c2)).max(0.5);
    let cap = MAX_LIFT * d.length();
    let n = np + nq;
    let nl = n.length();
    let m = 0.5 * (p + q);
    if nl > 0.0 && s.is_finite() {
        m + s.clamp(-cap, cap) * (n / nl)
    } else {
        m
    }
}

/// Triangles whose vertex normals turn by more than 60° (the smallest cosine between two of
/// them is below this) are measured on the Gaussian sum itself ([`sharp_area_volume`]).
pub const SHARP_COS: f32 = 0.5;
/// A sharp triangle's edges are split into this many parts for its measurement.
pub const SHARP_LEVEL: usize = 4;

/// The exact Gaussian sum a mesh lies on, for measuring its sharp triangles.
#[derive(Debug, Clone, Copy)]
pub struct OnField<'a> {
    /// The sum of the atoms' Gaussians.
    pub field: &'a AnalyticField,
    /// The isovalue I the mesh's vertices lie on (dimensionless).
    pub iso: f32,
}

/// Area (Å²) and enclosed volume (Å³) of the surface that `mesh` (vertices on it, analytic unit
/// normals) triangulates, with the curvature correction of the module docs; with `on`, its sharp
/// triangles (see [`SHARP_COS`]) measured on the Gaussian sum instead.
pub fn curved_area_volume(mesh: &Mesh, on: Option<OnField<'_>>) -> (f64, f64) {
    let measured = curved_measure(mesh, on, false);
    (measured.area, measured.volume)
}

/// A sharp triangle measured on the Gaussian sum ([`sharp_area_volume`]): its corners (Å, in
/// the mesh's order), its area (Å²) and its signed volume about [`SharpTriangles::centre`] (Å³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharpTriangle {
    /// The corners, mesh vertices, in the triangle's order (Å).
    pub corners: [Vec3; 3],
    /// Area of the piece of the level set over the triangle (Å²).
    pub area: f64,
    /// Its signed volume about the centre (Å³).
    pub volume: f64,
}

/// The sharp triangles of a refined surface as measured with it, for another surface on the
/// same grid to take where its sum is the same ([`super::analytic::RefinedReuse`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SharpTriangles {
    /// The point the volumes are about (Å): the centre of the mesh's bounding box.
    pub centre: Vec3,
    /// The triangles, in mesh order.
    pub triangles: Vec<SharpTriangle>,
}

/// What [`curved_measure`] found.
#[derive(Debug, Clone, Default)]
pub struct CurvedMeasure {
    /// Area in Å².
    pub area: f64,
    /// Enclosed volume in Å³.
    pub volume: f64,
    /// The sharp triangles measured on the sum, when asked to record them.
    pub sharp: Option<SharpTriangles>,
}

/// [`curved_area_volume`], recording the sharp triangles measured on the sum when `record`.
/// When `on`'s field takes another surface's results ([`AnalyticField::reuse`]), the
/// volume is about that surface's centre and a sharp triangle it measured, where no atom that
/// differs reaches, is taken instead of measured again.
pub fn curved_measure(mesh: &Mesh, on: Option<OnField<'_>>, record: bool) -> CurvedMeasure {
    let Some((lo, hi)) = mesh.bounds() else {
        return CurvedMeasure::default();
    };
    let centre = on
        .and_then(|on| on.field.reuse()?.centre())
        .unwrap_or(0.5 * (lo + hi));
    const CHUNK: usize = 3 * 256;
    let (pos, nrm) = (&mesh.positions, &mesh.normals);
    if nrm.len() != pos.len() {
        let (area, volume) = mesh.area_and_volume();
        return CurvedMeasure {
            area,
            volume,
            sharp: None,
        };
    }
    let partial: Vec<((f64, f64), Vec<SharpTriangle>)> = mesh
        .indices
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mid = |i: u32, j: u32| -> DVec3 {
                let (a, b) = if i < j { (i, j) } else { (j, i) };
                let (a, b) = (a as usize, b as usize);
                (lifted_midpoint(pos[a] - centre, pos[b] - centre, nrm[a], nrm[b])).as_dvec3()
            };
            let mut acc = (0.0f64, 0.0f64);
            let mut sharp_here = Vec::new();
            for t in chunk.chunks_exact(3) {
                let [ia, ib, ic] = [t[0], t[1], t[2]].map(|i| i as usize);
                let sharp = on.filter(|_| is_sharp(nrm[ia], nrm[ib], nrm[ic]));
                let corners = [pos[ia], pos[ib], pos[ic]];
                let measured = sharp.and_then(|on| {
                    on.field
                        .reuse()
                        .and_then(|r| r.sharp(corners))
                        .or_else(|| sharp_area_volume(on, corners, centre))
                });
                if let Some((a, v)) = measured {
                    acc.0 += a;
                    acc.1 += v;
                    if record {
                        sharp_here.push(SharpTriangle {
                            corners,
                            area: a,
                            volume: v,
                        });
                    }
                    continue;
                }
                let [a, b, c] = [ia, ib, ic].map(|i| (pos[i] - centre).as_dvec3());
                let (ab, bc, ca) = (mid(t[0], t[1]), mid(t[1], t[2]), mid(t[2], t[0]));
                let subs = [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]];
                let a1: f64 = subs.iter().map(|s| area(s[0], s[1], s[2])).sum();
                let v1: f64 = subs.iter().map(|s| volume(s[0], s[1], s[2])).sum();
                let (a0, v0) = (area(a, b, c), volume(a, b, c));
                acc.0 += a1 + (a1 - a0) / 3.0;
                acc.1 += v1 + (v1 - v0) / 3.0;
            }
            (acc, sharp_here)
        })
        .collect();
    let (area, volume) = partial
        .iter()
        .fold((0.0, 0.0), |(a, v), ((pa, pv), _)| (a + pa, v + pv));
    let sharp = record.then(|| SharpTriangles {
        centre,
        triangles: partial.into_iter().flat_map(|(_, t)| t).collect(),
    });
    CurvedMeasure {
        area,
        volume,
        sharp,
    }
}

/// True when the unit normals of a triangle's corners turn by more than 60° between two of
/// them (a crease or a feature smaller than the triangle).
pub fn is_sharp(na: Vec3, nb: Vec3, nc: Vec3) -> bool {
    na.dot(nb).min(nb.dot(nc)).min(nc.dot(na)) < SHARP_COS
}

/// Points of a triangle split [`SHARP_LEVEL`] times along each edge, by (steps towards `b`,
/// steps towards `c`), row after row: `(0, 0)` is `a`.
const SHARP_POINTS: usize = (SHARP_LEVEL + 1) * (SHARP_LEVEL + 2) / 2;

/// Index into the points of [`SHARP_POINTS`] of the point `i` steps towards `b` and `j` towards
/// `c` (`i + j <= SHARP_LEVEL`).
const fn sharp_point(i: usize, j: usize) -> usize {
    // Rows of constant i hold SHARP_LEVEL + 1 - i points.
    i * (2 * SHARP_LEVEL + 3 - i) / 2 + j
}

/// True for the point `(i, j)` of [`sharp_point`] (`i + j <= SHARP_LEVEL`) that is a corner of
/// the triangle.
const fn is_corner(i: usize, j: usize) -> bool {
    (i == 0 || i == SHARP_LEVEL) && (j == 0 || j == SHARP_LEVEL)
}

/// Area (Å²) and signed volume about `centre` (Å³) of the piece of the Gaussian sum's level
/// set over the triangle `abc` (Å, corners on it): the triangle is split into
/// [`SHARP_LEVEL`]² small ones whose corners (those not already the mesh's) are moved onto the
/// surface along the gradient
/// ([`AnalyticField::project_points`]), and Richardson extrapolation over that level and half
/// of it (`A = A4 + (A4 - A2) / 3`) removes the leading chord error, as for the curved
/// measure. `None` when a point does not reach the surface within the triangle's longest edge
/// (the caller measures that triangle the usual way).
pub fn sharp_area_volume(
    on: OnField<'_>,
    [a, b, c]: [Vec3; 3],
    centre: Vec3,
) -> Option<(f64, f64)> {
    // The corners are mesh vertices, already on the surface; the other points start on the
    // flat triangle and are moved onto it (in `inner`, in the order of `points`).
    let n = SHARP_LEVEL as f32;
    let mut points = [Vec3::ZERO; SHARP_POINTS];
    let mut inner = [Vec3::ZERO; SHARP_POINTS - 3];
    let mut k = 0;
    for i in 0..=SHARP_LEVEL {
        for j in 0..=SHARP_LEVEL - i {
            let p = a + (b - a) * (i as f32 / n) + (c - a) * (j as f32 / n);
            points[sharp_point(i, j)] = p;
            if !is_corner(i, j) {
                inner[k] = p;
                k += 1;
            }
        }
    }
    let mid = (a + b + c) / 3.0;
    let radius = [a, b, c]
        .map(|p| (p - mid).length())
        .into_iter()
        .fold(0.0, f32::max);
    let longest = [b - a, c - b, a - c]
        .map(|e| e.length())
        .into_iter()
        .fold(0.0, f32::max);
    if !on
        .field
        .project_points(&mut inner, mid, radius, on.iso, longest)
    {
        return None;
    }
    let mut moved = inner.iter();
    for i in 0..=SHARP_LEVEL {
        for j in 0..=SHARP_LEVEL - i {
            if !is_corner(i, j) {
                points[sharp_point(i, j)] = *moved.next()?;
            }
        }
    }
    let p = |i: usize, j: usize| (points[sharp_point(i, j)] - centre).as_dvec3();
    // Sums over the small triangles of a split with steps of `s` points (1: fine, 2: half).
    let level = |s: usize| {
        let (mut area_sum, mut volume_sum) = (0.0, 0.0);
        for i in (0..SHARP_LEVEL).step_by(s) {
            for j in (0..SHARP_LEVEL - i).step_by(s) {
                let (p0, pi, pj) = (p(i, j), p(i + s, j), p(i, j + s));
                area_sum += area(p0, pi, pj);
                volume_sum += volume(p0, pi, pj);
                if i + j + s < SHARP_LEVEL {
                    let pij = p(i + s, j + s);
                    area_sum += area(pi, pij, pj);
                    volume_sum += volume(pi, pij, pj);
                }
            }
        }
        (area_sum, volume_sum)
    };
    let (fine, half) = (level(1), level(2));
    Some((
        fine.0 + (fine.0 - half.0) / 3.0,
        fine.1 + (fine.1 - half.1) / 3.0,
    ))
}

fn area(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

fn volume(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c)) / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::GridSpec;
    use crate::surface::bin::PreparedAtom;

    #[test]
    fn sharp_points_are_numbered_once_each() {
        let mut seen = [false; SHARP_POINTS];
        for i in 0..=SHARP_LEVEL {
            for j in 0..=SHARP_LEVEL - i {
                assert!(!seen[sharp_point(i, j)], "({i}, {j}) numbered twice");
                seen[sharp_point(i, j)] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    /// One atom (alpha 1.5 Å, I = 0.5): its surface is a sphere of radius
    /// `alpha sqrt(2 ln 2)`. A triangle of three points on it, 70° apart as seen from the
    /// centre (normals 70° apart: sharp), measured on the sum gives the spherical triangle: area
    /// `r² E` and, about the centre, volume `r³ E / 3`, with `E` its spherical excess, within
    /// 0.4 % and 0.7 % (split 4 x 4 with Richardson over 2 x 2: -0.21 % and -0.47 % on a sphere).
    /// The curved correction alone, capped across such a turn, falls further short.
    #[test]
    fn a_sharp_triangle_on_one_atom_measures_the_spherical_triangle() {
        let alpha = 1.5f32;
        let k = 0.5 / (alpha * alpha);
        let atom = PreparedAtom {
            pos: [0.0; 3],
            k,
            cut: 4.0 * alpha,
            cut2: 16.0 * alpha * alpha,
            colour: [1.0; 3],
        };
        let grid = GridSpec {
            origin: Vec3::splat(-8.0),
            spacing: 1.0,
            dims: [17; 3],
        };
        let field = AnalyticField::new(&[atom], &grid);
        let rs = alpha * (2.0 * 2f32.ln()).sqrt();
        let (cos, sin) = (70f32.to_radians().cos(), 70f32.to_radians().sin());
        let y = cos * (1.0 - cos) / sin;
        let normals = [
            Vec3::X,
            Vec3::new(cos, sin, 0.0),
            Vec3::new(cos, y, (1.0 - cos * cos - y * y).sqrt()),
        ];
        let [a, b, c] = normals.map(|n| n.as_dvec3());
        assert!(is_sharp(normals[0], normals[1], normals[2]));
        let excess =
            2.0 * (a.dot(b.cross(c)).abs() / (1.0 + a.dot(b) + b.dot(c) + c.dot(a))).atan();
        let r = rs as f64;
        let (exact_area, exact_volume) = (r * r * excess, r * r * r * excess / 3.0);
        let corners = normals.map(|n| n * rs);
        let on = OnField {
            field: &field,
            iso: 0.5,
        };
        let (area, volume) = sharp_area_volume(on, corners, Vec3::ZERO).expect("on the sphere");
        assert!(
            (area / exact_area - 1.0).abs() < 0.004,
            "area {area} vs {exact_area}"
        );
        assert!(
            (volume / exact_volume - 1.0).abs() < 0.007,
            "volume {volume} vs {exact_volume}"
        );
        let mesh = Mesh {
            positions: corners.to_vec(),
            normals: normals.to_vec(),
            indices: vec![0, 1, 2],
            ..Mesh::default()
        };
        let lifted = curved_area_volume(&mesh, None).0;
        assert!(
            (lifted / exact_area - 1.0).abs() > 2.0 * (area / exact_area - 1.0).abs(),
            "lifted {lifted} vs {exact_area}, on the sum {area}"
        );
    }
}
