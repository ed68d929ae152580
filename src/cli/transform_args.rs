//! The per-frame transformation flags shared by the viewer, `surface` and `render`
//! (`--whole`/`--no-whole`, `--center`, `--fit`, `--fit-reference`, `--smooth`), and
//! [`FrameReader`]: a trajectory read through the transformations the flags ask for.

use super::common::{Backend, make_engine};
use anyhow::Result;
use mdsurf::io::Trajectory;
use mdsurf::model::Frame;
use mdsurf::scene::state_file::StateFile;
use mdsurf::scene::{SceneBackend, SceneEngine};
use mdsurf::surface::periodic::GPU_NOTE;
use mdsurf::surface::{CpuEngine, SurfaceEngine};
use mdsurf::transform::{
    FitReference, Replicate, TransformChain, TransformOptions, TransformedFrames, chain_for,
};

/// Per-frame transformations, applied in this order: whole, center, fit, smooth.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct TransformArgs {
    /// Join molecules split across the periodic box (default: on when the file has a box and
    /// bonds or residues).
    #[arg(long, overrides_with = "no_whole")]
    pub whole: bool,
    /// Do not join molecules split across the periodic box.
    #[arg(long, overrides_with = "whole")]
    pub no_whole: bool,
    /// Put this selection's centre (mass-weighted) at the box centre and wrap whole molecules
    /// into the box around it.
    #[arg(long, value_name = "SEL")]
    pub center: Option<String>,
    /// Superpose every frame on the reference by a least-squares fit of this selection (e.g.
    /// 'protein and name CA').
    #[arg(long, value_name = "SEL")]
    pub fit: Option<String>,
    /// What --fit superposes on: first (the first frame) or topology (the topology file's
    /// coordinates).
    #[arg(long, value_name = "REF", default_value = "first")]
    pub fit_reference: FitReference,
    /// Average positions over ±K frames (after the steps above); 0: off.
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub smooth: usize,
    /// Periodic density: Gaussians near a box face also reach across it, so a liquid or a
    /// membrane patch has no walls at the box faces; the mesh is the surface in one cell and
    /// area and volume are per cell (rectangular or triclinic; computed on the CPU).
    #[arg(long)]
    pub periodic: bool,
    /// With --periodic (implied): show A x B x C images of the cell side by side (along a, b,
    /// c).
    #[arg(long, value_name = "A,B,C")]
    pub replicate: Option<Replicate>,
}

impl TransformArgs {
    /// True when any transformation flag was given.
    pub fn any(&self) -> bool {
        self.whole
            || self.no_whole
            || self.center.is_some()
            || self.fit.is_some()
            || self.smooth > 0
            || self.periodic
            || self.replicate.is_some()
    }

    /// The library's options for these flags; a state file's options fill in what the flags
    /// leave out when no flag is given.
    pub fn options(&self, state: Option<&StateFile>) -> TransformOptions {
        if !self.any()
            && let Some(state) = state
        {
            return state.trajectory.transforms();
        }
        TransformOptions {
            whole: match (self.whole, self.no_whole) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            center: self.center.clone(),
            fit: self.fit.clone(),
            fit_reference: self.fit_reference,
            smooth: self.smooth,
            periodic: self.periodic || self.replicate.is_some(),
            replicate: self.replicate.unwrap_or_default(),
        }
    }
}

/// The scene engine of a headless command on the host: `backend`'s engine (the mesh comes back
/// to the host), or, when `chain` is periodic, the CPU periodic engine (then a GPU asked for
/// with `--backend gpu` is not started, and a note says so unless `quiet`).
pub fn host_scene(backend: Backend, chain: &TransformChain, quiet: bool) -> Result<SceneEngine> {
    let engine: Box<dyn SurfaceEngine + Send> = match chain.periodic() {
        None => make_engine(backend, quiet)?,
        Some(_) => {
            if backend == Backend::Gpu && !quiet {
                eprintln!("{GPU_NOTE}");
            }
            Box::new(CpuEngine::new())
        }
    };
    let mut scene = SceneEngine::new(SceneBackend::Host(engine));
    scene.set_periodic(chain.periodic());
    Ok(scene)
}

/// A trajectory read through a transformation chain.
pub struct FrameReader<'a> {
    trajectory: &'a Trajectory,
    frames: TransformedFrames,
}

impl<'a> FrameReader<'a> {
    /// Reads `trajectory` through the transformations `options` ask for.
    pub fn new(trajectory: &'a Trajectory, options: &TransformOptions) -> Result<FrameReader<'a>> {
        let chain = chain_for(options, trajectory)?;
        Ok(FrameReader {
            frames: TransformedFrames::new(chain, trajectory.len()),
            trajectory,
        })
    }

    /// The chain in use.
    pub fn chain(&self) -> &TransformChain {
        self.frames.chain()
    }

    /// Frame `index`, transformed (and smoothed).
    pub fn read_frame(&mut self, index: usize) -> Result<Frame> {
        let trajectory = self.trajectory;
        self.frames.read(index, |i| {
            trajectory.read_frame(i).map_err(anyhow::Error::from)
        })
    }

    /// Prints what runs, on stderr (nothing when nothing runs).
    pub fn print_summary(&self) {
        let summary = self.chain().summary();
        if !summary.is_empty() {
            eprintln!("transforms: {summary}");
        }
    }
}
