// The exact Gaussian sum at any point, over the binned atoms: shared by refine.wgsl (refined
// vertices) and measure.wgsl (sharp triangles measured on the surface), which src/gpu/shaders.rs
// prepends it to. Twin of crate::surface::analytic::AnalyticField::{eval, project}. Each shader
// that includes it binds `sorted_atoms` (position, alpha; sorted by cell) and `cell_end` (the
// binning's inclusive cell ends) and defines `field_cells()`, where the atoms are binned.

// Twins of crate::surface::analytic::{REFINE_REACH, REFINE_STEP}. REFINE_REACH is quality max's
// cutoff, which every refined frame runs at, grid included (crate::surface::VertexMode::effective,
// issue 33): so the sum here is the one density.wgsl samples, with the same cutoff test.
const REFINE_REACH: f32 = 4.0;
// Å.
const REFINE_STEP: f32 = 1e-4;

// The binning's cell grid: first cell's corner (Å), cell edge (Å), cells per axis, and how far
// (Å) the farthest-reaching atom counts from its centre.
struct FieldCells {
    origin: vec3<f32>,
    size: f32,
    dims: vec3<u32>,
    reach: f32,
}

fn field_cell(x: f32, o: f32, size: f32, n: u32) -> u32 {
    return u32(clamp(i32(floor((x - o) / size)), 0, i32(n) - 1));
}

// (grad rho (Å⁻¹), rho) at p (Å): the sum over the atoms with |p - p_i| < REFINE_REACH alpha_i
// of exp(-|p - p_i|² / (2 alpha_i²)) and its gradient. The cutoff test is density.wgsl's (d²
// summed x, y, z in that order against (q alpha)², q = u.cutoff = REFINE_REACH there), so at a
// grid point an atom counts here exactly when it counts in the sample.
fn field_eval(p: vec3<f32>) -> vec4<f32> {
    let fc = field_cells();
    let reach = fc.reach;
    let cx0 = field_cell(p.x - reach, fc.origin.x, fc.size, fc.dims.x);
    let cx1 = field_cell(p.x + reach, fc.origin.x, fc.size, fc.dims.x);
    let cy0 = field_cell(p.y - reach, fc.origin.y, fc.size, fc.dims.y);
    let cy1 = field_cell(p.y + reach, fc.origin.y, fc.size, fc.dims.y);
    let cz0 = field_cell(p.z - reach, fc.origin.z, fc.size, fc.dims.z);
    let cz1 = field_cell(p.z + reach, fc.origin.z, fc.size, fc.dims.z);
    var rho = 0.0;
    var g = vec3<f32>(0.0);
    for (var cz = cz0; cz <= cz1; cz++) {
        for (var cy = cy0; cy <= cy1; cy++) {
            let row = fc.dims.x * (cy + fc.dims.y * cz);
            let c0 = row + cx0;
            var first = 0u;
            if (c0 > 0u) {
                first = cell_end[c0 - 1u];
            }
            let last = cell_end[row + cx1];
            for (var s = first; s < last; s++) {
                let a = sorted_atoms[s];
                let d = p - a.xyz;
                let d2 = (d.x * d.x + d.y * d.y) + d.z * d.z;
                let r = REFINE_REACH * a.w;
                if (d2 < r * r) {
                    let k = 0.5 / (a.w * a.w);
                    let w = exp(-k * d2);
                    rho += w;
                    g -= (2.0 * k * w) * d;
                }
            }
        }
    }
    return vec4<f32>(g, rho);
}

struct Projected {
    ok: bool,
    pos: vec3<f32>,
    grad: vec3<f32>,
}

// p (Å) moved onto rho = iso by Newton steps along the gradient (at most `iterations`, done when
// a step is shorter than `tolerance` Å), with the gradient there; not ok when that does not
// converge within max_dist Å of p.
fn field_project(
    p: vec3<f32>,
    iso: f32,
    max_dist: f32,
    iterations: u32,
    tolerance: f32,
) -> Projected {
    var x = p;
    for (var it = 0u; it < iterations; it++) {
        let e = field_eval(x);
        let g2 = dot(e.xyz, e.xyz);
        if (!(g2 > 0.0)) {
            break;
        }
        let step = ((e.w - iso) / g2) * e.xyz;
        x -= step;
        if (length(x - p) > max_dist) {
            break;
        }
        if (length(step) < tolerance) {
            return Projected(true, x, e.xyz);
        }
    }
    return Projected(false, p, vec3<f32>(0.0));
}
