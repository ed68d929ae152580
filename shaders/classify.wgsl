// Marching Cubes classification: per grid point of the slab (plus one layer above it), the case
// byte of the cell based there, which of its own x/y/z edges the surface crosses, and its
// triangle count; per workgroup of 256 points the sums of vertices, triangles and active cells,
// which scan.wgsl then prefix-sums. Rust side: src/gpu/mc.rs (Classify).
// Class word: case | crossed own edges << 8 | triangles << 12 | active << 16, stored at the
// point's entry (shaders/class_entries.wgsl).

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.
// So are the counter words and overflow bits (C_*, OVERFLOW_*: counters.wgsl), the brick
// constants (BRICK, CLASS_APRON, ...: brick_const.wgsl) and the Marching Cubes tables' layout
// (McTablesUniform, MC_TRI_BASE: mc_tables.wgsl).

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::classify`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: SlabUniform;
// Density words (f32 bits): see dens_at.
@group(0) @binding(1) var<storage, read> density: array<u32>;
fn table_word(i: u32) -> u32 {
    return mc.words[i / 4u][i % 4u];
}

// Triangles per case: case start c + 1 minus case start c.
@group(0) @binding(2) var<uniform> mc: McTablesUniform;
@group(0) @binding(3) var<storage, read_write> classes: array<u32>;
@group(0) @binding(4) var<storage, read_write> block_vertices: array<u32>;
@group(0) @binding(5) var<storage, read_write> block_triangles: array<u32>;
@group(0) @binding(6) var<storage, read_write> block_active: array<u32>;
// Per BRICK^3 brick: 1 when some atom reaches it (shaders/bricks.wgsl); read when u.sparse != 0.
@group(0) @binding(7) var<storage, read> brick_flags: array<u32>;
// Twin of crate::gpu::types::GpuCounters, as words: on sparse classes, an entry past the class
// buffers sets OVERFLOW_BRICKS and raises brick_slots, so the engine grows them (with the brick
// slots) and runs the frame again.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;

// Stores the class word of point p (entry e); false when its brick slot lies past the class
// buffers (flagged for the engine).
fn store_class(e: u32, word: u32) -> bool {
    if (!sparse_classes()) {
        classes[e] = word;
        return true;
    }
    if (e >= arrayLength(&classes)) {
        let slots = e / (CLASS_APRON * CLASS_APRON * CLASS_APRON) + 1u;
        atomicMax(&counters[C_BRICK_SLOTS], slots);
        atomicOr(&counters[C_OVERFLOW], OVERFLOW_BRICKS);
        return false;
    }
    classes[e] = word;
    return true;
}

// True when a brick holding one of the points (i..=i+1, j..=j+1, k..=k+1) (clamped to the grid)
// is reached by some atom. Otherwise every density this point's classification reads is 0 (the
// sparse density pass left those bricks zeroed, as the dense pass computes them), so the class
// word is 0 and the density need not be read.
fn near_reached_brick(i: u32, j: u32, k: u32) -> bool {
    let b0 = vec3<u32>(i, j, k) / BRICK;
    let b1 = min(vec3<u32>(i + 1u, j + 1u, k + 1u), u.dims - vec3<u32>(1u)) / BRICK;
    for (var bz = b0.z; bz <= b1.z; bz++) {
        for (var by = b0.y; by <= b1.y; by++) {
            for (var bx = b0.x; bx <= b1.x; bx++) {
                if (brick_flags[bx + u.brick_dims.x * (by + u.brick_dims.y * bz)] != 0u) {
                    return true;
                }
            }
        }
    }
    return false;
}

var<workgroup> sh: array<vec3<u32>, 256>;

fn dens(i: u32, j: u32, k: u32) -> f32 {
    return dens_at(i, j, k);
}

@compute @workgroup_size(256)
fn main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wg.x + wg.y * nwg.x;
    let n = block * 256u + lid;
    let layer = u.dims.x * u.dims.y;
    let k = u.own_z0 + n / layer;
    let class_z1 = min(u.own_z1 + 1u, u.dims.z);
    var counts = vec3<u32>(0u);
    var skip = false;
    var entry = n;
    if (n < u.class_points && k < class_z1 && sparse_classes()) {
        // A point has an entry exactly when its cell touches a reached brick.
        entry = class_entry(class_point(n));
        skip = entry == NO_ENTRY;
    } else if (n < u.class_points && k < class_z1 && u.sparse != 0u) {
        let r = n % layer;
        skip = !near_reached_brick(r % u.dims.x, r / u.dims.x, k);
    }
    if (n < u.class_points && k < class_z1 && !skip) {
        let r = n % layer;
        let i = r % u.dims.x;
        let j = r / u.dims.x;
        let iso = u.isovalue;
        let d0 = dens(i, j, k);
        let in0 = d0 >= iso;
        var edges = 0u;
        if (i + 1u < u.dims.x && (dens(i + 1u, j, k) >= iso) != in0) {
            edges |= 1u;
        }
        if (j + 1u < u.dims.y && (dens(i, j + 1u, k) >= iso) != in0) {
            edges |= 2u;
        }
        if (k + 1u < u.dims.z && (dens(i, j, k + 1u) >= iso) != in0) {
            edges |= 4u;
        }
        var case_id = 0u;
        var tris = 0u;
        if (i + 1u < u.dims.x && j + 1u < u.dims.y && k + 1u < u.dims.z && k < u.own_z1) {
            for (var c = 0u; c < 8u; c++) {
                if (dens(i + (c & 1u), j + ((c >> 1u) & 1u), k + ((c >> 2u) & 1u)) >= iso) {
                    case_id |= 1u << c;
                }
            }
            tris = table_word(case_id + 1u) - table_word(case_id);
        }
        let verts = countOneBits(edges);
        var is_active = 0u;
        if (k < u.own_z1 && (verts > 0u || tris > 0u)) {
            is_active = 1u;
        }
        let word = case_id | (edges << 8u) | (tris << 12u) | (is_active << 16u);
        if (store_class(entry, word)) {
            counts = vec3<u32>(verts, tris, is_active);
        }
    } else if (n < u.class_points && !sparse_classes()) {
        // Above the slab, or far from every atom (sparse bricks): outside, no edges. (Sparse
        // classes hold no entry for such points: compact.wgsl reads them as 0.)
        classes[n] = 0u;
    }
    sh[lid] = counts;
    workgroupBarrier();
    for (var off = 128u; off > 0u; off >>= 1u) {
        if (lid < off) {
            sh[lid] += sh[lid + off];
        }
        workgroupBarrier();
    }
    if (lid == 0u) {
        block_vertices[block] = sh[0].x;
        block_triangles[block] = sh[0].y;
        block_active[block] = sh[0].z;
    }
}
