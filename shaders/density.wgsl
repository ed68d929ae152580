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
// `bricks_tiled` is `bricks` with the atom loads shared by the brick's threads through
// workgroup memory (crate::gpu::DensityGather::Tiled); it writes the same bits.

// SlabUniform (twin of crate::gpu::types::SlabUniform) comes from slab_uniform.wgsl,
// prepended by src/gpu/shaders.rs.
// So are the counter words and overflow bits (C_*, OVERFLOW_*: counters.wgsl) and the brick
// constants (BRICK, SLOT_UNREACHED: brick_const.wgsl).

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
    let brick = brick_at(active_bricks[1u + a]);
    let bx = brick.x;
    let by = brick.y;
    let bz = brick.z;
    // Bricks outside this slab's density layers belong to another slab's pass.
    if (!in_slab(bz)) {
        return;
    }
    // The list index a is the brick's slot; slots count from the slab's first brick layer.
    let table = u.brick_dims.x * u.brick_dims.y * u.brick_dims.z;
    let slot = a - first_slot();
    if (!claim_slot(slot, lid)) {
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

// Atoms staged in workgroup memory by `bricks_tiled`: one chunk of one bin-cell row at a time.
const TILE: u32 = 64u;
var<workgroup> tile_atoms: array<vec4<f32>, TILE>;
var<workgroup> tile_colours: array<vec2<u32>, TILE>;
// The slot of the slab's first brick layer, read once by thread 0 and shared.
var<workgroup> tile_first_slot: u32;

// The sparse gather with its atom loads shared: the 64 threads of a brick visit the bin cells
// around the whole brick together, each chunk of TILE atoms is loaded once into workgroup memory
// and every thread tests it against its own run of RUN voxels. A thread visits the same rows
// in the same order as `gather` does, plus rows out of its own reach whose atoms all fail the
// y/z cutoff test, so every voxel gets the same bits as from `bricks`. All control flow around
// the barriers is uniform over the workgroup (brick id, cell ranges, row bounds).
@compute @workgroup_size(64)
fn bricks_tiled(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let a = wg.x + wg.y * nwg.x;
    if (a >= active_bricks[0]) {
        return;
    }
    let brick = brick_at(active_bricks[1u + a]);
    let bx = brick.x;
    let by = brick.y;
    let bz = brick.z;
    if (!in_slab(bz)) {
        return;
    }
    let table = u.brick_dims.x * u.brick_dims.y * u.brick_dims.z;
    // The first slot comes from a read-write buffer: shared through workgroup memory so the
    // barriers below stay in uniform control flow.
    if (lid == 0u) {
        tile_first_slot = first_slot();
    }
    let slot = a - workgroupUniformLoad(&tile_first_slot);
    if (!claim_slot(slot, lid)) {
        return;
    }
    let ly = lid % BRICK;
    let lz = lid / BRICK;
    let i0 = bx * BRICK;
    let j = by * BRICK + ly;
    let k = bz * BRICK + lz;
    // This thread's run is written only where it lies inside the slab and the grid.
    let own = k >= u.dens_z0 && i0 < u.dims.x && j < u.dims.y && k - u.dens_z0 < u.dens_layers;
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
    // The cells around the whole brick (the same x cells as every thread's own, since all
    // runs of a brick share i0; y and z over the brick's first to last sample).
    let reach = u.max_cut * 1.0001 + 1e-4;
    let ylo = u.origin.y + u.spacing * f32(by * BRICK);
    let yhi = u.origin.y + u.spacing * f32(by * BRICK + BRICK - 1u);
    let zlo = u.origin.z + u.spacing * f32(bz * BRICK);
    let zhi = u.origin.z + u.spacing * f32(bz * BRICK + BRICK - 1u);
    let cx0 = cell_coord(xs[0] - reach, u.cell_origin.x, u.cell_dims.x);
    let cx1 = cell_coord(xs[RUN - 1u] + reach, u.cell_origin.x, u.cell_dims.x);
    let cy0 = cell_coord(ylo - reach, u.cell_origin.y, u.cell_dims.y);
    let cy1 = cell_coord(yhi + reach, u.cell_origin.y, u.cell_dims.y);
    let cz0 = cell_coord(zlo - reach, u.cell_origin.z, u.cell_dims.z);
    let cz1 = cell_coord(zhi + reach, u.cell_origin.z, u.cell_dims.z);
    for (var cz = cz0; cz <= cz1; cz++) {
        for (var cy = cy0; cy <= cy1; cy++) {
            let row = u.cell_dims.x * (cy + u.cell_dims.y * cz);
            let first = cell_start[row + cx0];
            let last = cell_end[row + cx1];
            for (var base = first; base < last; base += TILE) {
                let s = base + lid;
                if (s < last) {
                    tile_atoms[lid] = sorted_atoms[s];
                    if (WITH_COLOUR) {
                        tile_colours[lid] = sorted_colours[s];
                    }
                }
                workgroupBarrier();
                let n = min(TILE, last - base);
                for (var t = 0u; t < n; t++) {
                    let a = tile_atoms[t];
                    let yz = yz_reach(a, y, z);
                    if (yz.x + yz.y >= yz.z) {
                        continue;
                    }
                    add_atom(a, tile_colours[t], yz, &xs, &dens, &col);
                }
                workgroupBarrier();
            }
        }
    }
    if (own) {
        let c = slot * (BRICK * BRICK * BRICK) + BRICK * (ly + BRICK * lz);
        write_run(i0, table + c, c, dens, col);
    }
}

// Brick coordinates of brick id b (x fastest).
fn brick_at(b: u32) -> vec3<u32> {
    return vec3<u32>(
        b % u.brick_dims.x,
        (b / u.brick_dims.x) % u.brick_dims.y,
        b / (u.brick_dims.x * u.brick_dims.y),
    );
}

// True when brick layer bz holds density layers of this slab.
fn in_slab(bz: u32) -> bool {
    let bz0 = u.dens_z0 / BRICK;
    let bz1 = (u.dens_z0 + u.dens_layers - 1u) / BRICK;
    return bz >= bz0 && bz <= bz1;
}

// The slot of the slab's first brick layer (from the slot table at the start of density).
fn first_slot() -> u32 {
    return density[(u.dens_z0 / BRICK) * u.brick_dims.x * u.brick_dims.y] & ~SLOT_UNREACHED;
}

// Records that `slot` is used (thread 0) and whether the buffers hold it; when they do not,
// raises OVERFLOW_BRICKS (thread 0) and returns false.
fn claim_slot(slot: u32, lid: u32) -> bool {
    let table = u.brick_dims.x * u.brick_dims.y * u.brick_dims.z;
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
        return false;
    }
    return true;
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
                let yz = yz_reach(a, y, z);
                // dx^2 >= 0, so no voxel of the run can pass when this fails (rounding is monotone).
                if (yz.x + yz.y >= yz.z) {
                    continue;
                }
                var pc = vec2<u32>(0u);
                if (WITH_COLOUR) {
                    pc = sorted_colours[s];
                }
                add_atom(a, pc, yz, &xs, &dens, &col);
            }
        }
    }
    write_run(i0, dbase, cbase, dens, col);
}

// The y/z part of atom a's squared distance from a run at (y, z) and its squared cutoff:
// (dy^2, dz^2, cut^2) in Å^2 (kept apart so d^2 = dx^2 + dy^2 + dz^2 rounds as the CPU's does).
fn yz_reach(a: vec4<f32>, y: f32, z: f32) -> vec3<f32> {
    let dy = y - a.y;
    let dz = z - a.z;
    let c = u.cutoff * a.w;
    return vec3<f32>(dy * dy, dz * dz, c * c);
}

// Adds atom a (position in Å, alpha in w) with packed colour pc to the RUN voxels at xs along
// x, the y/z part of their distances `yz` from yz_reach.
fn add_atom(
    a: vec4<f32>,
    pc: vec2<u32>,
    yz: vec3<f32>,
    xs: ptr<function, array<f32, RUN>>,
    dens: ptr<function, array<f32, RUN>>,
    col: ptr<function, array<vec3<f32>, RUN>>,
) {
    let scale = -1.0 / (2.0 * a.w * a.w);
    var rgb = vec3<f32>(0.0);
    if (WITH_COLOUR) {
        rgb = vec3<f32>(unpack2x16unorm(pc.x), unpack2x16unorm(pc.y).x);
    }
    for (var m = 0u; m < RUN; m++) {
        let dx = (*xs)[m] - a.x;
        let d2 = dx * dx + yz.x + yz.y;
        if (d2 < yz.z) {
            let w = exp(d2 * scale);
            (*dens)[m] += w;
            if (WITH_COLOUR) {
                (*col)[m] += w * rgb;
            }
        }
    }
}

// Writes one run's sums: density words dbase.. and colour samples cbase.., the voxels inside
// the grid along x only.
fn write_run(
    i0: u32,
    dbase: u32,
    cbase: u32,
    dens: array<f32, RUN>,
    col: array<vec3<f32>, RUN>,
) {
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
