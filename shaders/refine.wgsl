// Refined vertices (issue 13): after a slab's emission, one thread per active cell moves the
// vertices on the cell point's own crossed edges (the ones emit.wgsl wrote) onto the level set
// of the exact Gaussian sum and sets their normals to its normalised -gradient. Twin of
// crate::surface::analytic::AnalyticField::refine_edge: the same safeguarded Newton on the edge
// from the linear estimate (the bracket halved where a step leaves it or is more than half the
// step before), the same fallback projection along the gradient when that does not converge,
// the same constants. Atoms count out to REFINE_REACH alpha, the cutoff the grid was sampled
// with (refined frames run at quality max, issue 33), found through the binning's cells.
// Colours are left as emitted (the linear parameter, as on the CPU), and so is the normal where
// the gradient vanishes. Rust side: src/gpu/mc.rs (Refine).

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl, and
// field_eval and field_project from field.wgsl, both prepended by src/gpu/shaders.rs.
// So are the counter words (C_*: counters.wgsl) and the brick constants (brick_const.wgsl).

// Twins of crate::surface::analytic::{REFINE_ITERATIONS, PROJECT_ITERATIONS} (REFINE_REACH and
// REFINE_STEP are in field.wgsl).
const REFINE_ITERATIONS: u32 = 16u;
const PROJECT_ITERATIONS: u32 = 4u;

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


// Where the binning put the atoms, for field_eval (shaders/field.wgsl): the largest alpha is
// max_cut / cutoff, with a little slack as in density.wgsl.
fn field_cells() -> FieldCells {
    let reach = REFINE_REACH * u.max_cut / u.cutoff * 1.0001 + 1e-4;
    return FieldCells(u.cell_origin, u.cell_size, u.cell_dims, reach);
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
    let lo_inside = va >= iso;
    var g = vec3<f32>(0.0);
    var last_step = 1.0;
    var found = false;
    for (var it = 0u; it < REFINE_ITERATIONS; it++) {
        let e = field_eval(pa + t * dir);
        g = e.xyz;
        let f = e.w - iso;
        if (f == 0.0) {
            found = true;
            break;
        }
        if ((f >= 0.0) == lo_inside) {
            lo = t;
        } else {
            hi = t;
        }
        let df = dot(g, dir);
        var newton = -1.0;
        if (df != 0.0) {
            newton = t - f / df;
        }
        let step = abs(newton - t);
        if (df != 0.0 && newton >= lo && newton <= hi && step <= 0.5 * last_step) {
            t = newton;
            last_step = step;
            if (step * len < REFINE_STEP) {
                found = true;
                break;
            }
        } else {
            t = 0.5 * (lo + hi);
            last_step = 0.5 * (hi - lo);
            if ((hi - lo) * len < REFINE_STEP) {
                found = true;
                break;
            }
        }
    }
    var pos = pa + t * dir;
    if (!found) {
        let q = field_project(pos, iso, 0.5 * len, PROJECT_ITERATIONS, REFINE_STEP);
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

// Three threads per active cell, one per own edge (x, y, z), so that a cell's vertices are
// refined side by side rather than one after the other: the dispatch is the emission's (64
// cells per workgroup, arguments from measure.wgsl's slab_begin), each workgroup 3 x 64 threads.
@compute @workgroup_size(192)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let a = (wg.x + wg.y * nwg.x) * 64u + lid / 3u;
    let axis = lid % 3u;
    if (a >= counters[C_SCAN_ACTIVE]) {
        return;
    }
    let p = class_point(active_cells[a].x);
    let e = class_entry(p);
    let edges = (classes[e] >> 8u) & 7u;
    if ((edges & (1u << axis)) == 0u) {
        return;
    }
    // The vertices of a cell's crossed edges follow in x, y, z order from its base.
    let id = vertex_base[e] + countOneBits(edges & ((1u << axis) - 1u));
    if (id < counters[C_VERTEX_CAPACITY]) {
        refine_vertex(id, p, axis);
    }
}
