//! Unit tests of the frame plan: slabs, cells, bricks, buffer sizes and mesh growth.

use super::*;
use glam::Vec3;

fn grid(dims: [u32; 3]) -> GridSpec {
    GridSpec {
        origin: Vec3::ZERO,
        spacing: 1.0,
        dims,
    }
}

#[test]
fn slabs_tile_the_grid_with_overlap() {
    let p = SurfaceParams::default();
    let plan = plan_frame(grid([10, 10, 23]), &p, 1.5, 1 << 30, 1 << 30, Some(5)).unwrap();
    assert_eq!(plan.slabs.len(), 5);
    let mut next = 0;
    for s in &plan.slabs {
        assert_eq!(s.own_z0, next);
        next = s.own_z1;
        assert!(s.dens_z0 + 1 >= s.own_z0 && s.dens_z0 <= s.own_z0);
        assert!(s.dens_z0 + s.dens_layers >= (s.own_z1 + 2).min(23));
        assert!(s.dens_layers <= plan.dens_layers);
    }
    assert_eq!(next, 23);
    assert_eq!(plan.class_layers, 6);
}

#[test]
fn binding_limit_forces_slabs() {
    let p = SurfaceParams::default();
    let layer_bytes = 12 * 100 * 100;
    let plan = plan_frame(
        grid([100, 100, 100]),
        &p,
        1.5,
        20 * layer_bytes,
        1 << 40,
        None,
    )
    .unwrap();
    assert!(plan.slabs.len() > 1);
    assert!(plan.slab_voxels() * 12 <= 20 * layer_bytes);
    let one = plan_frame(grid([100, 100, 100]), &p, 1.5, 1 << 40, 1 << 40, None).unwrap();
    assert_eq!(one.slabs.len(), 1);
    assert_eq!(one.slabs[0].dens_layers, 100);
    assert_eq!(one.brick_dims, [13, 13, 13]);
    assert_eq!(one.brick_count(), 13 * 13 * 13);
}

#[test]
fn cells_cover_the_cutoff() {
    let p = SurfaceParams::default();
    let plan = plan_frame(grid([50, 40, 30]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
    assert!(plan.cell_size >= plan.max_cut);
    for a in 0..3 {
        assert!(plan.cell_dims[a] as f32 * plan.cell_size >= (plan.grid.dims[a] - 1) as f32);
    }
}

#[test]
fn reached_bricks_are_counted_per_layer_from_the_slot_table() {
    let p = SurfaceParams::default();
    // 3 x 2 x 2 bricks.
    let plan = plan_frame(grid([20, 10, 12]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
    assert_eq!(plan.brick_dims, [3, 2, 2]);
    const UNREACHED: u32 = SlotTable::UNREACHED;
    // Layer 0 reaches bricks 1, 2 and 4; layer 1 brick 9 only.
    let reached = [1, 2, 4, 9];
    let mut slot = 0;
    let table: Vec<u32> = (0..12)
        .map(|b| {
            let t = if reached.contains(&b) {
                slot
            } else {
                slot | UNREACHED
            };
            slot += u32::from(reached.contains(&b));
            t
        })
        .collect();
    let counted = SlotTable::new(&plan, &table).reached();
    assert_eq!(counted.layers, vec![3, 1]);
    assert_eq!(counted.total(), 4);
    // One slab holds both layers; the slots hold the need with room, in blocks of 64.
    assert_eq!(counted.slab_need(&plan), 4);
    assert_eq!(settled_brick_slots(&plan, 4, 1 << 30), 64);
}

#[test]
fn class_entries_move_to_brick_slots_only_when_that_takes_fewer() {
    let p = SurfaceParams::default();
    let plan = plan_frame(grid([64, 64, 64]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
    let points = plan.class_points();
    let dense = ClassEntries::for_plan(&plan, None);
    assert_eq!((dense.entries, dense.sparse), (points, false));
    // 64 slots of 729 entries: far fewer than 64^3 points.
    let few = ClassEntries::for_plan(&plan, Some(64));
    assert_eq!(
        (few.entries, few.sparse),
        (64 * CLASS_ENTRIES_PER_SLOT, true)
    );
    // Every brick reached: the slots' entries (9^3 per 8^3 points) would take more.
    let all = ClassEntries::for_plan(&plan, Some(plan.brick_count()));
    assert_eq!((all.entries, all.sparse), (points, false));
    let limits = DeviceLimits::NVIDIA_80GB;
    let mesh = MeshCapacity::default();
    let sizes = BufferPlan::new(&plan, 100, false, mesh, Some(64), &limits);
    assert_eq!(sizes.classes.bytes, 64 * CLASS_ENTRIES_PER_SLOT * 4);
    assert_eq!(sizes.active.bytes, 64 * CLASS_ENTRIES_PER_SLOT * 8);
    assert_eq!(sizes.class_entries, few);
}

#[test]
fn fresh_buffers_round_like_wgpu_and_start_at_16_bytes() {
    assert_eq!(Need::exact(0).fresh(), 16);
    assert_eq!(Need::exact(10).fresh(), 16);
    assert_eq!(Need::exact(18).fresh(), 20);
    let slack = Need::slack(800, 1 << 30);
    assert_eq!(
        (slack.bytes, slack.replace_with, slack.fresh()),
        (800, 900, 900)
    );
    // The slack never passes the largest binding, nor drops below the need.
    assert_eq!(Need::slack(800, 850).replace_with, 850);
    assert_eq!(Need::slack(800, 100).replace_with, 800);
}

#[test]
fn mesh_grows_past_90_percent_and_then_holds() {
    let plan = plan_frame(
        grid([40, 40, 40]),
        &SurfaceParams::default(),
        1.5,
        1 << 30,
        1 << 30,
        None,
    )
    .unwrap();
    let first = first_mesh_want(&plan);
    let big = 1 << 40;
    // Counts well under the first guess keep it.
    let calm = MeshCapacity::settled(first, (first.0 / 2, first.1 / 2), 1.25, big);
    assert_eq!((calm.vertices, calm.triangles), first);
    // A triangle count past 90 % grows the triangles only, to hold the count with room.
    let t = first.1 * 95 / 100;
    let grown = MeshCapacity::settled(first, (10, t), 1.25, big);
    assert_eq!(grown.vertices, first.0);
    assert!(grown.triangles > t && grown.triangles as f64 > t as f64 / 0.9);
    assert!(grown_mesh_want(t, grown.triangles, 1.25).is_none());
    // Never past the largest binding.
    let small = 1 << 20;
    let clipped = MeshCapacity::settled(first, (u32::MAX as u64, u32::MAX as u64), 1.25, small);
    assert_eq!(clipped, MeshCapacity::largest(small));
    assert!(clipped.vertices * BYTES_PER_VERTEX <= small);
    assert!(clipped.triangles * BYTES_PER_TRIANGLE <= small);
}

#[test]
fn buffer_plan_adds_up_per_atom_and_per_mesh_element() {
    let limits = DeviceLimits::NVIDIA_80GB;
    let plan = plan_frame(
        grid([60, 50, 40]),
        &SurfaceParams::default(),
        1.5,
        limits.max_binding(),
        limits.volume_budget(),
        None,
    )
    .unwrap();
    let mesh = MeshCapacity {
        vertices: 1000,
        triangles: 2000,
    };
    let m = |atoms, mesh| BufferPlan::new(&plan, atoms, true, mesh, None, &limits).fresh_memory();
    let (a, b) = (m(10_000, mesh), m(11_000, mesh));
    assert_eq!(b.atoms - a.atoms, 1000 * BYTES_PER_ATOM);
    assert_eq!(b.total() - a.total(), 1000 * BYTES_PER_ATOM);
    let more = MeshCapacity {
        vertices: 1100,
        triangles: 2100,
    };
    let c = m(10_000, more);
    let per_set = 100 * BYTES_PER_VERTEX + 100 * BYTES_PER_TRIANGLE;
    assert_eq!(
        c.mesh - a.mesh,
        crate::gpu::resources::OUTPUT_SETS as u64 * per_set
    );
    // Without colours the colour volume stays at its initial 16 bytes.
    let grey = BufferPlan::new(&plan, 10_000, false, mesh, None, &limits).fresh_memory();
    assert_eq!(
        a.volumes - grey.volumes,
        with_slack(plan.slab_voxels() * 12, limits.max_binding()) - 16
    );
}
