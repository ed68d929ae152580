// Density (and colour) gather: each thread computes RUN consecutive voxels along x of one slab
// layer, looping over the atoms of the neighbouring bin cells once and sharing the y/z distance
// work between its voxels (the paper's thread coarsening). Per-pair cutoff test before the
// exponential; arithmetic mirrors the CPU reference (crate::surface density). Rust side:
// src/gpu/density.rs. Output: density[v] (f32 bits) and colour[3c..3c+3] (sum of w * colour,
// not yet divided by I).
// Two entry points run the same gather (so a voxel gets the same bits from either): `main` over
// every voxel of the slab, with v = c = i + nx * (j + ny * (k - dens_z0)); and `bricks` over
// the sparse bricks some atom reaches (one workgroup of 64 threads per BRICK^3 brick,
// dispatched indirectly from the list of shaders/bricks.wgsl), brick-locally: the first
// brick_count words of density are the brick slot table (shaders/bricks.wgsl), then
// c = (slot - first slot of the slab's first brick layer) * BRICK^3 + local sample index and
// v = brick_count + c. A slab whose bricks do not fit the buffers sets OVERFLOW_BRICKS.

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.

// True when the colour volume is computed too.
override WITH_COLOUR: bool = true;
// False for a colour-only pass (colour scheme changed): the density volume is left as it is.
override WRITE_DENSITY: bool = true;

const RUN: u32 = 8u;

// Bindings (group 0) are named once in src/gpu/layout.rs (`layout::density`): the Rust side
// builds explicit bind-group layouts from that table, and tests/it/gpu_steady.rs checks these
// declarations against it with naga.
@group(0) @binding(0) var<uniform> u: SlabUniform;
@group(0) @binding(1) var<storage, read> sorted_atoms: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> sorted_colours: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> cell_start: array<u32>;
@group(0) @binding(4) var<storage, read> cell_end: array<u32>;
@group(0) @binding(5) var<storage, read_write> density: array<u32>;
@group(0) @binding(6) var<storage, read_write> colour: array<f32>;
// Word 0: number of listed bricks n; words 1..=n: brick ids (x fastest; shaders/bricks.wgsl).
@group(0) @binding(7) var<storage, read> active_bricks: array<u32>;
// Frame counters (twin of crate::gpu::types::GpuCounters), as words.
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;

// Word of the overflow bits in the counters, and the bit of crate::gpu::types::OVERFLOW_BRICKS.
const C_OVERFLOW: u32 = 2u;
const OVERFLOW_BRICKS: u32 = 4u;
// Word of crate::gpu::types::GpuCounters::brick_slots: the most slots one slab used.
const C_BRICK_SLOTS: u32 = 15u;

// Samples per brick edge (crate::gpu::plan::BRICK; one run of RUN voxels spans a brick row).
const BRICK: u32 = 8u;

fn cell_coord(x: f32, o: f32, n: u32) -> u32 {
    return u32(clamp(i32(floor((x - o) / u.cell_size)), 0, i32(n) - 1));
}

@compute @workgroup_size(4, 4, 4)
fn main(@builtin(global_invocation_id) g: vec3<u32>) {
    let i0 = g.x * RUN;
    let base = i0 + u.dims.x * (g.y + u.dims.y * g.z);
    gather(i0, g.y, g.z, base, base);
}

@compute @workgroup_size(64)
fn bricks(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let a = wg.x + wg.y * nwg.x;
    if (a >= active_bricks[0]) {
        return;
    }
    let b = active_bricks[1u + a];
    let bx = b % u.brick_dims.x;
    let by = (b / u.brick_dims.x) % u.brick_dims.y;
    let bz = b / (u.brick_dims.x * u.brick_dims.y);
    // Bricks outside this slab's density layers belong to another slab's pass.
    let bz0 = u.dens_z0 / BRICK;
    let bz1 = (u.dens_z0 + u.dens_layers - 1u) / BRICK;
    if (bz < bz0 || bz > bz1) {
        return;
    }
    // The list index a is the brick's slot; slots count from the slab's first brick layer.
    let table = u.brick_dims.x * u.brick_dims.y * u.brick_dims.z;
    let first = density[bz0 * u.brick_dims.x * u.brick_dims.y] & 0x7fffffffu;
    let slot = a - first;
    var capacity = (arrayLength(&density) - table) / (BRICK * BRICK * BRICK);
    if (WITH_COLOUR) {
        capacity = min(capacity, arrayLength(&colour) / (3u * BRICK * BRICK * BRICK));
    }
    if (lid == 0u) {
        atomicMax(&counters[C_BRICK_SLOTS], slot + 1u);
    }
    if (slot >= capacity) {
        if (lid == 0u) {
            atomicOr(&counters[C_OVERFLOW], OVERFLOW_BRICKS);
        }
        return;
    }
    let ly = lid % BRICK;
    let lz = lid / BRICK;
    let j = by * BRICK + ly;
    let k = bz * BRICK + lz;
    if (k < u.dens_z0) {
        return;
    }
    let c = slot * (BRICK * BRICK * BRICK) + BRICK * (ly + BRICK * lz);
    gather(bx * BRICK, j, k - u.dens_z0, table + c, c);
}

// RUN voxels from (i0, j, dens_z0 + kl) along x, into density words dbase.. and colour
// samples cbase..; nothing outside the slab.
fn gather(i0: u32, j: u32, kl: u32, dbase: u32, cbase: u32) {
    if (i0 >= u.dims.x || j >= u.dims.y || kl >= u.dens_layers) {
        return;
    }
    let k = u.dens_z0 + kl;
    let y = u.origin.y + u.spacing * f32(j);
    let z = u.origin.z + u.spacing * f32(k);
    var xs: array<f32, RUN>;
    var dens: array<f32, RUN>;
    var col: array<vec3<f32>, RUN>;
    for (var m = 0u; m < RUN; m++) {
        xs[m] = u.origin.x + u.spacing * f32(i0 + m);
        dens[m] = 0.0;
        col[m] = vec3<f32>(0.0);
    }
    // A little slack so that rounding in floor() never drops a cell holding an atom in reach.
    let reach = u.max_cut * 1.0001 + 1e-4;
    let cx0 = cell_coord(xs[0] - reach, u.cell_origin.x, u.cell_dims.x);
    let cx1 = cell_coord(xs[RUN - 1u] + reach, u.cell_origin.x, u.cell_dims.x);
    let cy0 = cell_coord(y - reach, u.cell_origin.y, u.cell_dims.y);
    let cy1 = cell_coord(y + reach, u.cell_origin.y, u.cell_dims.y);
    let cz0 = cell_coord(z - reach, u.cell_origin.z, u.cell_dims.z);
    let cz1 = cell_coord(z + reach, u.cell_origin.z, u.cell_dims.z);
    for (var cz = cz0; cz <= cz1; cz++) {
        for (var cy = cy0; cy <= cy1; cy++) {
            // Cells cx0..=cx1 of one row are contiguous in the sorted atom array.
            let row = u.cell_dims.x * (cy + u.cell_dims.y * cz);
            let first = cell_start[row + cx0];
            let last = cell_end[row + cx1];
            for (var s = first; s < last; s++) {
                let a = sorted_atoms[s];
                let dy = y - a.y;
                let dz = z - a.z;
                let dy2 = dy * dy;
                let dz2 = dz * dz;
                let c = u.cutoff * a.w;
                let cut2 = c * c;
                // dx^2 >= 0, so no voxel of the run can pass when this fails (rounding is monotone).
                if (dy2 + dz2 >= cut2) {
                    continue;
                }
                let scale = -1.0 / (2.0 * a.w * a.w);
                var rgb = vec3<f32>(0.0);
                if (WITH_COLOUR) {
                    let pc = sorted_colours[s];
                    rgb = vec3<f32>(unpack2x16unorm(pc.x), unpack2x16unorm(pc.y).x);
                }
                for (var m = 0u; m < RUN; m++) {
                    let dx = xs[m] - a.x;
                    let d2 = dx * dx + dy2 + dz2;
                    if (d2 < cut2) {
                        let w = exp(d2 * scale);
                        dens[m] += w;
                        if (WITH_COLOUR) {
                            col[m] += w * rgb;
                        }
                    }
                }
            }
        }
    }
    for (var m = 0u; m < RUN; m++) {
        if (i0 + m < u.dims.x) {
            if (WRITE_DENSITY) {
                density[dbase + m] = bitcast<u32>(dens[m]);
            }
            if (WITH_COLOUR) {
                // Unnormalised sum of w * colour; emit.wgsl divides by I (so an I change
                // re-runs only Marching Cubes).
                let c = col[m];
                colour[3u * (cbase + m)] = c.x;
                colour[3u * (cbase + m) + 1u] = c.y;
                colour[3u * (cbase + m) + 2u] = c.z;
            }
        }
    }
}
