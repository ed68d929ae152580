//! The whole viewer window inside an egui_kittest harness with a wgpu renderer: it loads the
//! bundled demo, computes a surface (CPU engine), and the rendered window shows the panels and a
//! 3D view that is not uniform; then a movie export writes its numbered PNGs. Needs a wgpu adapter; without one it returns early with a note,
//! unless `REQUIRE_GPU=1`.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use mdsurf::app::export::{MoviePlan, VideoPlan};
use mdsurf::app::{Command, DEMO_TOP, DEMO_TRAJ, ViewOptions, Viewer, create_viewer};
use mdsurf::render::RgbaImage;

use crate::cli_common::probe_video;

/// egui_kittest's wgpu set-up on the viewer's backends: its default also opens OpenGL, and on an
/// H100 dropping that instance deadlocked NVIDIA's driver against the GPU tests compiling on
/// other threads (this test and six GPU tests hung; see `GpuContext::window_backends`).
fn harness_wgpu() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_kittest::wgpu::default_wgpu_setup();
    if let egui_wgpu::WgpuSetup::CreateNew(new) = &mut setup {
        new.instance_descriptor.backends = mdsurf::gpu::GpuContext::window_backends();
    }
    setup
}

#[test]
fn window_loads_demo_and_draws_the_surface() {
    if let Err(e) = mdsurf::render::HeadlessGpu::new() {
        if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") {
            panic!("REQUIRE_GPU=1 but {e}");
        }
        eprintln!("note: skipping: {e}");
        return;
    }
    let config = tempfile::tempdir().expect("tempdir");
    // Keep the recent-files list out of the user's config.
    // SAFETY: this test binary has one test, and nothing else reads the environment concurrently.
    unsafe { std::env::set_var("XDG_CONFIG_HOME", config.path()) };
    let options = ViewOptions {
        backend: mdsurf::app::Backend::Cpu,
        ..Default::default()
    };
    let mut h = Harness::builder()
        .with_size([1200.0, 800.0])
        .wgpu_setup(harness_wgpu())
        .build_eframe(|cc| -> Viewer {
            let result = Arc::new(Mutex::new(None));
            create_viewer(
                cc,
                &options,
                result,
                PathBuf::from(DEMO_TOP),
                Some(PathBuf::from(DEMO_TRAJ)),
                Default::default(),
            )
        });
    let start = Instant::now();
    while h.state().core().shown.is_none() && h.state().core().error.is_none() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no surface after 2 minutes"
        );
        std::thread::sleep(Duration::from_millis(50));
        h.step();
    }
    assert!(
        h.state().core().error.is_none(),
        "{:?}",
        h.state().core().error
    );
    h.step();
    h.step();
    let core = h.state().core();
    let shown = &core.shown.as_ref().expect("surface").computed.layers[0];
    // The demo's default representation: its protein (not the retinal or ions).
    let topology = core.source.as_ref().expect("data").topology();
    let placeholder = mdsurf::model::Frame {
        positions: vec![Default::default(); topology.len()],
        ..Default::default()
    };
    let protein = mdsurf::selection::Selection::parse("protein or nucleic")
        .expect("parse")
        .bind(topology)
        .indices(&placeholder)
        .len();
    assert_eq!(shown.rep.name, "macromolecule");
    assert_eq!(shown.particles.positions.len(), protein);
    assert!(protein > 5000, "{protein}");
    assert!(shown.output.mesh.triangle_count() > 1000);
    // Panels and readouts are there.
    h.get_by_label("Play");
    h.get_by_label("Export movie (PNG sequence)");
    assert!(h.query_by_label_contains("triangles (all)").is_some());
    let image = h.render().expect("render the window");
    if let Ok(dir) = std::env::var("MDSURF_SAVE_WINDOW") {
        let _ = image.save(PathBuf::from(dir).join("window.png"));
    }
    // The centre of the window is the 3D view: it must not be one flat colour.
    let (w, hgt) = image.dimensions();
    let mut colours: Vec<[u8; 4]> = (0..40)
        .flat_map(|dy| (0..40).map(move |dx| (w / 2 - 20 + dx, hgt / 2 - 20 + dy)))
        .map(|(x, y)| image.get_pixel(x, y).0)
        .collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 50,
        "3D view looks flat: {} colours",
        colours.len()
    );

    // Movie export: three trajectory frames with a turntable, written as numbered PNGs.
    let movie = config.path().join("movie");
    let plan = MoviePlan {
        frames: Some((0, 2)),
        stride: 1,
        degrees_per_frame: 15.0,
        turntable_frames: 1,
        size: [64, 48],
        dir: movie.clone(),
        video: None,
    };
    run_movie(&mut h, plan.clone());
    let frames: Vec<RgbaImage> = (0..3)
        .map(|i| {
            RgbaImage::read_png(&movie.join(format!("frame_{i:05}.png"))).expect("movie frame")
        })
        .collect();
    assert!(frames.iter().all(|f| (f.width, f.height) == (64, 48)));
    assert_ne!(
        frames[0].pixels, frames[2].pixels,
        "camera and frame should change"
    );
    assert!(!movie.join("frame_00003.png").exists());

    // The same movie as one MP4 file (H.264): ffprobe counts its frames and reads its size.
    let mp4 = config.path().join("movie.mp4");
    run_movie(
        &mut h,
        MoviePlan {
            video: Some(VideoPlan {
                path: mp4.clone(),
                fps: 10.0,
                ..VideoPlan::default()
            }),
            ..plan.clone()
        },
    );
    let text = probe_video(&mp4, "codec_name,width,height,nb_read_frames");
    assert_eq!(text, "h264,64,48,3", "ffprobe: {text}");
    // And as an animated GIF, chosen by the file's name.
    let gif = config.path().join("movie.gif");
    run_movie(
        &mut h,
        MoviePlan {
            video: Some(VideoPlan {
                path: gif.clone(),
                fps: 10.0,
                ..VideoPlan::default()
            }),
            ..plan
        },
    );
    let text = probe_video(&gif, "codec_name,width,height,nb_read_frames");
    assert_eq!(text, "gif,64,48,3", "ffprobe: {text}");
    // No temporary file is left beside it.
    let leftovers: Vec<_> = std::fs::read_dir(config.path())
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Starts the movie export `plan` in the window and steps it until it is done (at most two
/// minutes), with no error.
fn run_movie(h: &mut Harness<'_, Viewer>, plan: MoviePlan) {
    let ctx = h.ctx.clone();
    h.state_mut().command(&ctx, Command::StartMovie(plan));
    let start = Instant::now();
    while h.state().movie_running() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "movie not done after 2 minutes"
        );
        std::thread::sleep(Duration::from_millis(20));
        h.step();
    }
    assert!(
        h.state().core().error.is_none(),
        "{:?}",
        h.state().core().error
    );
}
