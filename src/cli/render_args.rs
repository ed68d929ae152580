//! The flags of `mdsurf render` and their parsers: one-line errors naming the value; NaN,
//! infinities and values out of their range are refused as the state file refuses them.

use anyhow::Result;
use std::path::PathBuf;

use mdsurf::export::video::{VideoQuality, check_fps};

use super::arg_error::ArgError;
use mdsurf::render::settings::{
    DEFAULT_EYE_SEPARATION, check_eye_separation, check_focal_distance,
};
use mdsurf::render::{AtomStyle, Background, Stereo};

use super::chunk::ChunkSpec;
use super::common::{Backend, FrameRange, InputArgs, ParamArgs};
use super::scene_args::SceneArgs;
use super::transform_args::TransformArgs;

/// Arguments of `mdsurf render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub input: InputArgs,
    #[command(flatten)]
    pub live: super::live_args::LiveArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub transforms: TransformArgs,
    /// Frame to render (from 0) when --frames is not given [default: 0; with --script, the
    /// frame the script leaves].
    #[arg(long)]
    pub frame: Option<usize>,
    /// Frames to render, START:STOP:STEP (STOP exclusive, parts optional), one index, or `all`;
    /// PNGs need `{frame}` or `{image}` in the output name, a movie takes them all.
    #[arg(long, value_name = "A:B[:S]")]
    pub frames: Option<FrameRange>,
    /// Output PNG. For several images a pattern: `{frame}` (or `{frame:05}`, zero-padded) is the
    /// trajectory frame index, as in `mdsurf surface`; `{image}` the image number (5 digits).
    /// A `.mp4` name writes all images as one H.264 movie instead (even --size needed), a
    /// `.gif` name as one looping animated GIF (256 colours a frame, at most 50 frames/s).
    #[arg(short = 'o', long = "output", value_name = "PNG|MP4|GIF")]
    pub output: PathBuf,
    /// Run the console commands of this file first, headless (one per line, `#` comments; the
    /// window's console language: `rep`, `frame`, `fit`, `view`, `screenshot FILE [WxH]`,
    /// `select`), stopping at the first error; `-o` then shows the scene the script left.
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Print only errors (no per-image lines, progress bar or summaries).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print one line per image (surfaces, timings, file) instead of the progress bar on a
    /// terminal, or of nothing per image when stderr is a file or a pipe.
    #[arg(short, long, conflicts_with = "quiet")]
    pub verbose: bool,
    /// Also write each rendered frame's area and volume per surface representation, as
    /// `mdsurf surface --stats` does (same columns).
    #[arg(long, value_name = "FILE.csv")]
    pub stats: Option<PathBuf>,
    /// Movie frame rate, frames per second (MP4 or GIF output; default 24).
    #[arg(long, value_name = "FPS", value_parser = parse_fps)]
    pub fps: Option<f64>,
    /// Movie quality preset: low, medium (default) or high (MP4: the bit rate; GIF: the colour
    /// quantiser's care; the surface's resolution is --quality).
    #[arg(long, value_name = "PRESET")]
    pub video_quality: Option<VideoQuality>,
    /// Image size in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = parse_size)]
    pub size: [u32; 2],
    /// Turn the camera by this many degrees per image (turntable). Without --frames, renders
    /// one full turn of the chosen frame.
    #[arg(long, value_name = "DEG_PER_FRAME", allow_negative_numbers = true,
          value_parser = parse_turntable)]
    pub turntable: Option<f32>,
    /// Stereo output: off, sbs (side by side, wall-eyed: left eye on the left), sbs-cross
    /// (cross-eyed: swapped), anaglyph (red/cyan, colour) or anaglyph-grey (red/cyan of each
    /// eye's luminance).
    #[arg(long, value_name = "MODE", default_value = "off")]
    pub stereo: Stereo,
    #[command(flatten)]
    pub eyes: StereoArgs,
    /// Background: dark or light.
    #[arg(long, value_name = "BG", default_value = "dark")]
    pub background: Background,
    /// Surface opacity 0..1 (below 1 shows the atoms inside).
    #[arg(long, value_name = "A", default_value_t = 1.0, value_parser = parse_unit)]
    pub opacity: f32,
    /// Atoms: none, spheres, sticks or ball-and-stick.
    #[arg(long, value_name = "STYLE", default_value = "none")]
    pub atoms: AtomStyle,
    /// Ambient occlusion strength 0..1 (0: off).
    #[arg(long, value_name = "S", default_value_t = 0.7, value_parser = parse_unit)]
    pub ao: f32,
    /// Depth cue strength 0..1 (far parts fade towards the background).
    #[arg(long, value_name = "S", default_value_t = 0.6, value_parser = parse_unit)]
    pub depth_cue: f32,
    /// Orthographic instead of perspective projection.
    #[arg(long)]
    pub ortho: bool,
    /// Camera yaw and pitch in degrees.
    #[arg(long, value_name = "YAW,PITCH", value_parser = parse_pair, allow_negative_numbers = true)]
    pub view: Option<[f32; 2]>,
    /// Surface engine.
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    /// Render one block of the images: I/N (0-based I of N contiguous blocks) or `slurm`
    /// (I = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, N = SLURM_ARRAY_TASK_COUNT). Names,
    /// camera and turntable angles are those of the whole run, so the blocks together give the
    /// same images as one run.
    #[arg(long, value_name = "I/N|slurm")]
    pub chunk: Option<ChunkSpec>,
    #[command(flatten)]
    pub look: super::look_args::LookArgs,
}

/// Stereo eye flags shared by `mdsurf render` and the viewer.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct StereoArgs {
    /// Stereo eye separation as a fraction of the focal distance (default 1/30).
    #[arg(long, value_name = "F", default_value_t = DEFAULT_EYE_SEPARATION,
          value_parser = parse_eye_separation, allow_negative_numbers = true)]
    pub eye_separation: f32,
    /// Stereo focal (zero-parallax) distance in Å from the camera (default: the distance to
    /// the molecule's centre, following the camera).
    #[arg(long, value_name = "D", value_parser = parse_focal, allow_negative_numbers = true)]
    pub focal: Option<f32>,
}

/// A number for flag `what`, or one line naming the value.
pub(crate) fn parse_f32(s: &str, what: &'static str) -> Result<f32, ArgError> {
    s.trim().parse().map_err(|_| ArgError::Number {
        what,
        text: s.to_string(),
    })
}

/// A strength or opacity from 0 to 1 (NaN and infinities refused, as the state file does).
fn parse_unit(s: &str) -> Result<f32, ArgError> {
    match s.trim().parse::<f32>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(ArgError::Unit(s.to_string())),
    }
}

fn parse_eye_separation(s: &str) -> Result<f32, ArgError> {
    Ok(check_eye_separation(parse_f32(s, "eye separation")?)?)
}

fn parse_focal(s: &str) -> Result<f32, ArgError> {
    Ok(check_focal_distance(parse_f32(s, "focal distance")?)?)
}

pub(crate) fn parse_size(s: &str) -> Result<[u32; 2], ArgError> {
    let bad = || ArgError::Size(s.to_string());
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(ArgError::SizeRange(s.to_string()));
    }
    Ok([w, h])
}

fn parse_pair(s: &str) -> Result<[f32; 2], ArgError> {
    let bad = || ArgError::View(s.to_string());
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let pair: [f32; 2] = [
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ];
    if !pair.iter().all(|v| v.is_finite()) {
        return Err(ArgError::ViewNotFinite(s.to_string()));
    }
    Ok(pair)
}

fn parse_fps(s: &str) -> Result<f64, ArgError> {
    let fps: f64 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::FrameRate(s.to_string()))?;
    Ok(check_fps(fps)?)
}

fn parse_turntable(s: &str) -> Result<f32, ArgError> {
    let d: f32 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::Turntable(s.to_string()))?;
    if !d.is_finite() || d.abs() > 360.0 || (d != 0.0 && d.abs() < 0.01) {
        return Err(ArgError::TurntableRange(s.to_string()));
    }
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_pairs_parse() {
        assert_eq!(parse_size("640x480"), Ok([640, 480]));
        assert!(parse_size("640").is_err());
        assert!(parse_size("0x10").is_err());
        assert_eq!(parse_pair("30,-10"), Ok([30.0, -10.0]));
        assert!(parse_unit("nan").is_err() && parse_unit("1.5").is_err());
        assert_eq!(parse_unit("0.25"), Ok(0.25));
    }

    #[test]
    fn stereo_numbers_reject_nan_inf_and_negatives_in_one_line() {
        assert_eq!(parse_eye_separation("0.05"), Ok(0.05));
        assert_eq!(parse_eye_separation("0"), Ok(0.0));
        assert_eq!(parse_focal("80"), Ok(80.0));
        for bad in ["nan", "inf", "-0.1", "x"] {
            let e = parse_eye_separation(bad).expect_err(bad).to_string();
            assert!(!e.contains('\n') && e.contains("eye separation"), "{e}");
        }
        for bad in ["NaN", "-inf", "-5", "0"] {
            let e = parse_focal(bad).expect_err(bad).to_string();
            assert!(!e.contains('\n') && e.contains("focal distance"), "{e}");
        }
    }
}
