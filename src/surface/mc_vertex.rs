//! The vertex Marching Cubes places on one crossed grid edge: position, normal and colour, all
//! linearly interpolated along the edge (DESIGN section 2). Used by [`super::marching_cubes`];
//! public so the GPU parity tests can compute single vertices.

use glam::Vec3;

use super::analytic::AnalyticField;
use super::{DensityVolume, GridSpec};

/// One mesh vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeVertex {
    /// Position in Å.
    pub position: Vec3,
    /// Unit outward normal (normalised `-grad rho`).
    pub normal: Vec3,
    /// Linear RGB colour (white without a colour volume).
    pub colour: [f32; 3],
}

/// The vertex on the edge from sample `a = (i, j, k)` to `a + e_axis` (`axis` 0 = x, 1 = y,
/// 2 = z), which the isovalue `iso` must cross (`rho(a) >= iso` differs from `rho(b) >= iso`).
///
/// - `t = (iso - rho(a)) / (rho(b) - rho(a))`, position `p_a + t (p_b - p_a)` (Å);
/// - normal: [`interpolated_normal`] of the central-difference gradients (one-sided on the
///   grid boundary);
/// - colour: `c_a + t (c_b - c_a)` from the colour volume, else white.
///
/// With `field`, the position and normal are refined on the exact Gaussian sum (see
/// [`edge_geometry_refined`]); the colour keeps the linear parameter `t`.
pub fn edge_vertex_refined(
    grid: &GridSpec,
    density: &DensityVolume,
    iso: f32,
    a: [usize; 3],
    axis: usize,
    field: Option<&AnalyticField>,
) -> EdgeVertex {
    let v = &density.values;
    let (position, normal, t) =
        edge_geometry_refined(grid, |p| v[index(grid, p)], iso, a, axis, field);
    let colour = match &density.colours {
        Some(c) => {
            let mut b = a;
            b[axis] += 1;
            let (ca, cb) = (c[index(grid, a)], c[index(grid, b)]);
            lerp_colour(ca, cb, t)
        }
        None => [1.0; 3],
    };
    EdgeVertex {
        position,
        normal,
        colour,
    }
}

/// The colour of a vertex at parameter `t` on the edge from a sample of colour `ca` to one of
/// colour `cb` (the formula [`edge_vertex_refined`] uses).
pub fn lerp_colour(ca: [f32; 3], cb: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|n| ca[n] + t * (cb[n] - ca[n]))
}

/// Interpolation parameter `t` in 0..=1 of the crossing of `iso` between sample values `va`
/// and `vb` (0.5 when they are equal).
pub fn edge_t(va: f32, vb: f32, iso: f32) -> f32 {
    let denom = vb - va;
    if denom != 0.0 {
        ((iso - va) / denom).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// Position (Å), unit normal and interpolation parameter `t` of the vertex on the edge from
/// sample `a` to `a + e_axis`, reading densities through `value(sample)`. [`edge_vertex_refined`] on
/// a dense volume and the sparse engine ([`super::brick_mc`]) share it, so both give the same
/// bits from the same sample values.
#[inline]
pub fn edge_geometry(
    grid: &GridSpec,
    value: impl Fn([usize; 3]) -> f32,
    iso: f32,
    a: [usize; 3],
    axis: usize,
) -> (Vec3, Vec3, f32) {
    let mut b = a;
    b[axis] += 1;
    let (va, vb) = (value(a), value(b));
    let (position, t) = edge_position(grid, va, vb, iso, a, axis);
    let (ga, gb) = (
        gradient_with(grid, &value, a),
        gradient_with(grid, &value, b),
    );
    let normal = interpolated_normal(ga, gb, t, axis, va >= iso);
    (position, normal, t)
}

/// The normal of the vertex at parameter `t` on an edge along `axis` whose end samples have
/// density gradients `ga` and `gb` (Å⁻¹): each end's unit normal `n = -g / |g|`, interpolated
/// as `n_a + t (n_b - n_a)` and normalised (DESIGN section 2; `shaders/emit.wgsl` does the
/// same). Where that vanishes, the edge direction pointing from the inside end to the outside
/// one (`a_inside`: the first end has `rho >= I`).
#[inline]
pub fn interpolated_normal(ga: Vec3, gb: Vec3, t: f32, axis: usize, a_inside: bool) -> Vec3 {
    let (na, nb) = ((-ga).normalize_or_zero(), (-gb).normalize_or_zero());
    let n = na + t * (nb - na);
    if n.length_squared() > 0.0 && n.is_finite() {
        n.normalize()
    } else {
        let mut d = Vec3::ZERO;
        d[axis] = if a_inside { 1.0 } else { -1.0 };
        d
    }
}

/// Position (Å) and interpolation parameter `t` of the vertex on the edge from sample `a`
/// (density `va`) to `a + e_axis` (density `vb`): the position [`edge_geometry`] gives, without
/// its normal. Surfaces that are only measured need no more.
#[inline]
pub fn edge_position(
    grid: &GridSpec,
    va: f32,
    vb: f32,
    iso: f32,
    a: [usize; 3],
    axis: usize,
) -> (Vec3, f32) {
    let mut b = a;
    b[axis] += 1;
    let t = edge_t(va, vb, iso);
    let pa = point(grid, a);
    let pb = point(grid, b);
    (pa + t * (pb - pa), t)
}

/// [`edge_geometry`], or with `field` the refined vertex: the position where the exact Gaussian
/// sum crosses `iso` on the edge ([`AnalyticField::refine_edge`], started from the linear
/// estimate) and the normal `-grad rho` normalised there (the interpolated normal if the
/// gradient vanishes). The returned `t` is always the linear one (colours use it).
#[inline]
pub fn edge_geometry_refined(
    grid: &GridSpec,
    value: impl Fn([usize; 3]) -> f32,
    iso: f32,
    a: [usize; 3],
    axis: usize,
    field: Option<&AnalyticField>,
) -> (Vec3, Vec3, f32) {
    let Some(field) = field else {
        return edge_geometry(grid, value, iso, a, axis);
    };
    let mut b = a;
    b[axis] += 1;
    let (va, vb) = (value(a), value(b));
    let t = edge_t(va, vb, iso);
    let (pa, pb) = (point(grid, a), point(grid, b));
    let reused = field
        .reuse()
        .and_then(|r| r.vertex(index(grid, a), axis, pa, pb));
    if let Some((position, normal)) = reused {
        return (position, normal, t);
    }
    let (position, normal) = field.refine_edge(pa, pb, va, iso, t);
    match normal {
        Some(normal) => (position, normal, t),
        None => {
            let (_, normal, _) = edge_geometry(grid, value, iso, a, axis);
            (position, normal, t)
        }
    }
}

fn index(grid: &GridSpec, p: [usize; 3]) -> usize {
    let [nx, ny, _] = grid.dims.map(|d| d as usize);
    p[0] + nx * (p[1] + ny * p[2])
}

fn point(grid: &GridSpec, p: [usize; 3]) -> Vec3 {
    grid.point(p[0] as u32, p[1] as u32, p[2] as u32)
}

/// Central-difference gradient in Å⁻¹ of the density at sample `p` (one-sided on the grid
/// boundary), reading the density through `value(sample)`.
#[inline]
pub fn gradient_with(grid: &GridSpec, value: impl Fn([usize; 3]) -> f32, p: [usize; 3]) -> Vec3 {
    let dims = grid.dims.map(|d| d as usize);
    if (0..3).all(|a| p[a] >= 1 && p[a] + 1 < dims[a]) {
        // Interior: plain central differences along x, y and z.
        #[inline(always)]
        fn d(
            grid: &GridSpec,
            value: &impl Fn([usize; 3]) -> f32,
            p: [usize; 3],
            axis: usize,
        ) -> f32 {
            let (mut lo, mut hi) = (p, p);
            lo[axis] -= 1;
            hi[axis] += 1;
            (value(hi) - value(lo)) / (2.0 * grid.spacing)
        }
        return Vec3::new(
            d(grid, &value, p, 0),
            d(grid, &value, p, 1),
            d(grid, &value, p, 2),
        );
    }
    let mut g = Vec3::ZERO;
    for axis in 0..3 {
        let (mut lo, mut hi) = (p, p);
        lo[axis] = p[axis].saturating_sub(1);
        hi[axis] = (p[axis] + 1).min(dims[axis] - 1);
        let steps = (hi[axis] - lo[axis]) as f32;
        if steps > 0.0 {
            g[axis] = (value(hi) - value(lo)) / (steps * grid.spacing);
        }
    }
    g
}
