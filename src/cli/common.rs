//! What the headless subcommands share: the input options (files, beads, colours, radii), the
//! surface parameters (H, R, I, quality), the frame selection, the backend choice, and loading
//! a system into the particles an engine consumes. Sits between the command line and the
//! library's `io`, `model`, `surface` and `gpu` modules.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use glam::Vec3;
use mdsurf::gpu::{GpuEngine, Picked};
use mdsurf::io::{self, Trajectory};
use mdsurf::model::colour_data;
use mdsurf::model::colour_map::parse_range;
use mdsurf::model::{
    ColorScheme, ColourMap, DataColours, Frame, ParticleOptions, Particles, RadiusOverrides,
};
use mdsurf::scene::representation::Representation;
use mdsurf::surface::{
    CpuEngine, Preset, Quality, RadiusSet, SurfaceEngine, SurfaceParams, VertexMode,
};

/// Input files and how their atoms become particles.
#[derive(clap::Args, Debug, Clone)]
pub struct InputArgs {
    /// Structure or topology file (PDB, mmCIF, GRO, XYZ, ...); may be the trajectory itself.
    #[arg(value_name = "TOP")]
    pub top: PathBuf,
    /// Trajectory file (XTC, TRR, DCD, LAMMPS dump, TNG, NetCDF, ...).
    #[arg(value_name = "TRAJ")]
    pub traj: Option<PathBuf>,
    #[command(flatten)]
    pub particles: ParticleArgs,
}

/// How atoms become particles: beads, colours, radius overrides.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ParticleArgs {
    /// One bead per residue instead of one particle per atom.
    #[arg(long)]
    pub beads: bool,
    /// Colour scheme: element, chain, residue-type, residue-index, b-factor, single:#rrggbb,
    /// data:FILE.csv (rows index,value or frame,index,value; atoms without a value are grey), or
    /// exposure (each residue's area on its surface over its type's area alone, 0 to 1, per
    /// frame; surfaces only).
    #[arg(long = "color", value_name = "SCHEME", default_value = "element")]
    pub color: String,
    /// Colour map of --color data:FILE, exposure (and of per-model B-factors): viridis or bwr
    /// (blue-white-red, for signed data).
    #[arg(long = "color-map", value_name = "MAP")]
    pub color_map: Option<ColourMap>,
    /// Values at the ends of the colour map, LOW:HIGH (default: the data's minimum and maximum;
    /// for bwr, ± the largest magnitude, so that 0 is white).
    #[arg(long = "color-range", value_name = "LOW:HIGH", allow_hyphen_values = true,
          value_parser = parse_range)]
    pub color_range: Option<[f32; 2]>,
    /// Radius override in Å per element or particle type, e.g. `C=1.7` or `2=1.2` (repeatable).
    #[arg(long = "radius", value_name = "TYPE=Å")]
    pub radius: Vec<String>,
}

impl ParticleArgs {
    /// The library's particle options; fails with a one-line message on a bad scheme or radius.
    pub fn options(&self) -> Result<ParticleOptions> {
        let mut colours =
            ColorScheme::from_str(&self.color).map_err(|e| anyhow!("--color: {e}"))?;
        match &mut colours {
            ColorScheme::Data(d) => {
                d.map = self.color_map.unwrap_or(d.map);
                d.range = self.color_range.or(d.range);
            }
            ColorScheme::BFactor => {}
            ColorScheme::Exposure(map) if self.color_range.is_none() => {
                *map = self.color_map.unwrap_or(*map);
            }
            ColorScheme::Exposure(_) => {
                bail!("--color-range does not apply to --color exposure (its range is 0 to 1)")
            }
            _ if self.color_map.is_some() || self.color_range.is_some() => {
                bail!(
                    "--color-map and --color-range apply to --color data:FILE.csv or b-factor (--color-map also to exposure)"
                )
            }
            _ => {}
        }
        let radius_overrides =
            RadiusOverrides::parse_all(&self.radius).map_err(|e| anyhow!("--radius: {e}"))?;
        Ok(ParticleOptions {
            beads: self.beads,
            radius_overrides,
            colours,
            exposure: None,
        })
    }
}

impl ParticleArgs {
    /// [`ParticleArgs::options`] for `trajectory`: a data file is checked against its atoms and
    /// frames (one line naming the file and line), and `b-factor` on a multi-model PDB becomes
    /// the B-factors of each model, per frame.
    pub fn options_for(&self, trajectory: &Trajectory) -> Result<ParticleOptions> {
        let mut options = self.options()?;
        let path = trajectory.path();
        let is_pdb = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("pdb") || e.eq_ignore_ascii_case("ent"));
        if options.colours == ColorScheme::BFactor && is_pdb && trajectory.len() > 1 {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("{}: cannot read", path.display()))?;
            let table = colour_data::parse_pdb_bfactors(path, &text).map_err(|e| anyhow!(e))?;
            let map = self.color_map.unwrap_or(ColourMap::BlueWhiteRed);
            let range = self.color_range.unwrap_or(table.min_max);
            options.colours = ColorScheme::Data(DataColours {
                id: colour_data::register(table),
                map,
                range: Some(range),
            });
        }
        if let Some(table) = options.colours.data().and_then(|d| d.table()) {
            table
                .check(trajectory.topology().len(), None)
                .map_err(|e| anyhow!("--color: {e}"))?;
        }
        Ok(options)
    }
}

/// Fails with one line when per-frame data colours have no values for a frame of `frames`.
pub fn check_colour_frames(options: &ParticleOptions, frames: &[usize]) -> Result<()> {
    let table = options.colours.data().and_then(|d| d.table());
    if let (Some(table), Some(&last)) = (table, frames.iter().max()) {
        table
            .check(usize::MAX, Some(last + 1))
            .map_err(|e| anyhow!("--color: {e}"))?;
    }
    Ok(())
}

/// The surface parameters H, R, I and quality.
#[derive(clap::Args, Debug, Clone)]
pub struct ParamArgs {
    /// Grid spacing H in Å.
    #[arg(
        long,
        value_name = "H",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub spacing: f32,
    /// Radius scale R: Gaussian width = radius * R.
    #[arg(
        long,
        value_name = "R",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub radius_scale: f32,
    /// Isovalue I of the density (1.0 = peak of one isolated atom).
    #[arg(
        long,
        value_name = "I",
        default_value_t = 0.5,
        allow_negative_numbers = true
    )]
    pub isovalue: f32,
    /// Gaussian cutoff: low (2 alpha), medium (2.5), high (3), max (4).
    #[arg(long, value_name = "Q", default_value = "medium")]
    pub quality: Quality,
    /// Named R, I, quality, vertices and radii (H kept): `ses` = area close to the
    /// solvent-excluded surface (probe 1.4 Å; within 1.84 % at H = 0.35 to 1 Å on the 22
    /// proteins of tests/data/ses_reference.csv): R 0.802, I 0.293, quality max, refined
    /// vertices unless --vertices says otherwise, radii H 1.020, N 0.707, O 1.413 Å under any
    /// --radius, atoms with fewer than 160 heavy atoms within 16 Å shrunk in each frame (by up
    /// to 59.8 %, for an isolated atom).
    #[arg(long, value_name = "NAME", conflicts_with_all = ["radius_scale", "isovalue", "quality"])]
    pub preset: Option<Preset>,
    /// Vertices: `interpolated` (linear along grid edges, as the paper) or `refined` (on the
    /// exact Gaussian sum, analytic normals, area and volume that hold at any H; slower).
    /// Default: the preset's (refined for `ses`), else interpolated.
    #[arg(long, value_name = "MODE")]
    pub vertices: Option<VertexMode>,
}

impl ParamArgs {
    /// Checked parameters: H, R and I must be positive and finite. Says on stderr when a preset
    /// is used at a grid spacing it does not hold at ([`Preset::spacing_note`]).
    pub fn params(&self) -> Result<SurfaceParams> {
        let params = SurfaceParams {
            spacing: self.spacing,
            radius_scale: self.radius_scale,
            isovalue: self.isovalue,
            quality: self.quality,
        };
        let params = match self.preset {
            Some(preset) => preset.apply(params),
            None => params,
        };
        params.validate()?;
        if let Some(note) = self.preset.and_then(|p| p.spacing_note(params.spacing)) {
            eprintln!("note: {note}");
        }
        Ok(params)
    }

    /// The radii the atoms start from: the preset's, else mdsurf's element table (`--radius`
    /// overrides apply on top of either).
    pub fn radius_set(&self) -> RadiusSet {
        self.preset.map(Preset::radius_set).unwrap_or_default()
    }

    /// Sets how the vertices of `reps` are placed: by [`ParamArgs::vertex_mode`], except that
    /// representations from a state file (`from_state`) keep their own unless `--vertices` or
    /// `--preset` is given. A `--preset` also gives a state file's representations its R, I,
    /// quality and radii (each keeps its H), as it gives them to the command's own.
    pub fn apply_to_reps(&self, reps: &mut [Representation], from_state: bool) {
        if from_state && let Some(preset) = self.preset {
            for rep in reps.iter_mut() {
                rep.set_params(&preset.apply(rep.params()));
                rep.radii = preset.radius_set();
            }
        }
        if from_state && self.vertices.is_none() && self.preset.is_none() {
            return;
        }
        let mode = self.vertex_mode();
        for rep in reps {
            rep.vertices = mode;
        }
    }

    /// How vertices are placed: `--vertices` when given, else the preset's, else interpolated.
    pub fn vertex_mode(&self) -> VertexMode {
        self.vertices
            .or(self.preset.map(Preset::vertices))
            .unwrap_or_default()
    }
}

/// Sets `engine` to place vertices by `mode`, saying on stderr when it places them otherwise.
pub fn set_vertex_mode(engine: &mut dyn SurfaceEngine, mode: VertexMode) {
    engine.set_vertices(mode);
    if engine.vertices() != mode {
        eprintln!(
            "note: the {} engine places vertices {}; --vertices {mode} needs --backend cpu",
            engine.name(),
            engine.vertices(),
        );
    }
}

/// Which engine computes the surfaces.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// The multi-threaded CPU reference engine.
    Cpu,
    /// The wgpu compute engine.
    Gpu,
    /// The GPU when a hardware adapter exists, else the CPU (a software adapter such as
    /// lavapipe is slower than the CPU engine).
    Auto,
}

/// Creates the engine for `backend` on a headless device ([`mdsurf::gpu::pick_engine`]);
/// `auto` says on stderr which one it picked and why (unless `quiet`).
pub fn make_engine(backend: Backend, quiet: bool) -> Result<Box<dyn SurfaceEngine + Send>> {
    let note = |text: String| {
        if !quiet {
            eprintln!("{text}");
        }
    };
    // `From` lives beside the viewer's flags (`cli/view.rs`): the viewer's backend is this one.
    let picked = mdsurf::gpu::pick_engine(backend.into(), None)
        .context("--backend gpu: cannot start the GPU engine")?;
    match picked {
        Picked::Gpu(gpu) => {
            if backend == Backend::Auto {
                note(format!("backend: gpu ({})", gpu.context().adapter_name));
            }
            Ok(gpu)
        }
        Picked::Cpu { why } => {
            if let Some(why) = why {
                note(format!("backend: cpu ({why})"));
            }
            Ok(Box::new(CpuEngine::new()))
        }
    }
}

/// Which engines `mdsurf bench` times.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchBackend {
    /// Only the CPU engine.
    Cpu,
    /// Only the GPU engine (an error when there is none).
    Gpu,
    /// Every engine that starts on this machine.
    All,
}

/// An engine being benchmarked; the GPU one also reports its memory.
pub enum BenchEngine {
    /// The CPU reference engine.
    Cpu(Box<CpuEngine>),
    /// The wgpu compute engine.
    Gpu(Box<GpuEngine>),
}

impl BenchEngine {
    /// The engine to compute with.
    pub fn engine(&mut self) -> &mut dyn SurfaceEngine {
        match self {
            BenchEngine::Cpu(e) => e.as_mut(),
            BenchEngine::Gpu(e) => e.as_mut(),
        }
    }

    /// Short name (`cpu`, `gpu`).
    pub fn name(&self) -> &str {
        match self {
            BenchEngine::Cpu(e) => e.name(),
            BenchEngine::Gpu(e) => e.name(),
        }
    }

    /// Bytes of GPU memory the engine's buffers hold; `None` for the CPU engine.
    pub fn gpu_bytes(&self) -> Option<u64> {
        match self {
            BenchEngine::Cpu(_) => None,
            BenchEngine::Gpu(e) => Some(e.gpu_bytes()),
        }
    }
}

/// The engines `backend` asks for; `all` skips a GPU that does not start, saying so on stderr.
pub fn engines_for(backend: BenchBackend) -> Result<Vec<BenchEngine>> {
    let mut engines = Vec::new();
    if backend != BenchBackend::Gpu {
        engines.push(BenchEngine::Cpu(Box::new(CpuEngine::new())));
    }
    if backend == BenchBackend::Cpu {
        return Ok(engines);
    }
    match mdsurf::gpu::pick_engine(mdsurf::gpu::Backend::Gpu, None) {
        Ok(Picked::Gpu(gpu)) => {
            eprintln!("gpu: {}", gpu.context().adapter_name);
            engines.push(BenchEngine::Gpu(gpu));
        }
        // `pick_engine` gives the CPU for `Backend::Gpu` never; say so rather than panic.
        Ok(Picked::Cpu { why }) => eprintln!(
            "note: no GPU engine ({}); timing the CPU only",
            why.unwrap_or_default()
        ),
        Err(err) if backend == BenchBackend::Gpu => {
            return Err(
                anyhow::Error::new(err).context("--backend gpu: cannot start the GPU engine")
            );
        }
        Err(err) => eprintln!("note: no GPU engine ({err}); timing the CPU only"),
    }
    Ok(engines)
}

/// A `START:STOP:STEP` frame selection (STOP exclusive; each part optional; a single number
/// selects one frame; `all` every frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame, from 0.
    pub start: usize,
    /// One past the last frame; `None` for the end of the trajectory.
    pub stop: Option<usize>,
    /// Step between frames (at least 1).
    pub step: usize,
}

impl Default for FrameRange {
    fn default() -> Self {
        FrameRange {
            start: 0,
            stop: None,
            step: 1,
        }
    }
}

impl FromStr for FrameRange {
    type Err = super::arg_error::ArgError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || super::arg_error::ArgError::FrameRange(s.to_string());
        let num = |p: &str| -> Result<Option<usize>, super::arg_error::ArgError> {
            let p = p.trim();
            if p.is_empty() {
                Ok(None)
            } else {
                p.parse().map(Some).map_err(|_| bad())
            }
        };
        if s.trim().eq_ignore_ascii_case("all") {
            return Ok(FrameRange::default());
        }
        let parts: Vec<&str> = s.split(':').collect();
        let range = match parts.as_slice() {
            [one] => {
                let n = num(one)?.ok_or_else(bad)?;
                FrameRange {
                    start: n,
                    stop: Some(n + 1),
                    step: 1,
                }
            }
            [a, b] | [a, b, ""] => FrameRange {
                start: num(a)?.unwrap_or(0),
                stop: num(b)?,
                step: 1,
            },
            [a, b, c] => FrameRange {
                start: num(a)?.unwrap_or(0),
                stop: num(b)?,
                step: num(c)?.unwrap_or(1),
            },
            _ => return Err(bad()),
        };
        if range.step == 0 {
            return Err(super::arg_error::ArgError::FrameStep(s.to_string()));
        }
        Ok(range)
    }
}

impl fmt::Display for FrameRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.stop {
            Some(stop) => write!(f, "{}:{}:{}", self.start, stop, self.step),
            None => write!(f, "{}::{}", self.start, self.step),
        }
    }
}

impl FrameRange {
    /// The selected frame indices of a trajectory with `len` frames.
    pub fn indices(&self, len: usize) -> Vec<usize> {
        let stop = self.stop.unwrap_or(len).min(len);
        (self.start..stop).step_by(self.step).collect()
    }
}

/// An opened system: its trajectory and the particles the engine gets.
pub struct System {
    /// The trajectory (or single structure).
    pub trajectory: Trajectory,
    /// Radii and colours per particle; positions per frame.
    pub particles: Particles,
    /// The file frames come from (the trajectory, else the topology), for messages.
    pub frames_path: PathBuf,
}

impl System {
    /// Opens `input`, reads `first_frame` to size beads, and builds the particles.
    /// Returns the system and that frame.
    pub fn open(input: &InputArgs, first_frame: usize) -> Result<(System, Frame)> {
        System::open_or_follow(input, None, first_frame)
    }

    /// [`System::open`], with the frames coming from a running simulation or a growing file
    /// when `live` says so.
    pub fn open_or_follow(
        input: &InputArgs,
        live: Option<&io::LiveSource>,
        first_frame: usize,
    ) -> Result<(System, Frame)> {
        let trajectory = match live {
            Some(live) => io::open_growing(&input.top, live)?,
            None => io::open(&input.top, input.traj.as_deref())?,
        };
        let options = input.particles.options_for(&trajectory)?;
        let frames_path = trajectory.path().to_path_buf();
        if trajectory.is_empty() {
            bail!("{}: the trajectory has no frames", frames_path.display());
        }
        // A running simulation may have pushed the frame out already: then the oldest held.
        let (_, first) = io::read_held(
            first_frame.min(trajectory.len() - 1),
            |i| trajectory.read_frame(i),
            io::IoError::oldest_held,
        )?;
        let particles = Particles::new(trajectory.topology(), &first, &options)
            .map_err(|e| anyhow!("{}: {e}", frames_path.display()))?;
        Ok((
            System {
                trajectory,
                particles,
                frames_path,
            },
            first,
        ))
    }

    /// Number of readable frames.
    pub fn len(&self) -> usize {
        self.trajectory.len()
    }

    /// Frames a selection may name: the readable ones plus, in a damaged (truncated) file, the
    /// first unreadable one, so that a run over the whole file reaches it and reports its error
    /// after processing the good frames.
    pub fn selectable_len(&self) -> usize {
        match self.trajectory.damage() {
            Some(damage) => damage.frame + 1,
            None => self.trajectory.len(),
        }
    }

    /// Reads frame `index` and writes its particle positions (Å) into `out`. Returns the frame
    /// (for its time) and the time the read took in ms.
    pub fn read_positions(&mut self, index: usize, out: &mut Vec<Vec3>) -> Result<(Frame, f64)> {
        let t0 = Instant::now();
        let frame = self.trajectory.read_frame(index)?;
        self.particles
            .positions_into(&frame, out)
            .map_err(|e| anyhow!("{}: frame {index}: {e}", self.frames_path.display()))?;
        Ok((frame, ms_since(t0)))
    }
}

/// Milliseconds elapsed since `t0`.
pub fn ms_since(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}

/// The bundled demo (`assets/md_1u19.gro` + `.xtc`): next to the working directory, else in
/// the source tree the binary was built from.
pub fn demo_files() -> Result<(PathBuf, PathBuf)> {
    for root in [Path::new("."), Path::new(env!("CARGO_MANIFEST_DIR"))] {
        let gro = root.join("assets/md_1u19.gro");
        let xtc = root.join("assets/md_1u19.xtc");
        if gro.is_file() && xtc.is_file() {
            return Ok((gro, xtc));
        }
    }
    bail!("the bundled demo assets/md_1u19.gro + .xtc was not found; give TOP [TRAJ]")
}

#[cfg(test)]
mod frame_range_tests {
    use super::FrameRange;

    fn range(s: &str) -> FrameRange {
        s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn ranges_parse_with_optional_parts_and_all_means_every_frame() {
        let r = |start, stop, step| FrameRange { start, stop, step };
        assert_eq!(range("10"), r(10, Some(11), 1));
        assert_eq!(range("0:50:5"), r(0, Some(50), 5));
        assert_eq!(range("3:"), r(3, None, 1));
        assert_eq!(range("::2"), r(0, None, 2));
        assert_eq!(range("all"), r(0, None, 1));
        assert_eq!(range(" All "), r(0, None, 1));
    }

    #[test]
    fn bad_ranges_name_the_text() {
        for bad in ["", "x", "1:2:3:4", "-1", "every"] {
            let e = bad.parse::<FrameRange>().unwrap_err().to_string();
            assert!(e.contains(&format!("'{bad}'")), "{bad}: {e}");
        }
        let e = "0:10:0".parse::<FrameRange>().unwrap_err().to_string();
        assert!(e.contains("step must be at least 1"), "{e}");
    }
}
