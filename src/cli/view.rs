//! The viewer's command line (no subcommand): `mdsurf [TOP [TRAJ]]` opens the window, with the
//! bundled demo when no file is given; `--play-frames N --screenshot FILE --quit` runs a scripted
//! session (used by tests). The window itself lives in `mdsurf::app`.

use std::path::PathBuf;

use anyhow::Result;
use mdsurf::app::{self, Script, ViewOptions};

use super::common::{Backend, ParamArgs, ParticleArgs};

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
    pub params: ParamArgs,
    #[command(flatten)]
    pub particles: ParticleArgs,
    /// Scripted run: play this many frames (each computed and shown) first.
    #[arg(long, value_name = "N")]
    pub play_frames: Option<usize>,
    /// Scripted run: then save a screenshot of the window's view to this PNG.
    #[arg(long, value_name = "FILE")]
    pub screenshot: Option<PathBuf>,
    /// Scripted run: then close the window (exit status 0 when everything worked).
    #[arg(long)]
    pub quit: bool,
    /// Surface engine: `gpu` (drawn straight from its buffers; even on a software adapter),
    /// `cpu`, or `auto` (GPU on a hardware adapter, else CPU).
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// Same as `--backend cpu`.
    #[arg(long, conflicts_with = "backend")]
    pub cpu: bool,
}

/// Runs the viewer.
pub fn run(args: ViewArgs) -> Result<()> {
    let options = ViewOptions {
        files: args.top.map(|t| (t, args.traj)),
        script: Script {
            play_frames: args.play_frames,
            screenshot: args.screenshot,
            quit: args.quit,
        },
        backend: if args.cpu {
            app::Backend::Cpu
        } else {
            args.backend.into()
        },
        params: args.params.params()?,
        particles: args.particles.options()?,
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
