// Marching Cubes emission, one thread per active cell: the vertices on the point's own crossed
// edges (position and colour interpolated along the edge, normal = normalised -grad rho from
// central differences at both ends, interpolated) and the cell's triangles as vertex indices.
// Never writes past the capacities in the counters; sets the overflow bits instead.
// Rust side: src/gpu/mc.rs (Emit). Vertex layout: twin of crate::gpu::types::GpuVertex
// (9 f32: position, normal, colour; 36 bytes).

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.
// So are the counter words and overflow bits (C_*, OVERFLOW_*: counters.wgsl), the brick
// constants (brick_const.wgsl) and the Marching Cubes tables' layout (McTablesUniform,
// MC_TRI_BASE: mc_tables.wgsl).

// First corner of each cell edge (crate::surface::tables::EDGE_CORNERS[e][0]); edge e runs
// along axis e / 4.
const EDGE_CORNER0: array<u32, 12> = array<u32, 12>(0u, 2u, 4u, 6u, 0u, 1u, 4u, 5u, 0u, 1u, 2u, 3u);

override WITH_COLOUR: bool = true;

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::emit`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: SlabUniform;
// Density words (f32 bits): see dens_at.
@group(0) @binding(1) var<storage, read> density: array<u32>;
@group(0) @binding(2) var<storage, read> colour: array<f32>;
@group(0) @binding(3) var<storage, read> classes: array<u32>;
@group(0) @binding(4) var<storage, read> vertex_base: array<u32>;
@group(0) @binding(5) var<storage, read> active_cells: array<vec2<u32>>;
fn table_word(i: u32) -> u32 {
    return mc.words[i / 4u][i % 4u];
}

@group(0) @binding(6) var<uniform> mc: McTablesUniform;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> vertices: array<f32>;
@group(0) @binding(10) var<storage, read_write> indices: array<u32>;

fn local_index(p: vec3<u32>) -> u32 {
    return p.x + u.dims.x * (p.y + u.dims.y * (p.z - u.dens_z0));
}

fn dens(p: vec3<u32>) -> f32 {
    return dens_at(p.x, p.y, p.z);
}

// Colour sum at grid point p: the slab volume, or on sparse bricks the sample of its brick
// slot (0 when no atom reaches the brick, as the dense pass computes it).
fn col(p: vec3<u32>) -> vec3<f32> {
    var s = local_index(p);
    if (u.sparse != 0u) {
        s = sample_slot(p.x, p.y, p.z);
        if (s == NO_SAMPLE) {
            return vec3<f32>(0.0);
        }
    }
    let v = 3u * s;
    return vec3<f32>(colour[v], colour[v + 1u], colour[v + 2u]);
}


// -grad rho at grid point p by central differences (one-sided at the grid boundary), in
// density units per sample; only its direction is used.
fn neg_gradient(p: vec3<u32>) -> vec3<f32> {
    var g = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        var lo = p;
        var hi = p;
        if (p[a] > 0u) {
            lo[a] = p[a] - 1u;
        }
        if (p[a] + 1u < u.dims[a]) {
            hi[a] = p[a] + 1u;
        }
        g[a] = (dens(lo) - dens(hi)) / f32(hi[a] - lo[a]);
    }
    return g;
}

fn safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if (l > 0.0) {
        return v / l;
    }
    return vec3<f32>(0.0);
}

fn write_vertex(id: u32, p0: vec3<u32>, axis: u32) {
    var p1 = p0;
    p1[axis] = p0[axis] + 1u;
    let d0 = dens(p0);
    let d1 = dens(p1);
    let t = (u.isovalue - d0) / (d1 - d0);
    let x0 = u.origin + u.spacing * vec3<f32>(p0);
    let x1 = u.origin + u.spacing * vec3<f32>(p1);
    let pos = x0 + (x1 - x0) * t;
    let n0 = safe_normalize(neg_gradient(p0));
    let n1 = safe_normalize(neg_gradient(p1));
    let nrm = safe_normalize(n0 + (n1 - n0) * t);
    var c = vec3<f32>(1.0);
    if (WITH_COLOUR) {
        // The colour volume holds sum(w * colour); on the surface sum(w) = I.
        let c0 = col(p0);
        c = (c0 + (col(p1) - c0) * t) / u.isovalue;
    }
    let o = 9u * id;
    vertices[o] = pos.x;
    vertices[o + 1u] = pos.y;
    vertices[o + 2u] = pos.z;
    vertices[o + 3u] = nrm.x;
    vertices[o + 4u] = nrm.y;
    vertices[o + 5u] = nrm.z;
    vertices[o + 6u] = c.x;
    vertices[o + 7u] = c.y;
    vertices[o + 8u] = c.z;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let a = gid.x + gid.y * nwg.x * 64u;
    if (a >= atomicLoad(&counters[C_SCAN_ACTIVE])) {
        return;
    }
    let cell = active_cells[a];
    let p = class_point(cell.x);
    let first = class_first_slot();
    let e0 = class_entry_from(p, first);
    let word = classes[e0];
    let edges = (word >> 8u) & 7u;
    let vcap = atomicLoad(&counters[C_VERTEX_CAPACITY]);
    let tcap = atomicLoad(&counters[C_TRIANGLE_CAPACITY]);
    if (edges != 0u) {
        var id = vertex_base[e0];
        for (var axis = 0u; axis < 3u; axis++) {
            if ((edges & (1u << axis)) != 0u) {
                if (id < vcap) {
                    write_vertex(id, p, axis);
                } else {
                    atomicOr(&counters[C_OVERFLOW], OVERFLOW_VERTICES);
                }
                id++;
            }
        }
    }
    let case_id = word & 255u;
    let t0 = table_word(case_id);
    let t1 = table_word(case_id + 1u);
    for (var t = t0; t < t1; t++) {
        let tri = cell.y + (t - t0);
        if (tri >= tcap) {
            atomicOr(&counters[C_OVERFLOW], OVERFLOW_TRIANGLES);
            break;
        }
        for (var v = 0u; v < 3u; v++) {
            let e = table_word(MC_TRI_BASE + 3u * t + v);
            let c = EDGE_CORNER0[e];
            let axis = e / 4u;
            let q = class_entry_from(p + vec3<u32>(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u), first);
            let qe = (classes[q] >> 8u) & 7u;
            indices[3u * tri + v] = vertex_base[q] + countOneBits(qe & ((1u << axis) - 1u));
        }
    }
}
