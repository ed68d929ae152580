//! `mdsurf render`: pictures without a window, through the viewer's renderer. Opens the files,
//! computes the surface of each selected frame with the chosen engine, renders it offscreen with
//! `render_to_rgba` (optionally turning the camera per image, or in stereo) and writes PNGs, or
//! one H.264 MP4 movie (`-o movie.mp4`), atomically.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use mdsurf::app::membrane_view::orient_to_layer;
use mdsurf::render::{
    Camera, GpuScene, HeadlessGpu, Projection, RenderSettings, Renderer, bounding_sphere,
    render_to_rgba, write_png,
};
use mdsurf::scene::defaults::{LIPID, MACROMOLECULE};

use mdsurf::export::movie::{Movie, MovieFormat, is_movie};
use mdsurf::export::stats_merge::part_path;
use mdsurf::export::{StatsRow, StatsWriter};
use mdsurf::gpu::{GpuEngine, Picked, SOFTWARE_ADAPTER, pick_engine};
use mdsurf::render::colour_bar::draw_colour_bar;
use mdsurf::scene::cavity_layer::MovieCavityIds;
use mdsurf::scene::movie::Shot;
use mdsurf::scene::representation::Representation;
use mdsurf::scene::state_file::{CameraState, StateFile};
use mdsurf::scene::{LayerResult, SceneBackend, SceneEngine, SceneFrame};

use super::chunk::{Chunk, ChunkSpec};
use super::common::{Backend, System, check_colour_frames, ms_since, set_vertex_mode};
use super::interrupt::{catch_interrupts, interrupted};
pub use super::render_args::{RenderArgs, StereoArgs};
use super::render_output::output_paths;
use super::scene_args::bind_scene;
use super::transform_args::{FrameReader, host_scene};

/// Runs `mdsurf render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let params = args.params.params()?;
    let chunk = args.chunk.map(ChunkSpec::resolve).transpose()?;
    let state = args.scene.load_state()?;
    // A script sets the scene up first; what it leaves stands in for --state.
    let state = match &args.script {
        Some(script) => Some(super::render_script::run(
            &args,
            script,
            state,
            look_flags(&args),
        )?),
        None => state,
    };
    // Without --frame, a script's pictures go on from the frame its last `frame` line chose.
    let mut args = args;
    if args.script.is_some() && args.frame.is_none() {
        args.frame = state.as_ref().map(|s| s.trajectory.frame);
    }
    let transforms = args.transforms.options(state.as_ref());
    let first = args.frames.map_or(args.frame.unwrap_or(0), |r| r.start);
    let live = args.live.options(args.input.traj.as_deref())?;
    if live.is_some() {
        check_live_output(&args)?;
    }
    let (system, _) = System::open_or_follow(&args.input, live.as_ref(), first)?;
    let Images { frames, shots, fps } = images(&args, state.as_ref(), &system)?;
    let movie_out = is_movie(&args.output);
    let paths = output_files(&args, &frames, fps, chunk)?;
    // The images this process writes; the camera is still fitted to the run's first frame.
    if let Some(c) = chunk {
        super::chunk::check_chunk_count(c, frames.len())?;
    }
    let block = chunk.map_or(0..frames.len(), |c| c.block(frames.len()));
    if block.is_empty() {
        eprintln!(
            "chunk {}: no image to render ({} in all)",
            chunk.map(|c| c.to_string()).unwrap_or_default(),
            frames.len()
        );
        return Ok(());
    }
    let mut settings = look_flags(&args);
    let options = args.input.particles.options_for(&system.trajectory)?;
    check_colour_frames(&options, &frames)?;
    let topology = system.trajectory.topology().clone();
    let mut reader = FrameReader::new(&system.trajectory, &transforms)?;
    // A running simulation may have pushed the first frame out already: then the oldest held.
    let (first_index, first_frame) =
        super::live_args::read_held(frames[0], |i| reader.read_frame(i))?;
    let first_frame = Arc::new(first_frame);
    let mut choice = args.scene.representations(
        state,
        &topology,
        &first_frame,
        (&params, args.params.radius_set()),
        &options,
        args.quiet,
    )?;
    if let Some(state) = &choice.state {
        // The state file's look replaces the look flags.
        state
            .look
            .apply(&mut settings)
            .map_err(|e| anyhow!("{e}"))?;
    } else {
        super::render_script::apply_rep_flags(&args, &mut choice.reps, &options);
    }
    args.params
        .apply_to_reps(&mut choice.reps, choice.state.is_some());
    let gpu = HeadlessGpu::new().map_err(|e| anyhow!("{e} ({SOFTWARE_ADAPTER})"))?;
    let renderer = Renderer::new(&gpu.device);
    // The GPU engine computes on the render device and its buffers are drawn in place, as in
    // the window; otherwise the mesh comes back to the host and is uploaded (the CPU engine,
    // or the periodic one: never a second GPU device).
    let mut engine = match in_place_engine(args.backend, &reader, &gpu, args.quiet)? {
        Some(e) => SceneEngine::new(SceneBackend::Gpu(Box::new(e))),
        None => {
            let host = match reader.chain().periodic() {
                Some(_) => args.backend,
                None => Backend::Cpu,
            };
            host_scene(host, reader.chain(), args.quiet)?
        }
    };
    if let SceneBackend::Host(e) = engine.backend_mut() {
        set_vertex_mode(e.as_mut(), args.params.vertex_mode());
    }
    let files = system.frames_path.display().to_string();
    let reps = bind_scene(
        &mut engine,
        &choice.reps,
        &topology,
        &first_frame,
        &options.radius_overrides,
        &files,
    )?;
    if reps.is_empty() {
        bail!("nothing to draw: every representation is hidden");
    }
    choice.print_defaults();
    if args.transforms.any() && !args.quiet {
        reader.print_summary();
    }
    let mut scene = GpuScene::new();
    let mut camera = Camera {
        projection: if args.ortho {
            Projection::Orthographic
        } else {
            Projection::Perspective
        },
        ..Camera::default()
    };
    // The movie is written to a temporary file and renamed at the end: an error (or an early
    // exit) on any frame leaves no movie file.
    let mut movie = if movie_out {
        let quality = args.video_quality.unwrap_or_default();
        Some(Movie::create(
            &paths[0],
            args.size,
            fps,
            quality,
            block.start,
        )?)
    } else {
        None
    };
    let mut stats = args.stats.as_deref().map(StatsWriter::create).transpose()?;
    let mut stats_frame = None;
    catch_interrupts();
    // A line per image with -v; a bar on a terminal; a running simulation has no length.
    let length = live.is_none().then_some(block.len());
    let progress = super::progress::Progress::new(length, args.quiet, args.verbose);
    let started = Instant::now();
    let mut images = 0usize;
    let mut cavity_ids = MovieCavityIds::default();
    // Frames before this one left a running simulation's ring unread (skipped).
    let last = frames.last().copied();
    let (mut resume_at, mut skips) = (0usize, super::live_args::OverrunSkips::up_to(last));
    for (i, &f) in frames.iter().enumerate() {
        if i >= block.end {
            break;
        }
        if i > 0 && i < block.start {
            continue;
        }
        if f < resume_at {
            skips.pass_over();
            continue;
        }
        if interrupted() {
            match &movie {
                Some(m) => bail!(
                    "{}: interrupted after {} of {} frames; no movie written",
                    m.path().display(),
                    m.frames(),
                    frames.len()
                ),
                None => bail!(
                    "interrupted by a signal after {} of {} images (those written are kept)",
                    i.saturating_sub(block.start),
                    block.len()
                ),
            }
        }
        let t0 = Instant::now();
        let frame = if i == 0 && first_index == f {
            first_frame.clone()
        } else {
            match reader.read_frame(f) {
                Ok(frame) => Arc::new(frame),
                Err(e) if let Some(oldest) = skips.skip(&e, args.quiet) => {
                    resume_at = oldest;
                    continue;
                }
                // The end of a running simulation ends the movie; it is not a failure.
                Err(e) => match super::live_args::end_of_stream(&e) {
                    Some(end) => {
                        if !args.quiet {
                            eprintln!("{end}");
                        }
                        break;
                    }
                    None => return Err(e),
                },
            }
        };
        let read_ms = ms_since(t0);
        let mut computed = engine
            .frame(&topology, f, &frame, &reps)
            .map_err(|e| anyhow!("{files}: {e}"))?;
        if block.contains(&i) {
            // Each cavity in its id's colour, ids followed over the images.
            cavity_ids.track(&mut computed);
        }
        // The script's fades: a representation faded out is not drawn.
        let shot = shots.get(i);
        let drawn = faded_layers(&computed.layers, shot);
        scene.show_layers(
            &gpu.device,
            &gpu.queue,
            drawn.iter().map(|(l, rep)| (*l, rep)),
            &settings,
        );
        let summary: Vec<String> = computed
            .surfaces()
            .map(|l| {
                format!(
                    "{}: {} triangles, area {:.1} Å², volume {:.1} Å³",
                    l.rep.name,
                    l.triangle_count(),
                    l.output.area,
                    l.output.volume
                )
            })
            .collect();
        if i == 0 {
            let state_camera = choice.state.as_ref().and_then(|s| s.camera);
            fit_camera(&mut camera, &mut engine, &computed, state_camera, args.view)
                .map_err(|e| anyhow!("{files}: {e}"))?;
        }
        if !block.contains(&i) {
            // Frame 0 of a later chunk: computed only to fit the camera.
            continue;
        }
        let mut cam = camera;
        cam.turn(args.turntable.unwrap_or(0.0) * i as f32);
        if let Some(shot) = shot {
            let c = shot.camera;
            cam.orbit(-c.yaw_deg.to_radians(), c.pitch_deg.to_radians());
            cam.zoom(1.0 / c.zoom);
        }
        let mut image = render_to_rgba(
            &gpu.device,
            &gpu.queue,
            &renderer,
            &scene,
            &cam,
            &settings,
            args.size,
        )?;
        // Data and exposure colours get a colour bar (the first representation so coloured).
        if let Some((map, range)) = reps.iter().find_map(|r| r.rep.colour.colour_bar()) {
            draw_colour_bar(&mut image, map, range);
        }
        if let Some(stats) = stats.as_mut()
            && stats_frame != Some(f)
        {
            // One set of rows per frame (a turntable shows one frame many times).
            for row in StatsRow::of_scene(&computed, read_ms) {
                stats.write_row(&row)?;
            }
            stats_frame = Some(f);
        }
        let path = &paths[i];
        match movie.as_mut() {
            Some(m) => m.push(&image)?,
            None => write_png(path, &image)?,
        }
        images += 1;
        progress.advance();
        progress.line(|| {
            format!(
                "frame {f}: {}; read {read_ms:.1} ms, total {:.1} ms -> {}",
                if summary.is_empty() {
                    "atoms only".to_string()
                } else {
                    summary.join("; ")
                },
                ms_since(t0),
                path.display()
            )
        });
    }
    progress.finish();
    skips.finish(args.quiet);
    if let Some(stats) = stats {
        stats.finish()?;
    }
    if let Some(m) = movie {
        let written = m.path().to_path_buf();
        let s = m.finish()?;
        if args.quiet {
            return Ok(());
        }
        eprintln!(
            "movie: {} frames, {:.2} s at {} frames/s, {:.1} kB -> {}",
            s.frames,
            s.seconds,
            fps,
            s.bytes as f64 / 1000.0,
            written.display()
        );
    } else if progress.shows_summary() {
        let secs = started.elapsed().as_secs_f64();
        eprintln!(
            "{images} image(s) in {secs:.2} s ({:.1} images/s) -> {}",
            images as f64 / secs.max(1e-9),
            args.output.display()
        );
    }
    Ok(())
}

/// The look the command-line flags ask for (a state file's look replaces it).
fn look_flags(args: &RenderArgs) -> RenderSettings {
    let mut settings = RenderSettings {
        background: args.background,
        surface_opacity: args.opacity,
        atom_style: args.atoms,
        stereo: args.stereo,
        eye_separation: args.eyes.eye_separation,
        focal_distance: args.eyes.focal,
        ambient_occlusion: args.ao,
        depth_cue: args.depth_cue,
        ..RenderSettings::default()
    };
    args.look.apply(&mut settings);
    settings
}

/// What `render --imd` can write: a movie of the run (until it ends, or `--frames :N`), or a
/// numbered image sequence of a stated length; one picture of a stream makes no sense.
fn check_live_output(args: &RenderArgs) -> Result<()> {
    if args.chunk.is_some() {
        bail!(
            "--chunk splits a trajectory's frames: a running simulation (--imd) has no fixed frames to split"
        );
    }
    let bounded = args.frames.is_some_and(|r| r.stop.is_some());
    if !is_movie(&args.output) && !bounded {
        bail!(
            "-o {}: with --imd, render a movie (.mp4 or .gif) or say how many images with --frames :N",
            args.output.display()
        );
    }
    Ok(())
}

/// The layers of `layers` as `shot` shows them: a representation the camera script faded
/// takes the faded opacity, and is not drawn at 0.
fn faded_layers<'a>(
    layers: &'a [Arc<LayerResult>],
    shot: Option<&Shot>,
) -> Vec<(&'a LayerResult, Representation)> {
    layers
        .iter()
        .filter_map(|l| {
            let mut rep = l.rep.clone();
            if let Some((_, o)) = shot.and_then(|s| s.opacity.iter().find(|(n, _)| *n == rep.name))
            {
                if *o <= 0.0 {
                    return None;
                }
                rep.opacity = *o;
            }
            Some((l.as_ref(), rep))
        })
        .collect()
}

/// Fits `camera` to the first frame's atoms and surfaces (their meshes read back once when
/// they stayed on the GPU): a membrane is seen from the side, unless the state file's camera
/// (`state_camera`) or `--view` says where to look.
fn fit_camera(
    camera: &mut Camera,
    engine: &mut SceneEngine,
    computed: &SceneFrame,
    state_camera: Option<CameraState>,
    view: Option<[f32; 2]>,
) -> Result<()> {
    let mut points = Vec::new();
    let (mut lipids, mut protein) = (Vec::new(), Vec::new());
    for l in &computed.layers {
        if l.rep.selection == LIPID {
            lipids.extend_from_slice(&l.particles.positions);
        } else if l.rep.selection == MACROMOLECULE {
            protein.extend_from_slice(&l.particles.positions);
        }
        if l.is_surface() {
            let mesh = engine.read_mesh(computed.frame, l)?;
            points.extend_from_slice(&mesh.positions);
        } else {
            points.extend_from_slice(&l.particles.positions);
        }
    }
    let (centre, radius) = bounding_sphere(points.iter()).ok_or_else(|| {
        anyhow!(
            "frame {}: nothing to draw (empty surfaces and no atoms)",
            computed.frame
        )
    })?;
    if state_camera.is_none() && view.is_none() {
        // A membrane is drawn from the side, its normal up (as the window opens it).
        orient_to_layer(camera, &lipids, &protein);
    }
    camera.fit_sphere(centre, radius);
    if let Some(cam) = state_camera {
        cam.apply(camera);
    }
    if let Some([yaw, pitch]) = view {
        camera.yaw = yaw.to_radians();
        camera.pitch = pitch.to_radians();
    }
    Ok(())
}

/// The images of a run: the trajectory frame of each, the camera script's shot of each (empty
/// without a script) and the movie's frame rate.
struct Images {
    frames: Vec<usize>,
    shots: Vec<Shot>,
    fps: f64,
}

/// Which images `args` ask for: `--frames`, one frame, a turntable of it, or the state file's
/// camera script (unless --frames or --turntable choose the images); of a running simulation
/// without --frames, every frame until it ends.
fn images(args: &RenderArgs, state: Option<&StateFile>, system: &System) -> Result<Images> {
    let (len, frames_path) = (system.len(), &system.frames_path);
    let frame = args.frame.unwrap_or(0);
    let mut frames = match args.frames {
        Some(r) => r.indices(len),
        // A running simulation: every frame from --frame on, until the run ends.
        None if system.trajectory.is_live() => (frame..len).collect(),
        None if frame < len => vec![frame],
        None => bail!("{}: no frame {frame} (it has {len})", frames_path.display()),
    };
    if frames.is_empty() {
        bail!(
            "{}: --frames selects no frame (it has {len})",
            frames_path.display()
        );
    }
    if args.frames.is_none() && args.turntable.is_some_and(|d| d != 0.0) {
        let images = (360.0 / args.turntable.unwrap_or(1.0).abs())
            .round()
            .max(1.0) as usize;
        frames = vec![frames[0]; images];
    }
    let script = state
        .and_then(|s| Some((s, s.movie.as_ref()?)))
        .filter(|_| args.frames.is_none() && args.turntable.is_none());
    let shots = match script {
        Some((state, script)) => {
            let opacity = |name: &str| {
                state
                    .representations
                    .iter()
                    .find(|r| r.name == name)
                    .map(|r| r.opacity)
            };
            let shots = script.shots(frame, len, opacity).map_err(|e| {
                let file = args.scene.state.as_deref().unwrap_or(Path::new("state"));
                anyhow!("{}: {e}", file.display())
            })?;
            frames = shots.iter().map(|s| s.frame).collect();
            shots
        }
        None => Vec::new(),
    };
    let fps = args.fps.or(script.map(|(_, s)| s.fps)).unwrap_or(24.0);
    Ok(Images { frames, shots, fps })
}

/// The file of every image (one movie for all when `-o` is a movie; a chunk's movie is its
/// part, `OUT.part-IIII-of-NNNN.mp4` or `.gif`, for `mdsurf merge OUT.mp4`), checked before any
/// work, with the movie's size and frame rate `fps`: a known
/// format, no two images in one file, existing folders, and a `--stats` file that is neither an
/// image nor an input.
fn output_files(
    args: &RenderArgs,
    frames: &[usize],
    fps: f64,
    chunk: Option<Chunk>,
) -> Result<Vec<PathBuf>> {
    let paths = if let Some(format) = MovieFormat::of(&args.output) {
        format.check(&args.output, args.size, fps)?;
        let movie = chunk.map_or_else(
            || args.output.clone(),
            |c| part_path(&args.output, c.index, c.count),
        );
        vec![movie; frames.len()]
    } else {
        if args.fps.is_some() || args.video_quality.is_some() {
            bail!(
                "-o {}: --fps and --video-quality apply to a movie; give the output a .mp4 or .gif name",
                args.output.display()
            );
        }
        output_paths(&args.output, frames)?
    };
    // Like `surface`, a missing output folder is refused before any work (never created).
    if let Some(first) = paths.first() {
        super::surface::check_parent_dir(first)?;
    }
    if let Some(stats) = &args.stats {
        super::surface::check_parent_dir(stats)?;
        if args.chunk.is_some() {
            bail!(
                "--stats {}: a chunk renders part of the frames; run `mdsurf surface --chunk` for their stats",
                stats.display()
            );
        }
        if paths.iter().any(|p| p == stats) {
            bail!(
                "-o {} and --stats {} are the same file: give them different names",
                args.output.display(),
                stats.display()
            );
        }
        let inputs: Vec<PathBuf> = std::iter::once(args.input.top.clone())
            .chain(args.input.traj.clone())
            .collect();
        super::surface::refuse_shared_paths(None, Some(stats), &inputs)?;
    }
    Ok(paths)
}

/// The GPU engine on `gpu`'s device when `backend` picks it and the surfaces are not periodic
/// (the periodic engine runs on the CPU): the engine of the first surface layer.
fn in_place_engine(
    backend: Backend,
    reader: &FrameReader,
    gpu: &HeadlessGpu,
    quiet: bool,
) -> Result<Option<GpuEngine>> {
    if backend == Backend::Cpu || reader.chain().periodic().is_some() {
        return Ok(None);
    }
    let picked = pick_engine(backend.into(), Some(gpu.context.clone()))
        .context("--backend gpu: cannot start the GPU engine")?;
    Ok(match picked {
        Picked::Gpu(e) => {
            if !quiet {
                eprintln!(
                    "backend: gpu ({}), drawn in place",
                    e.context().adapter_name
                );
            }
            Some(*e)
        }
        Picked::Cpu { why } => {
            if let Some(why) = why.filter(|_| !quiet) {
                eprintln!("backend: cpu ({why})");
            }
            None
        }
    })
}
