//! The viewer's command line (no subcommand): `mdsurf [TOP [TRAJ]]` opens the window, with the
//! bundled demo when no file is given; `--play-frames N --screenshot FILE --quit` runs a scripted
//! session (used by tests). The window itself lives in `mdsurf::app`.

use std::path::PathBuf;

use anyhow::{Result, bail};
use mdsurf::app::{self, Script, ViewOptions};
use mdsurf::render::{RenderSettings, Stereo};

use mdsurf::scene::representation::{RepStyle, Representation};

use super::common::{Backend, ParamArgs, ParticleArgs};
use super::live_args::LiveArgs;
use super::render::StereoArgs;
use super::scene_args::SceneArgs;
use super::transform_args::TransformArgs;

/// Arguments of the viewer.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// Structure or topology file to open (default: the bundled demo trajectory).
    #[arg(value_name = "TOP")]
    pub top: Option<PathBuf>,
    /// Trajectory file.
    #[arg(value_name = "TRAJ")]
    pub traj: Option<PathBuf>,
    #[command(flatten)]
    pub live: LiveArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub particles: ParticleArgs,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub transforms: TransformArgs,
    /// Scripted run: play this many frames (each computed and shown) first.
    #[arg(long, value_name = "N")]
    pub play_frames: Option<usize>,
    /// Scripted run: then save a screenshot of the window's view to this PNG.
    #[arg(long, value_name = "FILE")]
    pub screenshot: Option<PathBuf>,
    /// Scripted run: then close the window (exit status 0 when everything worked).
    #[arg(long)]
    pub quit: bool,
    /// Run the console commands of this file first (one per line, `#` comments; see
    /// docs/usage.md), stopping at the first error.
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Scripted run: write the anonymous memory (KiB) after each frame shown to this CSV.
    #[arg(long, value_name = "FILE", hide = true)]
    pub memory_log: Option<PathBuf>,
    /// Surface engine: `gpu` (drawn straight from its buffers; even on a software adapter),
    /// `cpu`, or `auto` (GPU on a hardware adapter, else CPU).
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// Same as `--backend cpu`.
    #[arg(long, conflicts_with = "backend")]
    pub cpu: bool,
    /// Stereo view to start with: off, sbs (wall-eyed), sbs-cross (cross-eyed), anaglyph
    /// (red/cyan) or anaglyph-grey (also in the window's Look panel).
    #[arg(long, value_name = "MODE", default_value = "off")]
    pub stereo: Stereo,
    #[command(flatten)]
    pub eyes: StereoArgs,
}

/// Runs the viewer.
pub fn run(args: ViewArgs) -> Result<()> {
    let commands = match &args.script {
        Some(path) => Some((
            path.clone(),
            app::console::read_script(path).map_err(anyhow::Error::msg)?,
        )),
        None => None,
    };
    let live = args.live.options(args.traj.as_deref())?;
    if live.is_some() && args.top.is_none() {
        bail!(
            "--imd: give the structure file of the simulation's atoms (mdsurf TOP --imd HOST:PORT)"
        );
    }
    let params = args.params.params()?;
    let particles = args.particles.options()?;
    let state = args.scene.load_state()?;
    let transforms = args.transforms.options(state.as_ref());
    if transforms.periodic && args.backend == Backend::Gpu && !args.cpu {
        eprintln!("{}", mdsurf::surface::periodic::GPU_NOTE);
    }
    let mut render = RenderSettings {
        stereo: args.stereo,
        eye_separation: args.eyes.eye_separation,
        focal_distance: args.eyes.focal,
        ..RenderSettings::default()
    };
    let (reps, camera) = match (state, &args.scene.select) {
        (Some(state), _) => {
            state.look.apply(&mut render).map_err(anyhow::Error::msg)?;
            (Some(state.representations), state.camera)
        }
        (None, Some(expr)) => {
            let style = if particles.beads {
                RepStyle::Beads
            } else {
                RepStyle::Surface
            };
            let mut rep = Representation::new("selection", expr, style);
            rep.set_params(&params);
            rep.vertices = args.params.vertex_mode();
            rep.radii = args.params.radius_set();
            rep.colour = particles.colours;
            rep.validate().map_err(anyhow::Error::msg)?;
            (Some(vec![rep]), None)
        }
        (None, None) => (None, None),
    };
    let options = ViewOptions {
        files: args.top.map(|t| (t, args.traj)),
        script: Script {
            play_frames: args.play_frames,
            screenshot: args.screenshot,
            quit: args.quit,
            memory_log: args.memory_log,
            commands,
        },
        backend: if args.cpu {
            app::Backend::Cpu
        } else {
            args.backend.into()
        },
        params,
        vertices: args.params.vertex_mode(),
        radii: args.params.radius_set(),
        particles,
        render,
        reps,
        camera,
        transforms,
        live,
    };
    mdsurf::app::run(options)?;
    Ok(())
}

impl From<Backend> for app::Backend {
    fn from(b: Backend) -> app::Backend {
        match b {
            Backend::Cpu => app::Backend::Cpu,
            Backend::Gpu => app::Backend::Gpu,
            Backend::Auto => app::Backend::Auto,
        }
    }
}
