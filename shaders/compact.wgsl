// Marching Cubes compaction: turns the scanned block sums and a workgroup-local scan of the classes
// words into each point's first vertex id (global, x-fastest order over the whole grid) and the
// list of active cells with their first triangle id. Same 256-point blocks as classify.wgsl.
// Rust side: src/gpu/mc.rs (Compact).

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.
// So are the counter words (C_*: counters.wgsl) and the brick constants (NO_ENTRY, ...:
// brick_const.wgsl).

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::compact`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: SlabUniform;
@group(0) @binding(1) var<storage, read> classes: array<u32>;
@group(0) @binding(2) var<storage, read> block_vertices: array<u32>;
@group(0) @binding(3) var<storage, read> block_triangles: array<u32>;
@group(0) @binding(4) var<storage, read> block_active: array<u32>;
@group(0) @binding(5) var<storage, read_write> counters: array<u32>;
// Global id of the first vertex on each point's crossed edges (valid where it has any), at the
// point's class entry.
@group(0) @binding(6) var<storage, read_write> vertex_base: array<u32>;
// Active cells: (local class point index, global id of its first triangle).
@group(0) @binding(7) var<storage, read_write> active_cells: array<vec2<u32>>;
// Density words: only the brick slot table is read (sparse classes, class_entries.wgsl).
@group(0) @binding(8) var<storage, read> density: array<u32>;

// The class word of local class point n, and its entry (NO_ENTRY when it has none: word 0).
fn class_word(n: u32) -> vec2<u32> {
    if (n >= u.class_points) {
        return vec2<u32>(0u, NO_ENTRY);
    }
    if (!sparse_classes()) {
        // Dense classes: classify.wgsl wrote every point, 0 above the slab.
        return vec2<u32>(classes[n], n);
    }
    let p = class_point(n);
    if (p.z >= min(u.own_z1 + 1u, u.dims.z)) {
        return vec2<u32>(0u, NO_ENTRY);
    }
    let e = class_entry(p);
    if (e >= arrayLength(&classes)) {
        return vec2<u32>(0u, NO_ENTRY);
    }
    return vec2<u32>(classes[e], e);
}

var<workgroup> sh: array<vec3<u32>, 256>;
var<workgroup> block_empty: u32;

// Vertices plus active cells of `block` (from the scanned block sums; the last block's end is
// the scan total).
fn block_load(block: u32) -> u32 {
    let blocks = (u.class_points + 255u) / 256u;
    var end = vec2<u32>(counters[C_SCAN_VERTICES], counters[C_SCAN_ACTIVE]);
    if (block + 1u < blocks) {
        end = vec2<u32>(block_vertices[block + 1u], block_active[block + 1u]);
    }
    return (end.x - block_vertices[block]) + (end.y - block_active[block]);
}

@compute @workgroup_size(256)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wg.x + wg.y * nwg.x;
    let n = block * 256u + lid;
    // A block without vertices or active cells (most of them: empty space, or far from every
    // atom on sparse bricks) writes nothing, unless it holds the point where the slab's owned
    // vertices end; the whole workgroup leaves at once, before its scan.
    if (lid == 0u) {
        let owned_end = u.dims.x * u.dims.y * (u.own_z1 - u.own_z0);
        let holds_end = u.has_extra_layer != 0u && owned_end / 256u == block;
        block_empty = select(0u, 1u, block * 256u < u.class_points && !holds_end
            && block_load(block) == 0u);
    }
    if (workgroupUniformLoad(&block_empty) != 0u) {
        return;
    }
    let at = class_word(n);
    let word = at.x;
    let own = vec3<u32>(countOneBits((word >> 8u) & 7u), (word >> 12u) & 15u, (word >> 16u) & 1u);
    sh[lid] = own;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off *= 2u) {
        var add = vec3<u32>(0u);
        if (lid >= off) {
            add = sh[lid - off];
        }
        workgroupBarrier();
        sh[lid] += add;
        workgroupBarrier();
    }
    let excl = sh[lid] - own;
    if (n >= u.class_points) {
        return;
    }
    let slab_vertices = block_vertices[block] + excl.x;
    if (own.x > 0u) {
        vertex_base[at.y] = counters[C_SLAB_VERTEX_BASE] + slab_vertices;
    }
    if (own.z > 0u) {
        let tri = counters[C_SLAB_TRIANGLE_BASE] + block_triangles[block] + excl.y;
        active_cells[block_active[block] + excl.z] = vec2<u32>(n, tri);
    }
    // Vertices owned by this slab end where the extra layer above it begins.
    if (u.has_extra_layer != 0u && n == u.dims.x * u.dims.y * (u.own_z1 - u.own_z0)) {
        counters[C_SLAB_OWNED_VERTICES] = slab_vertices;
    }
}
