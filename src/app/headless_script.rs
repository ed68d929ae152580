//! Console scripts without a window (`mdsurf render --script FILE`): the commands of the
//! window's console ([`super::console`]) run against the viewer's own state ([`AppCore`]) and
//! compute worker, with the window's renderer ([`ViewRenderer`]) on a headless device. `rep`,
//! `frame`, `fit` and `select` change or query the state as in the window; `screenshot FILE
//! [WxH]` computes the frame and writes the picture; `view save` / `view open` write and read
//! state files; `play` and `pause` have no clock to run on and only say so. The state the
//! script leaves (representations, camera, look, frame) comes back as a [`StateFile`], so
//! `render` draws its own pictures from it as from `--state`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use super::console::{self, ConsoleError};
use super::source::FrameSource;
use super::state::{AppCore, Command};
use super::timeline::TimelineCmd;
use super::view_renderer::ViewRenderer;
use super::worker::{Engine, Worker};
use crate::gpu::GpuContext;
use crate::render::{RenderError, RenderSettings, write_png};
use crate::scene::representation::Representation;
use crate::scene::state_file::{LookError, StateFile, StateFileError};

/// Longest wait for one frame's surfaces (s): a script is a batch job, so this is generous.
const COMPUTE_TIMEOUT_S: u64 = 3600;

/// Why a script line failed: one line naming the script and the line (from 1).
#[derive(Debug, thiserror::Error)]
#[error("{}:{line}: {reason}", script.display())]
pub struct ScriptRunError {
    /// The script file.
    pub script: PathBuf,
    /// The line, from 1.
    pub line: usize,
    /// What went wrong.
    pub reason: Box<LineError>,
}

/// What went wrong on one script line.
#[derive(Debug, thiserror::Error)]
pub enum LineError {
    /// The command does not parse or cannot apply (an unknown representation, a bad value).
    #[error(transparent)]
    Console(#[from] ConsoleError),
    /// The frame's surfaces could not be computed (the worker's one-line message).
    #[error("{0}")]
    Compute(String),
    /// The frame's surfaces took longer than [`COMPUTE_TIMEOUT_S`].
    #[error("the surfaces were not ready within {COMPUTE_TIMEOUT_S} s")]
    Timeout,
    /// The picture could not be drawn or written.
    #[error(transparent)]
    Picture(#[from] RenderError),
    /// A state file could not be written or read.
    #[error(transparent)]
    State(#[from] StateFileError),
    /// A state file's look cannot be used.
    #[error(transparent)]
    Look(#[from] LookError),
}

/// What the script starts from and where it draws.
pub struct ScriptSetup<'a> {
    /// The device the pictures are drawn on.
    pub gpu: &'a GpuContext,
    /// The surface engine the worker runs (the GPU engine on `gpu`, or the CPU engine).
    pub engine: Engine,
    /// The trajectory.
    pub source: Arc<dyn FrameSource>,
    /// A state to start from (`--state`), else `reps`.
    pub start: Option<StateFile>,
    /// The representations to start from without a state (the command line's choice), else
    /// the default representations of the files.
    pub reps: Option<Vec<Representation>>,
    /// The representation new `rep add` lines copy (surface parameters, colours: the
    /// command-line flags).
    pub base: Representation,
    /// The look (command-line flags; a `start` state's look replaces it).
    pub render: RenderSettings,
    /// Picture size of `screenshot` lines without `WxH` (pixels).
    pub size: [u32; 2],
}

/// Runs the script `lines` (from [`console::read_script`] of `script`): every line in order,
/// stopping at the first error. `print` gets the lines the console would print (counts,
/// confirmations, files written). Returns the state the script leaves.
pub fn run_script(
    setup: ScriptSetup<'_>,
    script: &Path,
    lines: &[(usize, String)],
    print: &mut dyn FnMut(&str),
) -> Result<StateFile, ScriptRunError> {
    let ScriptSetup {
        gpu,
        engine,
        source,
        start,
        reps,
        base,
        render,
        size,
    } = setup;
    let mut core = AppCore::new(Worker::spawn_engine(engine, Box::new(|| {})));
    core.base = base;
    core.render = render;
    if let Some(reps) = reps {
        core.set_reps(reps);
        core.keep_reps_on_load = true;
    }
    core.set_source(source);
    let mut view = ViewRenderer::new(gpu.device.clone(), gpu.queue.clone());
    let at = |line: usize| {
        move |reason: LineError| ScriptRunError {
            script: script.to_path_buf(),
            line,
            reason: Box::new(reason),
        }
    };
    // A state file's look was checked when it was read; line 0 names the state, not a line.
    if let Some(state) = start {
        core.apply_view_state(state)
            .map_err(|e| at(0)(LineError::Look(e)))?;
    }
    for (line, text) in lines {
        run_line(&mut core, &mut view, text, size, print).map_err(at(*line))?;
    }
    Ok(core.view_state())
}

/// One script line against `core`.
fn run_line(
    core: &mut AppCore,
    view: &mut ViewRenderer,
    text: &str,
    size: [u32; 2],
    print: &mut dyn FnMut(&str),
) -> Result<(), LineError> {
    let Some(command) = console::parse(text)? else {
        return Ok(());
    };
    let outcome = command.resolve(core)?;
    if let Some(out) = &outcome.output {
        print(out);
    }
    for cmd in outcome.commands {
        match cmd {
            Command::Screenshot {
                size: asked, path, ..
            } => {
                let Some(path) = path else { continue };
                let image = picture(core, view, asked.unwrap_or(size))?;
                write_png(&path, &image)?;
                print(&format!("wrote {}", path.display()));
            }
            Command::SaveView(Some(path)) => {
                core.view_state().save(&path)?;
                print(&format!("wrote {}", path.display()));
            }
            Command::OpenView(Some(path)) => {
                core.apply_view_state(StateFile::load(&path)?)?;
            }
            Command::Timeline(TimelineCmd::SetPlaying(_)) => {
                print("play/pause: a script without a window has no clock; use frame N");
            }
            other => core.apply(other),
        }
    }
    Ok(())
}

/// Computes the current frame's representations and draws them at `size`.
fn picture(
    core: &mut AppCore,
    view: &mut ViewRenderer,
    size: [u32; 2],
) -> Result<crate::render::RgbaImage, LineError> {
    core.request_current();
    if !core.wait_idle(Duration::from_secs(COMPUTE_TIMEOUT_S)) {
        return Err(LineError::Timeout);
    }
    if let Some(e) = core.error.take() {
        return Err(LineError::Compute(e));
    }
    view.sync(core);
    Ok(view.snapshot(&core.camera, &core.render, size)?)
}
