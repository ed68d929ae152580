//! The viewer's compute worker with the GPU engine ([`Engine::Gpu`]): the reply keeps the mesh on
//! the GPU (empty host mesh, `gpu_surface` set) and its readouts (triangles, area, volume) come
//! from the engine's counters; they must match the CPU engine's within
//! `mdsurf::gpu::tolerance`, frame after frame (positions change, radii and colours do not).
//! A second run starts with mesh buffers far too small: the overflowing frame is resubmitted
//! and the reply still carries the whole surface. Without an adapter the test returns early with a note, unless `REQUIRE_GPU=1`.

use std::sync::Arc;
use std::time::Duration;

use mdsurf::app::source::{FrameSource, helix_source};
use mdsurf::app::worker::{Computed, Engine, Reply, Request, Worker};
use mdsurf::gpu::{GpuEngine, Work, tolerance as tol};
use mdsurf::model::{ColorScheme, ParticleOptions};
use mdsurf::render::HeadlessGpu;
use mdsurf::surface::{CpuEngine, SurfaceParams};

fn require_gpu() -> bool {
    std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1")
}

fn compute(worker: &Worker, source: &Arc<dyn FrameSource>, frame: usize) -> Computed {
    worker.submit(Request::single(
        1,
        frame,
        source.clone(),
        SurfaceParams {
            spacing: 0.5,
            ..SurfaceParams::default()
        },
        ParticleOptions::default(),
    ));
    match worker.recv_timeout(Duration::from_secs(60)) {
        Some(Reply::Done(c)) => *c,
        Some(Reply::Failed { message, .. }) => {
            panic!("{} frame {frame}: {message}", worker.engine_name())
        }
        None => panic!("{} frame {frame}: no reply in 60 s", worker.engine_name()),
    }
}

#[test]
fn gpu_worker_keeps_the_mesh_on_the_gpu_and_reads_out_like_the_cpu() {
    let g = match HeadlessGpu::new() {
        Ok(g) => g,
        Err(e) if require_gpu() => panic!("REQUIRE_GPU=1 but no adapter: {e}"),
        Err(e) => return eprintln!("note: skipping: {e}"),
    };
    for tiny in [false, true] {
        let mut engine = match GpuEngine::try_from_device(g.device.clone(), g.queue.clone()) {
            Ok(e) => e,
            Err(e) if require_gpu() => {
                panic!("REQUIRE_GPU=1 but the GPU engine cannot start: {e}")
            }
            Err(e) => return eprintln!("note: skipping: {e}"),
        };
        if tiny {
            let mut o = engine.options();
            o.initial_mesh_capacity = Some((16, 16));
            engine.set_options(o);
        }
        compare_frames(engine);
    }
}

fn compare_frames(engine: GpuEngine) {
    let gpu = Worker::spawn_engine(Engine::Gpu(Box::new(engine)), Box::new(|| {}));
    let cpu = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    assert_eq!(gpu.engine_name(), "gpu");
    let source: Arc<dyn FrameSource> = Arc::new(helix_source(20, 4));
    for frame in [0, 1, 3, 2] {
        let (a, b) = (compute(&gpu, &source, frame), compute(&cpu, &source, frame));
        assert_eq!(a.frame, frame);
        let surface = a.layers[0]
            .gpu_surface
            .as_ref()
            .expect("GPU reply carries its surface");
        assert!(
            a.layers[0].output.mesh.positions.is_empty(),
            "frame {frame}: the mesh was read back"
        );
        let stats = surface.stats.expect("counters of the frame");
        assert!(!stats.overflow, "frame {frame}: reply after an overflow");
        assert!(b.layers[0].gpu_surface.is_none());
        let (tg, tc) = (a.triangle_count(), b.triangle_count());
        assert!(tc > 100, "frame {frame}: CPU surface has {tc} triangles");
        assert!(
            tol::triangles_close(tg, tc),
            "frame {frame}: {tg} GPU vs {tc} CPU triangles"
        );
        for (what, x, y) in [
            ("area", a.layers[0].output.area, b.layers[0].output.area),
            (
                "volume",
                a.layers[0].output.volume,
                b.layers[0].output.volume,
            ),
        ] {
            assert!(
                tol::rel_close(x, y, tol::AREA_VOLUME_REL),
                "frame {frame}: {what} {x} GPU vs {y} CPU"
            );
        }
        assert_eq!(
            a.layers[0].output.grid, b.layers[0].output.grid,
            "frame {frame}: grid"
        );
    }
}

/// Submits `frame` with `isovalue` and `colours` and waits for the reply.
fn compute_with(
    worker: &Worker,
    source: &Arc<dyn FrameSource>,
    frame: usize,
    isovalue: f32,
    colours: ColorScheme,
) -> Computed {
    worker.submit(Request::single(
        1,
        frame,
        source.clone(),
        SurfaceParams {
            spacing: 0.5,
            isovalue,
            ..SurfaceParams::default()
        },
        ParticleOptions {
            colours,
            ..ParticleOptions::default()
        },
    ));
    match worker.recv_timeout(Duration::from_secs(60)) {
        Some(Reply::Done(c)) => *c,
        Some(Reply::Failed { message, .. }) => panic!("frame {frame}: {message}"),
        None => panic!("frame {frame}: no reply in 60 s"),
    }
}

/// The worker sends the engine only what changed: an isovalue change alone re-runs Marching
/// Cubes, a colour scheme the colour pass, a new frame everything; each surface equals the one
/// a fresh engine computes from scratch.
#[test]
fn gpu_worker_reruns_only_the_stages_a_change_needs() {
    let g = match HeadlessGpu::new() {
        Ok(g) => g,
        Err(e) if require_gpu() => panic!("REQUIRE_GPU=1 but no adapter: {e}"),
        Err(e) => return eprintln!("note: skipping: {e}"),
    };
    let engine = || match GpuEngine::try_from_device(g.device.clone(), g.queue.clone()) {
        Ok(e) => Some(Engine::Gpu(Box::new(e))),
        Err(e) if require_gpu() => panic!("REQUIRE_GPU=1 but the GPU engine cannot start: {e}"),
        Err(e) => {
            eprintln!("note: skipping: {e}");
            None
        }
    };
    let Some(e) = engine() else { return };
    let worker = Worker::spawn_engine(e, Box::new(|| {}));
    let source: Arc<dyn FrameSource> = Arc::new(helix_source(20, 4));
    let (el, ri) = (ColorScheme::Element, ColorScheme::ResidueIndex);
    let steps = [
        (0, 0.5, el, Work::Full, "first frame"),
        (0, 0.3, el, Work::Mc, "isovalue"),
        (0, 0.3, ri, Work::Colour, "colour scheme"),
        (0, 0.7, ri, Work::Mc, "isovalue again"),
        (2, 0.7, ri, Work::Full, "new frame"),
        (2, 0.4, ri, Work::Mc, "isovalue on the new frame"),
    ];
    for (frame, iso, colours, want, what) in steps {
        let a = compute_with(&worker, &source, frame, iso, colours);
        assert_eq!(a.layers[0].gpu_work, Some(want), "{what}: stages that ran");
        let Some(e) = engine() else { return };
        let fresh = Worker::spawn_engine(e, Box::new(|| {}));
        let b = compute_with(&fresh, &source, frame, iso, colours);
        assert_eq!(
            b.layers[0].gpu_work,
            Some(Work::Full),
            "{what}: fresh engine"
        );
        let (ta, tb) = (a.triangle_count(), b.triangle_count());
        assert!(tb > 100, "{what}: fresh surface has {tb} triangles");
        assert_eq!(ta, tb, "{what}: triangles, incremental vs from scratch");
        for (name, x, y) in [
            ("area", a.layers[0].output.area, b.layers[0].output.area),
            (
                "volume",
                a.layers[0].output.volume,
                b.layers[0].output.volume,
            ),
        ] {
            assert!(
                tol::rel_close(x, y, 1e-4),
                "{what}: {name} {x} incremental vs {y} from scratch"
            );
        }
        assert_eq!(
            a.layers[0].output.grid, b.layers[0].output.grid,
            "{what}: grid"
        );
    }
}
