//! The GPU engine's steady state allocates nothing: over several frames of a real trajectory
//! (AdK, 3341 atoms, H = 2 Å) every frame after the first creates no buffer, bind group,
//! texture or query set, whether the grid runs in one pass or is forced through slabs, on the
//! blocking path (`compute`, mesh read back) and the viewer's non-blocking one (`submit` +
//! `poll_stats`). Also: the binding tables of `gpu::layout` agree with the WGSL (no GPU needed).

use crate::data_support::data;
use crate::gpu_support::*;
use mdsurf::gpu::engine::EngineOptions;
use mdsurf::gpu::{Changes, GpuEngine, GpuObjects};
use mdsurf::surface::{SurfaceEngine, SurfaceParams};

const FRAMES: usize = 5;

/// The first `FRAMES` frames of AdK (positions from the DCD, radii and colours by element).
fn adk_frames() -> Vec<Atoms> {
    let base = load_pdb("adk_open.pdb");
    let traj =
        mdsurf::io::open(&data("adk_open.pdb"), Some(&data("adk_dims.dcd"))).expect("open AdK");
    assert!(traj.len() >= FRAMES, "only {} frames", traj.len());
    (0..FRAMES)
        .map(|i| {
            let positions = traj.read_frame(i).expect("frame").positions;
            assert_eq!(positions.len(), base.positions.len());
            Atoms {
                positions,
                ..base.clone()
            }
        })
        .collect()
}

fn params() -> SurfaceParams {
    SurfaceParams {
        spacing: 2.0,
        ..Default::default()
    }
}

fn engine_with(max_slab_layers: Option<u32>) -> Option<GpuEngine> {
    let mut engine = engine()?;
    let opts = EngineOptions {
        max_slab_layers,
        ..engine.options()
    };
    engine.set_options(opts);
    Some(engine)
}

/// Computes every frame through `compute` (blocking, mesh read back) and returns the objects
/// created after the first frame, and the slab count of the last frame.
fn blocking_run(engine: &mut GpuEngine, frames: &[Atoms]) -> (GpuObjects, usize) {
    let p = params();
    let mut after_first = None;
    for (i, atoms) in frames.iter().enumerate() {
        let out = engine
            .compute(&atoms.set(), &p)
            .unwrap_or_else(|e| panic!("frame {i}: {e}"));
        assert!(
            out.mesh.triangle_count() > 1000,
            "frame {i}: too few triangles"
        );
        assert!(out.mesh.is_closed(), "frame {i}: mesh not closed");
        if i == 0 {
            after_first = Some(engine.objects_created());
        }
    }
    let slabs = engine.last_frame().map(|f| f.slabs).unwrap_or(0);
    (
        engine.objects_created() - after_first.expect("a frame"),
        slabs,
    )
}

#[test]
fn one_pass_frames_create_no_gpu_objects() {
    let Some(mut engine) = engine_with(None) else {
        return;
    };
    let frames = adk_frames();
    let (created, slabs) = blocking_run(&mut engine, &frames);
    assert_eq!(slabs, 1);
    assert_eq!(
        created,
        GpuObjects::default(),
        "frames 2..{FRAMES} created GPU objects"
    );

    // The counter does see growth: twice the atoms in a longer box replace buffers and the
    // bind groups that bound them (the mesh buffers may grow once more on the next frame, when
    // the counters say the mesh came close to filling them); then the same frame creates
    // nothing.
    let mut twice = frames[0].clone();
    let shift = glam::Vec3::new(60.0, 0.0, 0.0);
    twice
        .positions
        .extend(frames[0].positions.iter().map(|p| *p + shift));
    twice.radii.extend_from_within(..);
    if let Some(c) = twice.colours.as_mut() {
        c.extend_from_within(..);
    }
    let before = engine.objects_created();
    engine.compute(&twice.set(), &params()).expect("two copies");
    let grown = engine.objects_created() - before;
    assert!(grown.buffers > 0 && grown.bind_groups > 0, "{grown:?}");
    engine
        .compute(&twice.set(), &params())
        .expect("two copies again");
    let before = engine.objects_created();
    engine
        .compute(&twice.set(), &params())
        .expect("two copies, settled");
    assert_eq!(engine.objects_created() - before, GpuObjects::default());
}

#[test]
fn slabbed_frames_create_no_gpu_objects() {
    let Some(mut engine) = engine_with(Some(4)) else {
        return;
    };
    let frames = adk_frames();
    let (created, slabs) = blocking_run(&mut engine, &frames);
    assert!(slabs >= 4, "only {slabs} slabs");
    assert_eq!(
        created,
        GpuObjects::default(),
        "frames 2..{FRAMES} through {slabs} slabs created GPU objects"
    );
}

/// The viewer's path: submit, poll until the counters arrive, draw from `surface()`.
#[test]
fn submitted_frames_create_no_gpu_objects() {
    let Some(mut engine) = engine_with(None) else {
        return;
    };
    let frames = adk_frames();
    let p = params();
    let mut after_first = None;
    for (i, atoms) in frames.iter().enumerate() {
        let changes = Changes {
            positions: true,
            ..Default::default()
        };
        let info = engine
            .submit(&atoms.set(), &p, changes)
            .unwrap_or_else(|e| panic!("frame {i}: {e}"));
        let stats = loop {
            engine.context().wait().expect("wait");
            if let Some(s) = engine.poll_stats().expect("poll")
                && s.frame >= info.frame
            {
                break s;
            }
        };
        assert!(!stats.overflow && stats.triangle_count > 1000, "{stats:?}");
        if i == 0 {
            after_first = Some(engine.objects_created());
        }
    }
    let created = engine.objects_created() - after_first.expect("a frame");
    assert_eq!(created, GpuObjects::default());
}

/// The binding numbers named in `gpu::layout` are the ones the WGSL declares.
#[test]
fn binding_tables_match_the_wgsl() {
    if let Err(e) = mdsurf::gpu::layout::check_against_wgsl() {
        panic!("{e}");
    }
}
