// Sparse bricks: which bricks of BRICK^3 samples some atom's cutoff sphere reaches, listed so
// that the density pass can be dispatched over them only (indirectly). Entry points, in order:
// mark (per brick: reached or not, from the atoms of the bin cells around it), [scan.wgsl over
// brick_scan, total to brick_args word 3], compact (the reached bricks' ids, ascending, after the
// count, and the brick slot table in the density buffer) and args (the indirect dispatch
// arguments). Rust side: src/gpu/bricks.rs. A brick that
// no atom reaches holds density 0 at every sample, exactly as the dense pass computes it there.
// BRICK and SLOT_UNREACHED come from brick_const.wgsl, prepended by src/gpu/shaders.rs.

// Twin of crate::gpu::types::BrickUniform (96 bytes).
struct BrickUniform {
    origin: vec3<f32>,
    spacing: f32,
    dims: vec3<u32>,
    brick_count: u32,
    brick_dims: vec3<u32>,
    max_groups: u32,
    cell_origin: vec3<f32>,
    cell_size: f32,
    cell_dims: vec3<u32>,
    cutoff: f32,
    max_cut: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::bricks`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: BrickUniform;
// Sorted atoms: (x, y, z in Å, alpha in Å).
@group(0) @binding(1) var<storage, read> sorted_atoms: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> cell_start: array<u32>;
@group(0) @binding(3) var<storage, read> cell_end: array<u32>;
// Per brick: 1 when some atom reaches it, else 0 (kept; classify.wgsl reads it).
@group(0) @binding(4) var<storage, read_write> brick_flags: array<u32>;
// Per brick: the flag, then (after the scan) the brick's slot in the list.
@group(0) @binding(5) var<storage, read_write> brick_scan: array<u32>;
// Word 0: number of reached bricks n; words 1..=n: their ids (x fastest), ascending.
@group(0) @binding(6) var<storage, read_write> active_bricks: array<u32>;
// Indirect dispatch arguments (x, y, z workgroups) and, in word 3, the scan total n.
@group(0) @binding(7) var<storage, read_write> brick_args: array<u32>;
// The density buffer: compact writes the brick slot table into its first brick_count words
// (per brick its slot, high bit set when unreached); the reached bricks' samples follow it
// (shaders/density.wgsl).
@group(0) @binding(8) var<storage, read_write> density: array<u32>;

fn linear_id(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 64u;
}

fn cell_coord(x: f32, o: f32, n: u32) -> u32 {
    return u32(clamp(i32(floor((x - o) / u.cell_size)), 0, i32(n) - 1));
}

@compute @workgroup_size(64)
fn mark(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let b = linear_id(gid, nwg);
    if (b >= u.brick_count) {
        return;
    }
    let bc = vec3<u32>(
        b % u.brick_dims.x,
        (b / u.brick_dims.x) % u.brick_dims.y,
        b / (u.brick_dims.x * u.brick_dims.y),
    );
    // The brick's samples span [lo, hi] (Å); the last brick along an axis may stop earlier,
    // and a larger box only marks more bricks (never fewer).
    let lo = u.origin + u.spacing * vec3<f32>(bc * BRICK);
    let hi = u.origin + u.spacing * vec3<f32>(bc * BRICK + vec3<u32>(BRICK - 1u));
    // The same slack as the density gather's cell range, and more on the distance test, so
    // rounding never leaves a brick unmarked that the dense pass gives a nonzero sample.
    let reach = u.max_cut * 1.0001 + 1e-4;
    let c0 = vec3<u32>(
        cell_coord(lo.x - reach, u.cell_origin.x, u.cell_dims.x),
        cell_coord(lo.y - reach, u.cell_origin.y, u.cell_dims.y),
        cell_coord(lo.z - reach, u.cell_origin.z, u.cell_dims.z),
    );
    let c1 = vec3<u32>(
        cell_coord(hi.x + reach, u.cell_origin.x, u.cell_dims.x),
        cell_coord(hi.y + reach, u.cell_origin.y, u.cell_dims.y),
        cell_coord(hi.z + reach, u.cell_origin.z, u.cell_dims.z),
    );
    var reached = 0u;
    for (var cz = c0.z; cz <= c1.z && reached == 0u; cz++) {
        for (var cy = c0.y; cy <= c1.y && reached == 0u; cy++) {
            let row = u.cell_dims.x * (cy + u.cell_dims.y * cz);
            let first = cell_start[row + c0.x];
            let last = cell_end[row + c1.x];
            for (var s = first; s < last; s++) {
                let a = sorted_atoms[s];
                // Distance (Å) from the atom to the brick's box of samples.
                let d = max(max(lo - a.xyz, a.xyz - hi), vec3<f32>(0.0));
                let c = u.cutoff * a.w * 1.001 + 1e-3;
                if (dot(d, d) < c * c) {
                    reached = 1u;
                    break;
                }
            }
        }
    }
    brick_flags[b] = reached;
    brick_scan[b] = reached;
}

@compute @workgroup_size(64)
fn compact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let b = linear_id(gid, nwg);
    if (b >= u.brick_count) {
        return;
    }
    // The exclusive scan: a reached brick's slot, and for any brick the slots before it (so
    // a slab finds the first slot of its first brick layer even when that brick is unreached).
    let slot = brick_scan[b];
    if (brick_flags[b] == 0u) {
        density[b] = slot | SLOT_UNREACHED;
        return;
    }
    density[b] = slot;
    active_bricks[1u + slot] = b;
}

@compute @workgroup_size(1)
fn args() {
    let n = brick_args[3];
    active_bricks[0] = n;
    let x = min(n, u.max_groups);
    var y = 1u;
    if (x > 0u) {
        y = (n + x - 1u) / x;
    }
    brick_args[0] = x;
    brick_args[1] = y;
    brick_args[2] = 1u;
}
