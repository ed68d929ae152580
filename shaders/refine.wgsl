// Refined vertices (issue 13): after a slab's emission, one thread per active cell moves the
// vertices on the cell point's own crossed edges (the ones emit.wgsl wrote) onto the level set
// of the exact Gaussian sum and sets their normals to its normalised -gradient. Twin of
// crate::surface::analytic::AnalyticField::refine_edge: the same safeguarded Newton / regula
// falsi on the edge from the linear estimate, bracketed by the slab's samples, the same
// fallback projection along the gradient when the sum has no root on the edge, the same
// constants. Atoms count out to REFINE_REACH alpha (beyond the quality's cutoff), found through
// the binning's cells. Colours are left as emitted (the linear parameter, as on the CPU), and
// so is the normal where the gradient vanishes. Rust side: src/gpu/mc.rs (Refine).

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.

// Word indices into the counters (twin of crate::gpu::types::GpuCounters).
const C_SCAN_ACTIVE: u32 = 6u;
const C_VERTEX_CAPACITY: u32 = 11u;

// Twins of crate::surface::analytic::{REFINE_REACH, REFINE_ITERATIONS, REFINE_STEP}.
const REFINE_REACH: f32 = 4.0;
const REFINE_ITERATIONS: u32 = 8u;
// Å.
const REFINE_STEP: f32 = 1e-4;

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::refine`). Eight storage
// buffers (the device minimum): the cell starts are read as the previous cell's end.
@group(0) @binding(0) var<uniform> u: SlabUniform;
// Density words (f32 bits): see dens_at.
@group(0) @binding(1) var<storage, read> density: array<u32>;
@group(0) @binding(2) var<storage, read> classes: array<u32>;
@group(0) @binding(3) var<storage, read> vertex_base: array<u32>;
@group(0) @binding(4) var<storage, read> active_cells: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read> sorted_atoms: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> cell_end: array<u32>;
@group(0) @binding(7) var<storage, read> counters: array<u32>;
@group(0) @binding(8) var<storage, read_write> vertices: array<f32>;

fn dens(p: vec3<u32>) -> f32 {
    return dens_at(p.x, p.y, p.z);
}


fn cell_coord(x: f32, o: f32, n: u32) -> u32 {
    return u32(clamp(i32(floor((x - o) / u.cell_size)), 0, i32(n) - 1));
}

// (grad rho (Å⁻¹), rho) at p (Å): the sum over the atoms with |p - p_i| < REFINE_REACH alpha_i
// of exp(-|p - p_i|² / (2 alpha_i²)) and its gradient (sorted_atoms: position, alpha).
fn eval(p: vec3<f32>) -> vec4<f32> {
    // The largest alpha is max_cut / cutoff; a little slack as in density.wgsl.
    let reach = REFINE_REACH * u.max_cut / u.cutoff * 1.0001 + 1e-4;
    let cx0 = cell_coord(p.x - reach, u.cell_origin.x, u.cell_dims.x);
    let cx1 = cell_coord(p.x + reach, u.cell_origin.x, u.cell_dims.x);
    let cy0 = cell_coord(p.y - reach, u.cell_origin.y, u.cell_dims.y);
    let cy1 = cell_coord(p.y + reach, u.cell_origin.y, u.cell_dims.y);
    let cz0 = cell_coord(p.z - reach, u.cell_origin.z, u.cell_dims.z);
    let cz1 = cell_coord(p.z + reach, u.cell_origin.z, u.cell_dims.z);
    var rho = 0.0;
    var g = vec3<f32>(0.0);
    for (var cz = cz0; cz <= cz1; cz++) {
        for (var cy = cy0; cy <= cy1; cy++) {
            let row = u.cell_dims.x * (cy + u.cell_dims.y * cz);
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

// p (Å) moved onto rho = iso by Newton steps along the gradient (at most four), with the
// gradient there; not ok when that does not converge within max_dist Å of p.
fn project(p: vec3<f32>, iso: f32, max_dist: f32) -> Projected {
    var x = p;
    for (var it = 0u; it < 4u; it++) {
        let e = eval(x);
        let g2 = dot(e.xyz, e.xyz);
        if (!(g2 > 0.0)) {
            break;
        }
        let step = ((e.w - iso) / g2) * e.xyz;
        x -= step;
        if (length(x - p) > max_dist) {
            break;
        }
        if (length(step) < REFINE_STEP) {
            return Projected(true, x, e.xyz);
        }
    }
    return Projected(false, p, vec3<f32>(0.0));
}

fn refine_vertex(id: u32, p0: vec3<u32>, axis: u32) {
    var p1 = p0;
    p1[axis] = p0[axis] + 1u;
    let iso = u.isovalue;
    let va = dens(p0);
    let vb = dens(p1);
    let pa = u.origin + u.spacing * vec3<f32>(p0);
    let pb = u.origin + u.spacing * vec3<f32>(p1);
    let dir = pb - pa;
    let len = length(dir);
    var t = 0.5;
    if (vb != va) {
        t = clamp((iso - va) / (vb - va), 0.0, 1.0);
    }
    var lo = 0.0;
    var hi = 1.0;
    var flo = va - iso;
    var fhi = vb - iso;
    let lo_inside = flo >= 0.0;
    var g = vec3<f32>(0.0);
    var f_last = 0.0;
    for (var it = 0u; it < REFINE_ITERATIONS; it++) {
        let e = eval(pa + t * dir);
        g = e.xyz;
        let f = e.w - iso;
        f_last = f;
        if (f == 0.0) {
            break;
        }
        if ((f >= 0.0) == lo_inside) {
            lo = t;
            flo = f;
        } else {
            hi = t;
            fhi = f;
        }
        let df = dot(g, dir);
        var newton = -1.0;
        if (df != 0.0) {
            newton = t - f / df;
        }
        if (df != 0.0 && newton >= lo && newton <= hi) {
            let done = abs(newton - t) * len < REFINE_STEP;
            t = newton;
            if (done) {
                break;
            }
        } else {
            if (flo != fhi) {
                t = clamp(lo - flo * (hi - lo) / (fhi - flo), lo, hi);
            } else {
                t = 0.5 * (lo + hi);
            }
            if ((hi - lo) * len < REFINE_STEP) {
                break;
            }
        }
    }
    var pos = pa + t * dir;
    let found = abs(f_last) * len <= 0.1 * REFINE_STEP * length(g) * len + 1e-4;
    if (!found) {
        let q = project(pos, iso, 0.5 * len);
        if (q.ok) {
            pos = q.pos;
            g = q.grad;
        }
    }
    let o = 9u * id;
    vertices[o] = pos.x;
    vertices[o + 1u] = pos.y;
    vertices[o + 2u] = pos.z;
    let n = -g;
    let l = length(n);
    if (l > 0.0 && l < 1e30) {
        vertices[o + 3u] = n.x / l;
        vertices[o + 4u] = n.y / l;
        vertices[o + 5u] = n.z / l;
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let a = gid.x + gid.y * nwg.x * 64u;
    if (a >= counters[C_SCAN_ACTIVE]) {
        return;
    }
    let p = class_point(active_cells[a].x);
    let e = class_entry(p);
    let edges = (classes[e] >> 8u) & 7u;
    let vcap = counters[C_VERTEX_CAPACITY];
    var id = vertex_base[e];
    for (var axis = 0u; axis < 3u; axis++) {
        if ((edges & (1u << axis)) != 0u) {
            if (id < vcap) {
                refine_vertex(id, p, axis);
            }
            id++;
        }
    }
}
