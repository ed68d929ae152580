// Binning stage: counting sort of atoms into a uniform cell grid (count, [scan.wgsl], copy,
// scatter, sort_cells). Rust side: src/gpu/bin.rs. The scatter's atomics hand out slots in any
// order; sort_cells then orders each cell's atoms by (x, y, z, alpha), so the density sums run
// in an order that depends neither on the run nor on the input order of the atoms. Cell of an atom: floor((p - cell_origin) / cell_size),
// clamped to the cell grid, linear index x fastest.

// Twin of crate::gpu::types::BinUniform (48 bytes).
struct BinUniform {
    cell_origin: vec3<f32>,
    cell_size: f32,
    cell_dims: vec3<u32>,
    atom_count: u32,
    radius_scale: f32,
    cell_count: u32,
    _pad0: u32,
    _pad1: u32,
}

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::bin`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: BinUniform;
// Positions in Å, packed x, y, z per atom.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
// Radii in Å.
@group(0) @binding(2) var<storage, read> radii: array<f32>;
// Colours as two u32: pack2x16unorm(r, g), pack2x16unorm(b, 0).
@group(0) @binding(3) var<storage, read> colours: array<vec2<u32>>;
// Per cell: atom count during `count`, then (after the scan) the first slot of the cell.
@group(0) @binding(4) var<storage, read_write> cell_count: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> cell_start: array<u32>;
// Per cell: fill cursor during `scatter`, one past the last slot afterwards.
@group(0) @binding(6) var<storage, read_write> cell_end: array<atomic<u32>>;
// Sorted atoms: (x, y, z in Å, alpha = r * R in Å).
@group(0) @binding(7) var<storage, read_write> sorted_atoms: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> sorted_colours: array<vec2<u32>>;

fn atom_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn cell_of(p: vec3<f32>) -> u32 {
    let c = vec3<i32>(floor((p - u.cell_origin) / u.cell_size));
    let cc = vec3<u32>(clamp(c, vec3<i32>(0), vec3<i32>(u.cell_dims) - vec3<i32>(1)));
    return cc.x + u.cell_dims.x * (cc.y + u.cell_dims.y * cc.z);
}

fn linear_id(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 256u;
}

@compute @workgroup_size(256)
fn count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_id(gid, nwg);
    if (i >= u.atom_count) {
        return;
    }
    atomicAdd(&cell_count[cell_of(atom_position(i))], 1u);
}

@compute @workgroup_size(256)
fn copy_starts(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let c = linear_id(gid, nwg);
    if (c >= u.cell_count) {
        return;
    }
    atomicStore(&cell_end[c], cell_start[c]);
}

@compute @workgroup_size(256)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_id(gid, nwg);
    if (i >= u.atom_count) {
        return;
    }
    let p = atom_position(i);
    let slot = atomicAdd(&cell_end[cell_of(p)], 1u);
    sorted_atoms[slot] = vec4<f32>(p, radii[i] * u.radius_scale);
    sorted_colours[slot] = colours[i];
}

// Cells holding more atoms than this keep the scatter order (insertion sort is quadratic).
const MAX_SORTED: u32 = 1024u;

fn atom_less(a: vec4<f32>, b: vec4<f32>) -> bool {
    if (a.x != b.x) {
        return a.x < b.x;
    }
    if (a.y != b.y) {
        return a.y < b.y;
    }
    if (a.z != b.z) {
        return a.z < b.z;
    }
    return a.w < b.w;
}

@compute @workgroup_size(256)
fn sort_cells(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let c = linear_id(gid, nwg);
    if (c >= u.cell_count) {
        return;
    }
    let first = cell_start[c];
    let last = atomicLoad(&cell_end[c]);
    if (last - first > MAX_SORTED) {
        return;
    }
    for (var i = first + 1u; i < last; i++) {
        let a = sorted_atoms[i];
        let ac = sorted_colours[i];
        var j = i;
        while (j > first && atom_less(a, sorted_atoms[j - 1u])) {
            sorted_atoms[j] = sorted_atoms[j - 1u];
            sorted_colours[j] = sorted_colours[j - 1u];
            j--;
        }
        sorted_atoms[j] = a;
        sorted_colours[j] = ac;
    }
}
