//! The arguments of `mdsurf bench` and their parsers (atom counts such as `2.37M`, the GPU
//! density gather choice, the viewer benchmark's frame rate).

use std::path::PathBuf;

use super::arg_error::ArgError;
use super::common::{BenchBackend, ParamArgs, ParticleArgs};

/// Arguments of `mdsurf bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Print only the results and errors (no "timing ..." progress lines on stderr).
    #[arg(short, long)]
    pub quiet: bool,
    /// Structure or topology file to benchmark (default: the bundled demo).
    #[arg(value_name = "TOP")]
    pub top: Option<PathBuf>,
    /// Trajectory file.
    #[arg(value_name = "TRAJ")]
    pub traj: Option<PathBuf>,
    /// Also (or only, without TOP) time a synthetic system of N particles, tiled from TOP or
    /// the demo with per-frame jitter; accepts 1000000, 1e6, 950k, 2.37M (repeatable).
    #[arg(long, value_name = "N", value_parser = parse_count)]
    pub synthetic: Vec<usize>,
    /// Also (or only) time N particles on hollow spherical shells (a capsid: 6 layers from
    /// 60 Å out, radii and colours from TOP or the demo), mostly empty space inside the box;
    /// each engine (CPU and GPU) is timed with sparse bricks and dense (repeatable).
    #[arg(long, value_name = "N", value_parser = parse_count)]
    pub synthetic_shell: Vec<usize>,
    /// Run the GPU engine's reproduction of the paper's Table 1 (its sizes and spacings,
    /// R = 1, I = 0.5) and print it beside the paper's figures.
    #[arg(long)]
    pub table1: bool,
    /// With --table1: print each row's GPU memory without a GPU instead of timing it: the
    /// engine's buffers for the row's synthetic system and grid under the limits of an 80 GB
    /// NVIDIA GPU, the mesh sized from the CPU engine's surface (which it computes per row).
    #[arg(long, requires = "table1")]
    pub plan_only: bool,
    /// With --plan-only: every mesh buffer at its largest binding instead of the CPU surface's
    /// counts (an upper bound for any surface; no surface is computed, so it takes seconds).
    #[arg(long, requires = "plan_only")]
    pub mesh_bound: bool,
    /// With --table1: skip the rows with more atoms than N (quick checks, small GPUs).
    #[arg(long, value_name = "N", value_parser = parse_count)]
    pub max_atoms: Option<usize>,
    /// Engines to time: cpu, gpu, or all that are available.
    #[arg(long, value_enum, default_value_t = BenchBackend::All)]
    pub backend: BenchBackend,
    /// Timed frames per case (each a new frame); medians are reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeats: u32,
    /// Untimed frames before timing (pipeline set-up, buffer growth).
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub particles: ParticleArgs,
    /// Compute surfaces without per-atom colours (the paper timed with colours).
    #[arg(long)]
    pub no_color: bool,
    /// Also time what `surface --per-residue` adds to each frame (area per atom, then per
    /// residue, on the frame's mesh; the file's case, not synthetic ones): the `per_residue_ms` column
    /// and a line with its share of the frame's compute.
    #[arg(long)]
    pub per_residue: bool,
    /// Compute each frame's surface periodic in the frame's box, as `surface --periodic` does
    /// (the CPU periodic engine, interpolated vertices; the file's case, not synthetic ones);
    /// with --per-residue, the atoms' areas are weighed over their images that reach the cell.
    #[arg(long)]
    pub periodic: bool,
    /// Also write the table as CSV.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// How the GPU's sparse density gather reads atoms: `tiled` (the brick's threads share
    /// each atom load through workgroup memory), `rows` (each thread loads its own) or `auto`
    /// (tiled where a brick spans at most three bin cells, as at H = 1 to 2 Å; the default).
    #[arg(long, value_enum, default_value_t = GatherArg::Auto)]
    pub density_gather: GatherArg,
    /// Play TOP [TRAJ] (or the demo) through the viewer's own frame loop offscreen: the
    /// window's worker, timeline and renderer drawing into a texture, with no window; prints
    /// frames shown per second, frames dropped, compute, latency and draw times, memory.
    #[arg(long)]
    pub viewer: bool,
    /// With --viewer: the picture's size in pixels.
    #[arg(long, value_name = "WxH", default_value = "1920x1080", requires = "viewer",
          value_parser = super::render_args::parse_size)]
    pub size: [u32; 2],
    /// With --viewer: timeline frames to play (a shorter trajectory loops).
    #[arg(long, value_name = "N", default_value_t = 240, requires = "viewer",
          value_parser = clap::value_parser!(u32).range(2..=1_000_000))]
    pub frames: u32,
    /// With --viewer: the timeline's speed in frames per second (as the window's, 0.5 to
    /// 240); frames not ready when the next falls due are dropped.
    #[arg(long, value_name = "FPS", default_value_t = 240.0, requires = "viewer",
          value_parser = parse_play_fps)]
    pub play_fps: f32,
    /// With --viewer: play the first frame as N frames, each atom moved by up to 0.3 Å per
    /// axis per frame (automatic for single-frame files, with --frames frames).
    #[arg(long, value_name = "N", requires = "viewer",
          value_parser = clap::value_parser!(u32).range(2..=1_000_000))]
    pub jitter_frames: Option<u32>,
    /// With --viewer: the look drawn (--look figure, --outline, --shadows; the window's by
    /// default), to time what outlines and shadows cost.
    #[command(flatten)]
    pub look: super::look_args::LookArgs,
}

/// Parses the viewer benchmark's timeline speed (0.5 to 240 frames per second).
fn parse_play_fps(s: &str) -> Result<f32, ArgError> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::PlayFps(s.to_string()))?;
    if !(0.5..=240.0).contains(&v) {
        return Err(ArgError::PlayFpsRange(s.to_string()));
    }
    Ok(v)
}

/// The `--density-gather` choices (see [`mdsurf::gpu::DensityGather`]).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum GatherArg {
    /// Each thread loads the atoms around its own run of voxels.
    Rows,
    /// A brick's threads stage the atoms around the brick in workgroup memory.
    Tiled,
    /// Tiled for small bricks against the bin cells, rows for large ones.
    Auto,
}

impl From<GatherArg> for mdsurf::gpu::DensityGather {
    fn from(g: GatherArg) -> Self {
        match g {
            GatherArg::Rows => mdsurf::gpu::DensityGather::Rows,
            GatherArg::Tiled => mdsurf::gpu::DensityGather::Tiled,
            GatherArg::Auto => mdsurf::gpu::DensityGather::Auto,
        }
    }
}

/// Parses an atom count: `1000000`, `1e6`, `950k`, `2.37M`.
pub fn parse_count(s: &str) -> Result<usize, ArgError> {
    let t = s.trim();
    let (num, mult) = match t.chars().last() {
        Some('k' | 'K') => (&t[..t.len() - 1], 1e3),
        Some('m' | 'M') => (&t[..t.len() - 1], 1e6),
        _ => (t, 1.0),
    };
    let v: f64 = num
        .replace(['_', ','], "")
        .parse()
        .map_err(|_| ArgError::Count(s.to_string()))?;
    let n = (v * mult).round();
    if !(1.0..=1e10).contains(&n) {
        return Err(ArgError::CountRange(s.to_string()));
    }
    Ok(n as usize)
}
