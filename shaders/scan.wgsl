// Reusable exclusive prefix sum of u32 arrays (in place), blocks of 1024 elements per workgroup,
// recursive over block sums. Rust side: src/gpu/scan.rs. Used for the cell counts of the binning
// stage and the per-block vertex/triangle/active-cell counts of Marching Cubes.

// Twin of crate::gpu::types::ScanUniform (16 bytes).
struct ScanUniform {
    count: u32,
    sum_index: u32,
    _pad0: u32,
    _pad1: u32,
}

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::scan`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> su: ScanUniform;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
// scan_blocks: receives each block's total at sum_index + block; add_sums: scanned block totals.
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

const WG: u32 = 256u;
const PER: u32 = 4u;
const BLOCK: u32 = 1024u;

var<workgroup> sh: array<u32, 256>;

@compute @workgroup_size(256)
fn scan_blocks(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wg.x + wg.y * nwg.x;
    let base = block * BLOCK + lid * PER;
    var local: array<u32, 4>;
    var s = 0u;
    for (var q = 0u; q < PER; q++) {
        local[q] = s;
        let idx = base + q;
        if (idx < su.count) {
            s += data[idx];
        }
    }
    sh[lid] = s;
    workgroupBarrier();
    for (var off = 1u; off < WG; off *= 2u) {
        var add = 0u;
        if (lid >= off) {
            add = sh[lid - off];
        }
        workgroupBarrier();
        sh[lid] += add;
        workgroupBarrier();
    }
    let excl = sh[lid] - s;
    for (var q = 0u; q < PER; q++) {
        let idx = base + q;
        if (idx < su.count) {
            data[idx] = excl + local[q];
        }
    }
    if (lid == WG - 1u) {
        sums[su.sum_index + block] = sh[WG - 1u];
    }
}

@compute @workgroup_size(256)
fn add_sums(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = wg.x + wg.y * nwg.x;
    let offset = sums[block];
    let base = block * BLOCK + lid * PER;
    for (var q = 0u; q < PER; q++) {
        let idx = base + q;
        if (idx < su.count) {
            data[idx] += offset;
        }
    }
}
