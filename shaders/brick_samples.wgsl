// Reading density samples, shared by classify.wgsl, compact.wgsl, emit.wgsl and refine.wgsl
// (each is built after the preludes, slab_uniform.wgsl and this file, see src/gpu/shaders.rs).
// It uses two names the stage declares: the slab uniform `u` and its density buffer `density`
// (array<u32>: density words and, on sparse bricks, the brick slot table); BRICK,
// SLOT_UNREACHED and NO_SAMPLE come from brick_const.wgsl.

// The density word of grid point (i, j, k) (global k, within the slab's density layers). Dense:
// the slab volume. Sparse bricks (u.sparse != 0): the first brick_count words are the brick slot
// table (shaders/bricks.wgsl: slot per brick, high bit set when unreached), then BRICK^3
// samples per slot, counted from the slot of the slab's first brick layer
// (shaders/density.wgsl); an unreached brick reads as 0, as the dense pass computes it.
fn dens_at(i: u32, j: u32, k: u32) -> f32 {
    if (u.sparse == 0u) {
        return bitcast<f32>(density[i + u.dims.x * (j + u.dims.y * (k - u.dens_z0))]);
    }
    let s = sample_slot(i, j, k);
    if (s == NO_SAMPLE) {
        return 0.0;
    }
    return bitcast<f32>(density[u.brick_dims.x * u.brick_dims.y * u.brick_dims.z + s]);
}

// On sparse bricks: the brick-local sample index of grid point (i, j, k) (counted from the
// slab's first slot; density word brick_count + index, colour sample index), or NO_SAMPLE
// when no atom reaches its brick.
fn sample_slot(i: u32, j: u32, k: u32) -> u32 {
    let bd = u.brick_dims;
    let t = density[i / BRICK + bd.x * (j / BRICK + bd.y * (k / BRICK))];
    if ((t & SLOT_UNREACHED) != 0u) {
        return NO_SAMPLE;
    }
    let first = density[(u.dens_z0 / BRICK) * bd.x * bd.y] & ~SLOT_UNREACHED;
    let local = i % BRICK + BRICK * (j % BRICK + BRICK * (k % BRICK));
    return (t - first) * (BRICK * BRICK * BRICK) + local;
}
