//! The desktop viewer (eframe): the top of the data flow. It reads frames through a
//! [`source::FrameSource`] (files through the io module's prefetching reader), computes surfaces on a [`worker::Worker`] thread with a surface
//! engine, and draws them with [`crate::render`]. UI functions end in `_ui` and return
//! [`state::Command`]s, applied in one place ([`state::AppCore::apply`] and the window layer in
//! [`viewer::Viewer`]). Nothing below this module imports it.

pub mod cavity_panel;
pub(crate) mod command;
pub mod console;
mod console_command;
pub(crate) mod console_complete;
pub(crate) mod console_ui;
pub mod device_loss;
pub mod export;
pub mod headless_script;
pub mod interface_panel;
pub mod keys;
pub mod membrane_view;
pub mod offscreen;
pub mod panels;
pub(crate) mod plot;
pub(crate) mod recent;
pub(crate) mod script_error;
pub mod settings_store;
pub mod simulation_panel;
pub mod source;
pub mod state;
pub mod timeline;
pub mod trajectory_panel;
pub(crate) mod view_renderer;
pub(crate) mod view_state;
pub(crate) mod viewer;
pub mod viewport;
pub mod worker;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

pub use state::{AppCore, Command};
pub use viewer::{Script, Viewer};

/// Bundled demo: topology of the rhodopsin (PDB 1U19) trajectory in assets/.
pub const DEMO_TOP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/md_1u19.gro");
/// Bundled demo trajectory.
pub const DEMO_TRAJ: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/md_1u19.xtc");

/// How the window starts.
#[derive(Debug, Clone, Default)]
pub struct ViewOptions {
    /// Files to open (`None`: the bundled demo).
    pub files: Option<(PathBuf, Option<PathBuf>)>,
    /// Scripted run.
    pub script: Script,
    /// Which surface engine computes (default: [`Backend::Auto`]).
    pub backend: Backend,
    /// Initial surface parameters.
    pub params: crate::surface::SurfaceParams,
    /// Initial vertex placement of the surfaces (`--vertices`).
    pub vertices: crate::surface::VertexMode,
    /// Initial radius set of the surfaces (`ses` with `--preset ses`).
    pub radii: crate::surface::RadiusSet,
    /// Initial particle options (beads, colours, radius overrides).
    pub particles: crate::model::ParticleOptions,
    /// Initial look (the viewer's command line sets the stereo fields).
    pub render: crate::render::RenderSettings,
    /// Representations to start with (`--state`, `--select`); `None`: each file's defaults.
    pub reps: Option<Vec<crate::scene::representation::Representation>>,
    /// Camera to start with (`--state`); `None`: fitted to the data.
    pub camera: Option<crate::scene::state_file::CameraState>,
    /// Per-frame transformations (whole, centre, fit, smooth) of the frames shown.
    pub transforms: crate::transform::TransformOptions,
    /// Frames from a running simulation (`--imd`) or a file being written (`--follow`); the
    /// structure file of `files` holds the atoms.
    pub live: Option<crate::io::LiveSource>,
}

/// Which surface engine the window uses: [`Backend::Gpu`] uses the GPU engine on the window's
/// device even on a software adapter (lavapipe), [`Backend::Auto`] only on a hardware one (the
/// rule lives in [`crate::gpu::pick_engine`]).
pub use crate::gpu::Backend;

/// Why the window could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No display to open a window on.
    #[error(
        "cannot open a window: {0}; use `mdsurf render TOP [TRAJ] -o out.png` to make pictures without a display"
    )]
    NoDisplay(String),
    /// No GPU adapter at all, not even a software one: the window (and `render`) need one.
    #[error("cannot open a window: no GPU adapter: {reason} ({hint})", hint = crate::gpu::SOFTWARE_ADAPTER)]
    NoAdapter {
        /// What each backend that was tried said.
        reason: String,
    },
    /// The scripted run failed.
    #[error("scripted run failed: {0}")]
    Script(String),
    /// The GPU device kept getting lost.
    #[error("the GPU device was lost ({0}); giving up")]
    DeviceLost(String),
}

/// The surface engine for the window: the GPU engine on eframe's own wgpu device (so no second
/// device is opened, and the renderer draws the engine's buffers in place), else the CPU
/// reference engine, as [`crate::gpu::pick_engine`] decides for `backend`. When the GPU engine
/// cannot start, the CPU engine takes over with a note on stderr.
fn make_engine(state: Option<&egui_wgpu::RenderState>, backend: Backend) -> worker::Engine {
    let cpu = || worker::Engine::Host(Box::new(crate::surface::CpuEngine::new()));
    let Some(s) = state.filter(|_| backend != Backend::Cpu) else {
        if backend == Backend::Gpu {
            eprintln!("--backend gpu: the window has no wgpu device; using the CPU engine");
        }
        return cpu();
    };
    let info = s.adapter.get_info();
    let ctx = crate::gpu::GpuContext::from_device(s.device.clone(), s.queue.clone(), String::new())
        .with_adapter(&info);
    match crate::gpu::pick_engine(backend, Some(ctx)) {
        Ok(crate::gpu::Picked::Gpu(engine)) => {
            eprintln!("surface engine: gpu on {}", engine.context().adapter_name);
            worker::Engine::Gpu(engine)
        }
        Ok(crate::gpu::Picked::Cpu { .. }) => cpu(),
        Err(err) => {
            eprintln!("GPU surface engine unavailable ({err}); using the CPU engine");
            cpu()
        }
    }
}

/// eframe's device asks for the limits and features the GPU surface engine needs (the adapter's
/// buffer sizes, 16 storage buffers per stage, timestamps when offered), so the engine and the
/// renderer share one device; its instance opens OpenGL only where nothing else has an adapter
/// ([`crate::gpu::GpuContext::window_backends`]).
fn wgpu_options() -> egui_wgpu::WgpuConfiguration {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = crate::gpu::GpuContext::window_backends();
    setup.power_preference = wgpu::PowerPreference::HighPerformance;
    setup.device_descriptor = Arc::new(|adapter: &wgpu::Adapter| {
        let mut limits = crate::gpu::GpuContext::wanted_limits(&adapter.limits());
        limits.max_texture_dimension_2d = adapter.limits().max_texture_dimension_2d;
        wgpu::DeviceDescriptor {
            label: Some("mdsurf viewer"),
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: limits,
            ..Default::default()
        }
    });
    egui_wgpu::WgpuConfiguration {
        wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup),
        ..Default::default()
    }
}

/// Builds the viewer inside eframe (or an egui_kittest harness): engine, worker, GPU view, and
/// the first load of `top` (+ `traj`).
pub fn create_viewer(
    cc: &eframe::CreationContext<'_>,
    options: &ViewOptions,
    script_result: viewer::ScriptResult,
    top: PathBuf,
    traj: Option<PathBuf>,
    device: (device_loss::DeviceWatch, device_loss::ReopenSlot),
) -> Viewer {
    let state = cc.wgpu_render_state.as_ref();
    let ctx = cc.egui_ctx.clone();
    let worker = worker::Worker::spawn_engine(
        make_engine(state, options.backend),
        Box::new(move || ctx.request_repaint()),
    );
    let mut core = AppCore::new(worker);
    core.base.set_params(&options.params);
    core.base.vertices = options.vertices;
    core.base.radii = options.radii;
    core.base.colour = options.particles.colours;
    if options.particles.beads {
        core.base.style = crate::scene::representation::RepStyle::Beads;
    }
    core.radius_overrides = options.particles.radius_overrides.clone();
    core.render = options.render;
    if let Some(reps) = &options.reps {
        core.set_reps(reps.clone());
        core.keep_reps_on_load = true;
    }
    if let Some(cam) = &options.camera {
        cam.apply(&mut core.camera);
        core.fit_pending = cam.fit;
        core.orient_pending = false;
    }
    let gpu = state.map(viewport::GpuView::new);
    let mut viewer = Viewer::new(core, gpu, options.script.clone(), script_result);
    viewer.set_transforms(options.transforms.clone());
    if let Some(s) = state {
        let ctx = cc.egui_ctx.clone();
        device.0.attach(&s.device, move || ctx.request_repaint());
        viewer.watch_device(device.0, device.1);
    }
    match options.live.clone() {
        Some(live) => viewer.open_live(&cc.egui_ctx, top, live),
        None => viewer.open(&cc.egui_ctx, top, traj),
    }
    viewer
}

/// Opens the viewer window and runs it until it is closed. When the GPU device is lost, the
/// window closes and a new one opens on a new device with the same files and settings (at most
/// [`device_loss::MAX_REOPENS`] times).
pub fn run(options: ViewOptions) -> Result<(), ViewError> {
    if cfg!(target_os = "linux")
        && std::env::var_os("DISPLAY").is_none()
        && std::env::var_os("WAYLAND_DISPLAY").is_none()
    {
        return Err(ViewError::NoDisplay(
            "neither DISPLAY nor WAYLAND_DISPLAY is set".into(),
        ));
    }
    let result: viewer::ScriptResult = Arc::new(Mutex::new(None));
    let watch = device_loss::DeviceWatch::default();
    let session: device_loss::ReopenSlot = Arc::new(Mutex::new(None));
    let outcome = device_loss::run_guarded(&watch, || {
        run_window(&options, result.clone(), (watch.clone(), session.clone()))
    });
    if let Some(reason) = watch.lost_after_poll() {
        return reopen_after_device_loss(&options, &session, &reason);
    }
    // `None` only comes with a lost device, so here the window ended normally.
    outcome.unwrap_or(Ok(()))?;
    match result.lock().ok().and_then(|r| r.clone()) {
        Some(e) => Err(ViewError::Script(e)),
        None => Ok(()),
    }
}

/// Starts mdsurf again on the session the lost window left, and waits for it: a new process
/// has a new event loop and a new device. Gives up after [`device_loss::MAX_REOPENS`].
fn reopen_after_device_loss(
    options: &ViewOptions,
    session: &device_loss::ReopenSlot,
    reason: &str,
) -> Result<(), ViewError> {
    let reopens: usize = std::env::var(device_loss::REOPENS_ENV)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    if reopens >= device_loss::MAX_REOPENS {
        return Err(ViewError::DeviceLost(format!(
            "{} times, last: {reason}",
            reopens + 1
        )));
    }
    let Some(last) = session.lock().ok().and_then(|mut s| s.take()) else {
        return Err(ViewError::DeviceLost(format!(
            "{reason}, before anything was shown"
        )));
    };
    let backend = match options.backend {
        Backend::Cpu => "cpu",
        Backend::Gpu => "gpu",
        Backend::Auto => "auto",
    };
    eprintln!("the GPU device was lost ({reason}); reopening the window on a new device");
    // The representations travel in a state file the new process reads.
    let state_path = std::env::temp_dir().join(format!(
        "mdsurf-reopen-{}-{reopens}.toml",
        std::process::id()
    ));
    let state = crate::scene::state_file::StateFile::new(last.reps.clone());
    let state_arg = state.save(&state_path).ok().map(|()| state_path.as_path());
    let exe = std::env::current_exe().map_err(|e| ViewError::DeviceLost(e.to_string()))?;
    let status = std::process::Command::new(exe)
        .args(device_loss::reopen_args(
            &last,
            backend,
            &options.script,
            state_arg,
        ))
        .env(device_loss::REOPENS_ENV, (reopens + 1).to_string())
        .status()
        .map_err(|e| ViewError::DeviceLost(format!("{reason}; cannot restart mdsurf: {e}")))?;
    if status.success() {
        Ok(())
    } else {
        std::process::exit(status.code().unwrap_or(2))
    }
}

/// One window on one wgpu device, until it closes (by the user, a scripted run, or a lost
/// device, which leaves its state in `reopen`).
fn run_window(
    options: &ViewOptions,
    script_result: viewer::ScriptResult,
    device: (device_loss::DeviceWatch, device_loss::ReopenSlot),
) -> Result<(), ViewError> {
    let (top, traj) = options
        .files
        .clone()
        .unwrap_or_else(|| (PathBuf::from(DEMO_TOP), Some(PathBuf::from(DEMO_TRAJ))));
    let mut native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(settings_store::DEFAULT_SIZE)
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: wgpu_options(),
        ..Default::default()
    };
    let keep = settings_store::Keep::for_run(options.script.quit);
    keep.configure(&mut native);
    let keeps = keep.keeps();
    let options = options.clone();
    let result = eframe::run_native(
        "mdsurf",
        native,
        Box::new(move |cc| {
            let mut viewer = create_viewer(cc, &options, script_result, top, traj, device);
            if keeps {
                viewer.keep_settings(cc.storage, options.reps.is_none());
            }
            Ok(Box::new(viewer))
        }),
    )
    .map_err(window_failure);
    keep.clean_up();
    result
}

/// Why eframe could not open the window. A wgpu failure ("failed to create surface for any
/// enabled backend") with no adapter anywhere is said as such, with the reason each backend
/// gave, rather than as a display problem.
fn window_failure(error: eframe::Error) -> ViewError {
    if matches!(error, eframe::Error::Wgpu(_))
        && let Err(crate::gpu::GpuError::NoAdapter(reason)) = crate::gpu::GpuContext::new_headless()
    {
        return ViewError::NoAdapter { reason };
    }
    ViewError::NoDisplay(error.to_string())
}
