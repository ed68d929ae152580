//! `mdsurf render`: pictures without a window, through the viewer's renderer. Opens the files,
//! computes the surface of each selected frame with the chosen engine, renders it offscreen with
//! `render_to_rgba` (optionally turning the camera per image, or in stereo) and writes PNGs
//! atomically.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use mdsurf::render::{
    AtomStyle, Background, Camera, GpuScene, HeadlessGpu, Projection, RenderSettings, Renderer,
    Stereo, atom_instances, bounding_sphere, guess_bonds, render_to_rgba, write_png,
};

use super::common::{Backend, FrameRange, InputArgs, ParamArgs, System, make_engine, ms_since};

/// Arguments of `mdsurf render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub input: InputArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Frame to render (from 0) when --frames is not given.
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// Frames to render, START:STOP:STEP (STOP exclusive); needs `{frame}` in the output name.
    #[arg(long, value_name = "A:B[:S]")]
    pub frames: Option<FrameRange>,
    /// Output PNG; `{frame}` is replaced by the image number (5 digits) for sequences.
    #[arg(short = 'o', long = "output", value_name = "PNG")]
    pub output: PathBuf,
    /// Image size in pixels.
    #[arg(long, value_name = "WxH", default_value = "1280x720", value_parser = parse_size)]
    pub size: [u32; 2],
    /// Turn the camera by this many degrees per image (turntable). Without --frames, renders
    /// one full turn of the chosen frame.
    #[arg(long, value_name = "DEG_PER_FRAME", allow_negative_numbers = true)]
    pub turntable: Option<f32>,
    /// Stereo output: off, sbs (side by side) or anaglyph (red/cyan).
    #[arg(long, value_name = "MODE", default_value = "off")]
    pub stereo: Stereo,
    /// Eye separation as a fraction of the viewing distance.
    #[arg(long, value_name = "F", default_value_t = 0.05)]
    pub eye_separation: f32,
    /// Background: dark or light.
    #[arg(long, value_name = "BG", default_value = "dark")]
    pub background: Background,
    /// Surface opacity 0..1 (below 1 shows the atoms inside).
    #[arg(long, value_name = "A", default_value_t = 1.0)]
    pub opacity: f32,
    /// Atoms: none, spheres, sticks or ball-and-stick.
    #[arg(long, value_name = "STYLE", default_value = "none")]
    pub atoms: AtomStyle,
    /// Ambient occlusion strength 0..1 (0: off).
    #[arg(long, value_name = "S", default_value_t = 0.7)]
    pub ao: f32,
    /// Depth cue strength 0..1 (far parts fade towards the background).
    #[arg(long, value_name = "S", default_value_t = 0.6)]
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
}

fn parse_size(s: &str) -> Result<[u32; 2], String> {
    let bad = || format!("bad size '{s}': expected WIDTHxHEIGHT, e.g. 1920x1080");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "bad size '{s}': each side must be 1 to 16384 pixels"
        ));
    }
    Ok([w, h])
}

fn parse_pair(s: &str) -> Result<[f32; 2], String> {
    let bad = || format!("bad view '{s}': expected YAW,PITCH in degrees");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    Ok([
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ])
}

/// `pattern` with `{frame}` replaced by `index` (5 digits).
fn output_path(pattern: &Path, index: usize) -> PathBuf {
    PathBuf::from(
        pattern
            .to_string_lossy()
            .replace("{frame}", &format!("{index:05}")),
    )
}

/// Runs `mdsurf render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let params = args.params.params()?;
    let first = args.frames.map_or(args.frame, |r| r.start);
    let (mut system, _) = System::open(&args.input, first)?;
    let len = system.len();
    let mut frames = match args.frames {
        Some(r) => r.indices(len),
        None if args.frame < len => vec![args.frame],
        None => bail!(
            "{}: no frame {} (it has {len})",
            system.frames_path.display(),
            args.frame
        ),
    };
    if frames.is_empty() {
        bail!(
            "{}: --frames selects no frame (it has {len})",
            system.frames_path.display()
        );
    }
    if args.frames.is_none() && args.turntable.is_some_and(|d| d != 0.0) {
        let images = (360.0 / args.turntable.unwrap_or(1.0).abs())
            .round()
            .max(1.0) as usize;
        frames = vec![frames[0]; images];
    }
    let sequence = frames.len() > 1;
    if sequence && !args.output.to_string_lossy().contains("{frame}") {
        bail!(
            "{} images to write: put {{frame}} in the output name, e.g. -o out/frame_{{frame}}.png",
            frames.len()
        );
    }
    let settings = RenderSettings {
        background: args.background,
        surface_opacity: args.opacity.clamp(0.0, 1.0),
        atom_style: args.atoms,
        stereo: args.stereo,
        eye_separation: args.eye_separation,
        ambient_occlusion: args.ao.clamp(0.0, 1.0),
        depth_cue: args.depth_cue.clamp(0.0, 1.0),
        ..RenderSettings::default()
    };
    let gpu = HeadlessGpu::new()
        .context("rendering needs a wgpu adapter (a software one such as lavapipe is enough)")?;
    let renderer = Renderer::new(&gpu.device);
    let mut engine = make_engine(args.backend)?;
    let mut scene = GpuScene::new();
    let mut camera = Camera {
        projection: if args.ortho {
            Projection::Orthographic
        } else {
            Projection::Perspective
        },
        ..Camera::default()
    };
    let bonds = match (settings.atom_style.has_bonds(), system.particles.is_beads()) {
        (true, false) if system.trajectory.topology().bonds.is_empty() => None,
        (true, false) => Some(system.trajectory.topology().bonds.clone()),
        _ => Some(Vec::new()),
    };
    let mut bonds = bonds;
    let mut positions = Vec::new();
    for (i, &f) in frames.iter().enumerate() {
        let t0 = Instant::now();
        let (_, read_ms) = system.read_positions(f, &mut positions)?;
        let atoms = system.particles.atom_set(&positions);
        let out = engine
            .compute(&atoms, &params)
            .map_err(|e| anyhow!("{}: frame {f}: {e}", system.frames_path.display()))?;
        scene.set_mesh(&gpu.device, &gpu.queue, &out.mesh);
        let radii = system.particles.radii();
        let b = bonds.get_or_insert_with(|| guess_bonds(&positions, radii));
        let (s, c) = atom_instances(
            &positions,
            radii,
            Some(system.particles.colours()),
            b,
            &settings,
        );
        scene.set_atoms(&gpu.device, &gpu.queue, &s, &c);
        if i == 0 {
            let shown_atoms =
                if settings.atom_style == AtomStyle::Hidden && !out.mesh.positions.is_empty() {
                    &[][..]
                } else {
                    &positions[..]
                };
            let points = out.mesh.positions.iter().chain(shown_atoms);
            let (centre, radius) = bounding_sphere(points).ok_or_else(|| {
                anyhow!("frame {f}: nothing to draw (empty surface and no atoms)")
            })?;
            camera.fit_sphere(centre, radius);
            if let Some([yaw, pitch]) = args.view {
                camera.yaw = yaw.to_radians();
                camera.pitch = pitch.to_radians();
            }
        }
        let mut cam = camera;
        cam.turn(args.turntable.unwrap_or(0.0) * i as f32);
        let image = render_to_rgba(
            &gpu.device,
            &gpu.queue,
            &renderer,
            &scene,
            &cam,
            &settings,
            args.size,
        )?;
        let path = if sequence {
            output_path(&args.output, i)
        } else {
            args.output.clone()
        };
        write_png(&path, &image)?;
        eprintln!(
            "frame {f}: {} triangles, area {:.1} Å², volume {:.1} Å³, read {read_ms:.1} ms, total {:.1} ms -> {}",
            out.mesh.triangle_count(),
            out.area,
            out.volume,
            ms_since(t0),
            path.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_patterns_parse() {
        assert_eq!(parse_size("640x480"), Ok([640, 480]));
        assert!(parse_size("640").is_err());
        assert!(parse_size("0x10").is_err());
        assert_eq!(
            output_path(Path::new("d/f_{frame}.png"), 7),
            Path::new("d/f_00007.png")
        );
        assert_eq!(parse_pair("30,-10"), Ok([30.0, -10.0]));
    }
}
