// Where a grid point's class word and vertex base live, shared by classify.wgsl, compact.wgsl,
// emit.wgsl and refine.wgsl (each is built after slab_uniform.wgsl and brick_samples.wgsl, see
// src/gpu/shaders.rs). Uses the slab uniform `u` and the density buffer's brick slot table;
// BRICK, CLASS_APRON, SLOT_UNREACHED and NO_ENTRY come from brick_const.wgsl.
//
// Dense classes (bit 1 of u.sparse clear): one entry per point of the slab's class layers,
// x fastest from layer own_z0. Sparse classes (bit 1 set, with sparse bricks): CLASS_APRON^3
// entries per brick slot, counted from the slab's first slot as the density samples are. A
// reached brick holds its own BRICK^3 points at local coordinates 1..=BRICK and, at local 0
// along an axis, the points just below it in an unreached brick: those are the only points of
// an unreached brick whose cell can touch a reached one (crate::gpu::plan::CLASS_ENTRIES_PER_SLOT
// counts the entries; the host twin is crate::gpu::engine's test hook `read_classes`). Every
// point that classify.wgsl does not skip (near_reached_brick) has an entry; the others none.

fn sparse_classes() -> bool {
    return (u.sparse & 2u) != 0u;
}

// On sparse classes, the slot of the slab's first brick layer (slots count from it); 0 on
// dense classes. A thread that looks up several entries reads it once (class_entry_from).
fn class_first_slot() -> u32 {
    if (!sparse_classes()) {
        return 0u;
    }
    return density[(u.dens_z0 / BRICK) * u.brick_dims.x * u.brick_dims.y] & ~SLOT_UNREACHED;
}

// The entry of grid point p (global coordinates, in the slab's class layers), or NO_ENTRY.
fn class_entry(p: vec3<u32>) -> u32 {
    return class_entry_from(p, class_first_slot());
}

// class_entry with the slab's first slot already read (class_first_slot).
fn class_entry_from(p: vec3<u32>, first: u32) -> u32 {
    if (!sparse_classes()) {
        return p.x + u.dims.x * (p.y + u.dims.y * (p.z - u.own_z0));
    }
    let bd = u.brick_dims;
    let b0 = p / BRICK;
    let l = p % BRICK;
    // Along an axis where p is the last sample of its brick, the cell based at p reaches the
    // next brick: that brick may hold p in its apron.
    let up = vec3<u32>(
        select(0u, 1u, l.x == BRICK - 1u && p.x + 1u < u.dims.x),
        select(0u, 1u, l.y == BRICK - 1u && p.y + 1u < u.dims.y),
        select(0u, 1u, l.z == BRICK - 1u && p.z + 1u < u.dims.z),
    );
    for (var dz = 0u; dz <= up.z; dz++) {
        for (var dy = 0u; dy <= up.y; dy++) {
            for (var dx = 0u; dx <= up.x; dx++) {
                let d = vec3<u32>(dx, dy, dz);
                let r = b0 + d;
                let t = density[r.x + bd.x * (r.y + bd.y * r.z)];
                if ((t & SLOT_UNREACHED) == 0u) {
                    // Local 1..=BRICK in its own brick, 0 in the apron of the brick above.
                    let a = l + vec3<u32>(1u) - BRICK * d;
                    return (t - first) * (CLASS_APRON * CLASS_APRON * CLASS_APRON)
                        + a.x + CLASS_APRON * (a.y + CLASS_APRON * a.z);
                }
            }
        }
    }
    return NO_ENTRY;
}

// Grid point of local class point n (x fastest from layer own_z0).
fn class_point(n: u32) -> vec3<u32> {
    let layer = u.dims.x * u.dims.y;
    let r = n % layer;
    return vec3<u32>(r % u.dims.x, r / u.dims.x, u.own_z0 + n / layer);
}
