// Area and volume of the finished mesh by a two-level deterministic reduction (fixed number of
// workgroups, fixed order; field_eval and field_project come from field.wgsl, prepended by
// src/gpu/shaders.rs), plus the bookkeeping kernels that run between slabs and at the end of
// a frame: emit dispatch arguments, slab bases, counts, overflow bits and the indirect draw
// arguments for the renderer. Rust side: src/gpu/measure.rs.
// The counter words and overflow bits (C_*, OVERFLOW_*) come from counters.wgsl, prepended too.

// Twin of crate::gpu::types::MeasureUniform (64 bytes).
struct MeasureUniform {
    centre: vec3<f32>,
    max_groups_x: u32,
    // The binning's cells (for field_eval with refined vertices).
    cell_origin: vec3<f32>,
    cell_size: f32,
    cell_dims: vec3<u32>,
    // Å: how far the farthest-reaching atom counts.
    reach: f32,
    isovalue: f32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

const PARTIAL_GROUPS: u32 = 256u;

// True with refined vertices (issue 13): area and volume with the curvature correction of
// crate::surface::curved (each triangle split in four at its edge midpoints lifted onto the
// surface from the end points' normals, then Richardson over the two levels).
override CURVED: bool = false;
// Twin of crate::surface::curved::MAX_LIFT (in units of the edge length).
const MAX_LIFT: f32 = 0.5;
// Twins of crate::surface::curved::{SHARP_COS, SHARP_LEVEL} and
// crate::surface::analytic::{PROJECT_POINTS_ITERATIONS, PROJECT_POINTS_STEP}.
const SHARP_COS: f32 = 0.5;
const SHARP_LEVEL: u32 = 4u;
const PROJECT_POINTS_ITERATIONS: u32 = 8u;
// Å.
const PROJECT_POINTS_STEP: f32 = 1e-3;

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::measure`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> mu: MeasureUniform;
@group(0) @binding(1) var<storage, read_write> counters: array<u32>;
@group(0) @binding(2) var<storage, read> vertices: array<f32>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
@group(0) @binding(4) var<storage, read_write> partials: array<vec2<f32>>;
// Emit dispatch (x, y, z) and draw-indexed-indirect arguments (index_count, instance_count,
// first_index, base_vertex, first_instance).
@group(0) @binding(5) var<storage, read_write> dispatch_args: array<u32>;
@group(0) @binding(6) var<storage, read_write> draw_args: array<u32>;
// The binned atoms (position, alpha) and the binning's inclusive cell ends, for field_eval.
@group(0) @binding(7) var<storage, read> sorted_atoms: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> cell_end: array<u32>;

fn field_cells() -> FieldCells {
    return FieldCells(mu.cell_origin, mu.cell_size, mu.cell_dims, mu.reach);
}

var<workgroup> sh: array<vec2<f32>, 256>;

fn vertex(i: u32) -> vec3<f32> {
    let o = 9u * i;
    return vec3<f32>(vertices[o], vertices[o + 1u], vertices[o + 2u]) - mu.centre;
}

fn vertex_normal(i: u32) -> vec3<f32> {
    let o = 9u * i + 3u;
    return vec3<f32>(vertices[o], vertices[o + 1u], vertices[o + 2u]);
}

// Twin of crate::surface::curved::lifted_midpoint, on the edge i -> j taken in index order (so
// both triangles of an edge get the same point).
fn lifted_midpoint(i: u32, j: u32) -> vec3<f32> {
    let a = min(i, j);
    let b = max(i, j);
    let p = vertex(a);
    let q = vertex(b);
    let np = vertex_normal(a);
    let nq = vertex_normal(b);
    let d = q - p;
    let c2 = sqrt(max(0.5 * (1.0 + dot(np, nq)), 0.0));
    let s = dot(nq - np, d) / 8.0 / max(0.5 * (1.0 + c2), 0.5);
    let cap = MAX_LIFT * length(d);
    let n = np + nq;
    let nl = length(n);
    let m = 0.5 * (p + q);
    if (nl > 0.0 && abs(s) < 1e30) {
        return m + clamp(s, -cap, cap) * (n / nl);
    }
    return m;
}

fn tri_area(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return 0.5 * length(cross(b - a, c - a));
}

fn tri_volume(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return dot(a, cross(b, c)) / 6.0;
}

// Index of the point i steps towards b and j towards c of a sharp triangle split SHARP_LEVEL
// times per edge (twin of crate::surface::curved::sharp_point).
fn sharp_point(i: u32, j: u32) -> u32 {
    return i * (2u * SHARP_LEVEL + 3u - i) / 2u + j;
}

// Twin of crate::surface::curved::sharp_area_volume: area and volume of the level set over the
// triangle abc (relative to the centre), its points split SHARP_LEVEL times per edge and the
// ones that are not corners moved onto the surface, Richardson over that level and half of it;
// z is 0 when a point did not reach the surface (the caller measures the triangle the usual
// way).
fn sharp_measure(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    var pts: array<vec3<f32>, 15>;
    let n = f32(SHARP_LEVEL);
    let longest = max(max(length(b - a), length(c - b)), length(a - c));
    for (var i = 0u; i <= SHARP_LEVEL; i++) {
        for (var j = 0u; j <= SHARP_LEVEL - i; j++) {
            let p = a + (b - a) * (f32(i) / n) + (c - a) * (f32(j) / n);
            // The corners are mesh vertices, already on the surface.
            let corner = (i == 0u || i == SHARP_LEVEL) && (j == 0u || j == SHARP_LEVEL);
            if (corner) {
                pts[sharp_point(i, j)] = p;
                continue;
            }
            let q = field_project(
                p + mu.centre,
                mu.isovalue,
                longest,
                PROJECT_POINTS_ITERATIONS,
                PROJECT_POINTS_STEP,
            );
            if (!q.ok) {
                return vec3<f32>(0.0);
            }
            pts[sharp_point(i, j)] = q.pos - mu.centre;
        }
    }
    var sums: array<vec2<f32>, 2>;
    for (var level = 0u; level < 2u; level++) {
        let s = level + 1u;
        var acc = vec2<f32>(0.0);
        for (var i = 0u; i < SHARP_LEVEL; i += s) {
            for (var j = 0u; j < SHARP_LEVEL - i; j += s) {
                let p0 = pts[sharp_point(i, j)];
                let pi = pts[sharp_point(i + s, j)];
                let pj = pts[sharp_point(i, j + s)];
                acc += vec2<f32>(tri_area(p0, pi, pj), tri_volume(p0, pi, pj));
                if (i + j + s < SHARP_LEVEL) {
                    let pij = pts[sharp_point(i + s, j + s)];
                    acc += vec2<f32>(tri_area(pi, pij, pj), tri_volume(pi, pij, pj));
                }
            }
        }
        sums[level] = acc;
    }
    let m = sums[0] + (sums[0] - sums[1]) / 3.0;
    return vec3<f32>(m, 1.0);
}

// Area and volume of triangle (i0, i1, i2), flat or curvature-corrected.
fn measure_triangle(i0: u32, i1: u32, i2: u32) -> vec2<f32> {
    let a = vertex(i0);
    let b = vertex(i1);
    let c = vertex(i2);
    let flat = vec2<f32>(tri_area(a, b, c), tri_volume(a, b, c));
    if (!CURVED) {
        return flat;
    }
    let n0 = vertex_normal(i0);
    let n1 = vertex_normal(i1);
    let n2 = vertex_normal(i2);
    if (min(min(dot(n0, n1), dot(n1, n2)), dot(n2, n0)) < SHARP_COS) {
        let sharp = sharp_measure(a, b, c);
        if (sharp.z != 0.0) {
            return sharp.xy;
        }
    }
    let ab = lifted_midpoint(i0, i1);
    let bc = lifted_midpoint(i1, i2);
    let ca = lifted_midpoint(i2, i0);
    let a1 = tri_area(a, ab, ca) + tri_area(ab, b, bc) + tri_area(ca, bc, c) + tri_area(ab, bc, ca);
    let v1 = tri_volume(a, ab, ca) + tri_volume(ab, b, bc) + tri_volume(ca, bc, c)
        + tri_volume(ab, bc, ca);
    let fine = vec2<f32>(a1, v1);
    return fine + (fine - flat) / 3.0;
}

fn tree_sum(lid: u32) {
    workgroupBarrier();
    for (var off = 128u; off > 0u; off >>= 1u) {
        if (lid < off) {
            sh[lid] += sh[lid + off];
        }
        workgroupBarrier();
    }
}

@compute @workgroup_size(256)
fn partial_sums(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let ntri = min(counters[C_TRIANGLE_COUNT], counters[C_TRIANGLE_CAPACITY]);
    let nvert = min(counters[C_VERTEX_COUNT], counters[C_VERTEX_CAPACITY]);
    var acc = vec2<f32>(0.0);
    for (var t = wg.x * 256u + lid; t < ntri; t += PARTIAL_GROUPS * 256u) {
        let i0 = indices[3u * t];
        let i1 = indices[3u * t + 1u];
        let i2 = indices[3u * t + 2u];
        if (i0 < nvert && i1 < nvert && i2 < nvert) {
            acc += measure_triangle(i0, i1, i2);
        }
    }
    sh[lid] = acc;
    tree_sum(lid);
    if (lid == 0u) {
        partials[wg.x] = sh[0];
    }
}

@compute @workgroup_size(256)
fn final_sum(@builtin(local_invocation_index) lid: u32) {
    sh[lid] = partials[lid];
    tree_sum(lid);
    if (lid == 0u) {
        counters[C_AREA] = bitcast<u32>(sh[0].x);
        counters[C_VOLUME] = bitcast<u32>(sh[0].y);
    }
}

// After the scans of a slab, before compaction: emit dispatch size and default owned vertices.
@compute @workgroup_size(1)
fn slab_begin() {
    let groups = (counters[C_SCAN_ACTIVE] + 63u) / 64u;
    let x = min(groups, mu.max_groups_x);
    dispatch_args[0] = x;
    dispatch_args[1] = select(0u, (groups + x - 1u) / max(x, 1u), groups > 0u);
    dispatch_args[2] = 1u;
    counters[C_SLAB_OWNED_VERTICES] = counters[C_SCAN_VERTICES];
}

// After a slab's emission: advance the global vertex and triangle bases.
@compute @workgroup_size(1)
fn slab_end() {
    counters[C_SLAB_VERTEX_BASE] += counters[C_SLAB_OWNED_VERTICES];
    counters[C_SLAB_TRIANGLE_BASE] += counters[C_SCAN_TRIANGLES];
    counters[C_ACTIVE_TOTAL] += counters[C_SCAN_ACTIVE];
}

// After the last slab: totals, overflow bits and the renderer's indirect draw arguments.
@compute @workgroup_size(1)
fn frame_end() {
    let nv = counters[C_SLAB_VERTEX_BASE];
    let nt = counters[C_SLAB_TRIANGLE_BASE];
    counters[C_VERTEX_COUNT] = nv;
    counters[C_TRIANGLE_COUNT] = nt;
    var overflow = counters[C_OVERFLOW];
    if (nv > counters[C_VERTEX_CAPACITY]) {
        overflow |= OVERFLOW_VERTICES;
    }
    if (nt > counters[C_TRIANGLE_CAPACITY]) {
        overflow |= OVERFLOW_TRIANGLES;
    }
    counters[C_OVERFLOW] = overflow;
    var draw = nt;
    if (overflow != 0u) {
        draw = 0u;
    }
    draw_args[0] = 3u * draw;
    draw_args[1] = 1u;
    draw_args[2] = 0u;
    draw_args[3] = 0u;
    draw_args[4] = 0u;
}
