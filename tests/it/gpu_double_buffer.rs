//! Double-buffered GPU outputs: the [`mdsurf::gpu::GpuSurface`] of frame A (the one the
//! renderer draws) still holds A's mesh after frame B was computed, frames alternate between two
//! output sets, an overflowed frame's rerun writes the same set again (never the one on
//! screen), a set the caller holds is never written while it is held, and a surface's counters
//! belong to its own frame.

use crate::gpu_support::*;
use mdsurf::gpu::engine::EngineOptions;
use mdsurf::gpu::output::read_mesh;
use mdsurf::gpu::{Changes, FrameStats, GpuEngine, GpuSurface};
use mdsurf::surface::{Mesh, SurfaceParams};

fn params() -> SurfaceParams {
    SurfaceParams {
        spacing: 0.7,
        ..Default::default()
    }
}

/// Two different small systems: a jittered blob, and the same blob twice, side by side.
fn systems() -> (Atoms, Atoms) {
    let base = load_pdb("1hpv.pdb");
    let n = base.positions.len().min(120);
    let a = Atoms {
        positions: base.positions[..n].to_vec(),
        radii: base.radii[..n].to_vec(),
        colours: base.colours.as_ref().map(|c| c[..n].to_vec()),
    };
    let mut b = jitter(&a, 5, 0.4);
    let shift = glam::Vec3::new(25.0, 0.0, 0.0);
    b.positions.extend(a.positions.iter().map(|p| *p + shift));
    b.radii.extend_from_within(..);
    if let Some(c) = b.colours.as_mut() {
        c.extend_from_within(..);
    }
    (a, b)
}

fn mesh_of(engine: &GpuEngine, surface: &GpuSurface, stats: &FrameStats) -> Mesh {
    let ctx = engine.context();
    read_mesh(
        &ctx.device,
        &ctx.queue,
        surface,
        stats.vertex_count,
        stats.triangle_count,
    )
    .expect("read mesh")
}

/// Runs one frame to completion (rerunning after overflows) and returns its surface, counters
/// and the output set of every submit it took.
fn frame(engine: &mut GpuEngine, atoms: &Atoms) -> (GpuSurface, FrameStats, Vec<usize>) {
    let mut sets = Vec::new();
    let mut changes = Changes::ALL;
    for _ in 0..4 {
        let info = engine
            .submit(&atoms.set(), &params(), changes)
            .expect("submit");
        sets.push(engine.output_set());
        let stats = loop {
            engine.context().wait().expect("wait");
            if let Some(s) = engine.poll_stats().expect("poll")
                && s.frame >= info.frame
            {
                break s;
            }
        };
        assert_eq!(stats.frame, info.frame);
        if !stats.overflow {
            let surface = engine.surface();
            assert_eq!(surface.stats, Some(stats), "the surface's own counters");
            return (surface, stats, sets);
        }
        changes = Changes::default();
    }
    panic!("kept overflowing");
}

#[test]
fn frame_a_survives_frame_b() {
    let Some(mut engine) = engine() else { return };
    let (a, b) = systems();
    let (surface_a, stats_a, sets_a) = frame(&mut engine, &a);
    let mesh_a = mesh_of(&engine, &surface_a, &stats_a);
    assert!(mesh_a.triangle_count() > 100 && mesh_a.is_closed());

    let (surface_b, stats_b, sets_b) = frame(&mut engine, &b);
    assert_ne!(sets_a.last(), sets_b.last(), "B must write the other set");
    assert!(
        stats_b.triangle_count > stats_a.triangle_count,
        "B (two copies) must be larger"
    );
    assert_ne!(surface_a.vertices, surface_b.vertices);
    assert_ne!(surface_a.draw_args, surface_b.draw_args);
    assert_eq!(
        mesh_of(&engine, &surface_a, &stats_a),
        mesh_a,
        "frame B overwrote frame A's buffers"
    );
    // A surface fetched after B carries B's counters, never A's.
    assert_eq!(engine.surface().stats, Some(stats_b));

    // A third frame writes A's set again, and leaves B's mesh alone.
    let mesh_b = mesh_of(&engine, &surface_b, &stats_b);
    let (_, _, sets_c) = frame(&mut engine, &a);
    assert_eq!(sets_c.last(), sets_a.last());
    assert_eq!(mesh_of(&engine, &surface_b, &stats_b), mesh_b);
}

#[test]
fn an_overflow_rerun_keeps_the_set_on_screen() {
    let Some(mut engine) = engine() else { return };
    // Tiny buffers and no headroom: A overflows once, and B (twice the atoms) overflows the
    // buffers grown for A.
    let opts = EngineOptions {
        initial_mesh_capacity: Some((16, 16)),
        headroom: 1.0,
        ..engine.options()
    };
    engine.set_options(opts);
    let (a, b) = systems();
    let (surface_a, stats_a, sets_a) = frame(&mut engine, &a);
    assert!(sets_a.len() > 1, "A must overflow first");
    assert!(
        sets_a.iter().all(|&s| s == sets_a[0]),
        "A's rerun: {sets_a:?}"
    );
    let mesh_a = mesh_of(&engine, &surface_a, &stats_a);
    let (surface_b, stats_b, sets_b) = frame(&mut engine, &b);
    assert!(sets_b.len() > 1, "B must overflow first");
    assert!(
        sets_b.iter().all(|&s| s != sets_a[0]),
        "an overflow rerun wrote the set on screen: A {sets_a:?}, B {sets_b:?}"
    );
    assert_eq!(mesh_of(&engine, &surface_a, &stats_a), mesh_a);
    assert!(mesh_of(&engine, &surface_b, &stats_b).is_closed());
}

/// The viewer holds the set it shows; a frame in between that is never shown (it failed, or was
/// dropped) must not make the next frame write the held set, as plain alternation would.
#[test]
fn a_held_set_survives_a_frame_that_was_never_shown() {
    let Some(mut engine) = engine() else { return };
    let (a, b) = systems();
    let (surface_a, stats_a, sets_a) = frame(&mut engine, &a);
    engine.hold_output_set();
    let mesh_a = mesh_of(&engine, &surface_a, &stats_a);

    // B is computed but never shown (no hold), then C comes.
    let (_, _, sets_b) = frame(&mut engine, &b);
    assert_ne!(sets_b.last(), sets_a.last());
    let (surface_c, stats_c, sets_c) = frame(&mut engine, &b);
    assert_ne!(
        sets_c.last(),
        sets_a.last(),
        "C wrote the held set (plain alternation would)"
    );
    assert_eq!(
        mesh_of(&engine, &surface_a, &stats_a),
        mesh_a,
        "the held set's mesh changed"
    );
    assert!(mesh_of(&engine, &surface_c, &stats_c).is_closed());

    // Once C is held, the next frame alternates back into A's old set.
    engine.hold_output_set();
    let (_, _, sets_d) = frame(&mut engine, &a);
    assert_eq!(sets_d.last(), sets_a.last());
}
