// Exposure radii of the SES preset on the GPU (Rust side: src/gpu/exposure.rs; the host rule is
// crate::model::exposure::heavy_neighbour_counts and ExposureModel::apply). The heavy atoms are
// binned by counting sort into cells of about a quarter of the counting radius (count_heavy,
// [scan.wgsl], copy_starts, scatter_heavy); count_neighbours then counts, for every atom, the
// heavy atoms within the radius (d^2 <= r^2, the host's test, with the same f32 roundings: see
// `exact`), visiting the cells that the sphere can reach nearest first and stopping at the
// model's saturation, and writes radius = base radius * factor[count] (the factor table is
// ExposureModel::factor of every count up to the saturation, computed on the host), so the radii
// equal the host's bit for bit.

// Twin of crate::gpu::types::ExposureUniform (64 bytes).
struct ExposureUniform {
    cell_origin: vec3<f32>,
    cell_size: f32,
    cell_dims: vec3<u32>,
    atom_count: u32,
    heavy_count: u32,
    offset_count: u32,
    cap: u32,
    radius_sq: f32,
    zero_bits: u32,
    cell_count: u32,
    _pad0: u32,
    _pad1: u32,
}

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::exposure`).
@group(0) @binding(0) var<uniform> u: ExposureUniform;
// Positions in Å, packed x, y, z per atom.
@group(0) @binding(1) var<storage, read> positions: array<f32>;
// Index of every heavy atom.
@group(0) @binding(2) var<storage, read> heavy: array<u32>;
// Per cell: heavy atom count during `count_heavy`, then (after the scan) its first slot.
@group(0) @binding(3) var<storage, read_write> cell_count: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read> cell_start: array<u32>;
// Per cell: fill cursor during `scatter_heavy`, one past the last slot afterwards.
@group(0) @binding(5) var<storage, read_write> cell_end: array<atomic<u32>>;
// Heavy atom positions in Å by cell (w unused).
@group(0) @binding(6) var<storage, read_write> sorted_heavy: array<vec4<f32>>;
// Cell offsets (x, y, z, unused) a sphere of the radius can reach, nearest first.
@group(0) @binding(7) var<storage, read> offsets: array<vec4<i32>>;
// Radius factor by count, 0 ..= cap.
@group(0) @binding(8) var<storage, read> factors: array<f32>;
// The atoms' own radii in Å.
@group(0) @binding(9) var<storage, read> base_radii: array<f32>;
// This frame's radii in Å (what binning reads).
@group(0) @binding(10) var<storage, read_write> radii: array<f32>;
// Heavy atoms counted per atom (at most cap).
@group(0) @binding(11) var<storage, read_write> counts: array<u32>;

fn atom_position(i: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
}

fn cell_coords(p: vec3<f32>) -> vec3<i32> {
    let c = vec3<i32>(floor((p - u.cell_origin) / u.cell_size));
    return clamp(c, vec3<i32>(0), vec3<i32>(u.cell_dims) - vec3<i32>(1));
}

fn cell_index(c: vec3<i32>) -> u32 {
    let cc = vec3<u32>(c);
    return cc.x + u.cell_dims.x * (cc.y + u.cell_dims.y * cc.z);
}

fn linear_id(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 256u;
}

// `x` as a rounded f32 the compiler cannot see through (zero_bits is 0 at run time): a product
// passed through here cannot be fused into a multiply-add, so each square and sum is rounded
// as the host rounds it.
fn exact(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) | u.zero_bits);
}

@compute @workgroup_size(256)
fn count_heavy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = linear_id(gid, nwg);
    if (j >= u.heavy_count) {
        return;
    }
    atomicAdd(&cell_count[cell_index(cell_coords(atom_position(heavy[j])))], 1u);
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
fn scatter_heavy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = linear_id(gid, nwg);
    if (j >= u.heavy_count) {
        return;
    }
    let p = atom_position(heavy[j]);
    let slot = atomicAdd(&cell_end[cell_index(cell_coords(p))], 1u);
    sorted_heavy[slot] = vec4<f32>(p, 0.0);
}

@compute @workgroup_size(256)
fn count_neighbours(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = linear_id(gid, nwg);
    if (i >= u.atom_count) {
        return;
    }
    let p = atom_position(i);
    let own = cell_coords(p);
    let top = vec3<i32>(u.cell_dims) - vec3<i32>(1);
    var n = 0u;
    for (var k = 0u; k < u.offset_count && n < u.cap; k++) {
        let c = own + offsets[k].xyz;
        if (any(c < vec3<i32>(0)) || any(c > top)) {
            continue;
        }
        let cell = cell_index(c);
        // The scan's starts are exclusive: a cell ends where the next begins (the last cell at
        // the heavy count). Not cell_end: count_neighbours keeps to 8 storage buffers, the
        // WebGPU default per stage.
        var last = u.heavy_count;
        if (cell + 1u < u.cell_count) {
            last = cell_start[cell + 1u];
        }
        for (var s = cell_start[cell]; s < last; s++) {
            // As glam's q.distance_squared(p): ((dx * dx) + (dy * dy)) + (dz * dz).
            let d = sorted_heavy[s].xyz - p;
            let d2 = exact(exact(exact(d.x * d.x) + exact(d.y * d.y)) + exact(d.z * d.z));
            n += select(0u, 1u, d2 <= u.radius_sq);
        }
    }
    n = min(n, u.cap);
    counts[i] = n;
    radii[i] = base_radii[i] * factors[n];
}
