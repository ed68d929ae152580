//! The vertex Marching Cubes places on one crossed grid edge: position, normal and colour, all
//! linearly interpolated along the edge (DESIGN section 2). Used by [`super::marching_cubes`];
//! public so the GPU parity tests can compute single vertices.

use glam::Vec3;

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
/// - normal: `-(g_a + t (g_b - g_a))` normalised, where `g` is the central-difference gradient
///   (one-sided on the grid boundary) in Å⁻¹; if that vanishes, the edge direction pointing from
///   the inside sample to the outside one;
/// - colour: `c_a + t (c_b - c_a)` from the colour volume, else white.
pub fn edge_vertex(
    grid: &GridSpec,
    density: &DensityVolume,
    iso: f32,
    a: [usize; 3],
    axis: usize,
) -> EdgeVertex {
    let mut b = a;
    b[axis] += 1;
    let v = &density.values;
    let ia = index(grid, a);
    let ib = index(grid, b);
    let (va, vb) = (v[ia], v[ib]);
    let denom = vb - va;
    let t = if denom != 0.0 {
        ((iso - va) / denom).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let pa = point(grid, a);
    let pb = point(grid, b);
    let position = pa + t * (pb - pa);
    let ga = gradient(grid, v, a);
    let gb = gradient(grid, v, b);
    let g = -(ga + t * (gb - ga));
    let normal = if g.length_squared() > 0.0 && g.is_finite() {
        g.normalize()
    } else {
        let mut d = Vec3::ZERO;
        d[axis] = if va >= iso { 1.0 } else { -1.0 };
        d
    };
    let colour = match &density.colours {
        Some(c) => {
            let (ca, cb) = (c[ia], c[ib]);
            [0, 1, 2].map(|n| ca[n] + t * (cb[n] - ca[n]))
        }
        None => [1.0; 3],
    };
    EdgeVertex {
        position,
        normal,
        colour,
    }
}

fn index(grid: &GridSpec, p: [usize; 3]) -> usize {
    let [nx, ny, _] = grid.dims.map(|d| d as usize);
    p[0] + nx * (p[1] + ny * p[2])
}

fn point(grid: &GridSpec, p: [usize; 3]) -> Vec3 {
    grid.point(p[0] as u32, p[1] as u32, p[2] as u32)
}

/// Central-difference gradient of `values` at sample `p` in Å⁻¹ (one-sided on the boundary).
pub fn gradient(grid: &GridSpec, values: &[f32], p: [usize; 3]) -> Vec3 {
    let dims = grid.dims.map(|d| d as usize);
    if (0..3).all(|a| p[a] >= 1 && p[a] + 1 < dims[a]) {
        // Interior: plain central differences with strides 1, nx, nx * ny.
        let i = index(grid, p);
        let (sy, sz) = (dims[0], dims[0] * dims[1]);
        let d = |s: usize| (values[i + s] - values[i - s]) / (2.0 * grid.spacing);
        return Vec3::new(d(1), d(sy), d(sz));
    }
    let mut g = Vec3::ZERO;
    for axis in 0..3 {
        let (mut lo, mut hi) = (p, p);
        lo[axis] = p[axis].saturating_sub(1);
        hi[axis] = (p[axis] + 1).min(dims[axis] - 1);
        let steps = (hi[axis] - lo[axis]) as f32;
        if steps > 0.0 {
            g[axis] = (values[index(grid, hi)] - values[index(grid, lo)]) / (steps * grid.spacing);
        }
    }
    g
}
