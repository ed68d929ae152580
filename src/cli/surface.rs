//! `mdsurf surface`: reads frames, computes each frame's surface with the chosen engine, writes
//! meshes (`-o`, a `{frame}` pattern for several frames) and a stats CSV (`--stats`), and prints
//! one summary line per frame (or a progress bar for long runs on a terminal).
//!
//! A failure in the middle (a truncated file, a bad frame) keeps the outputs of the frames
//! before it, is reported as one line naming the file and frame, and exits with status 2.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use super::progress::Progress;
use anyhow::{Context, Result, anyhow, bail};
use mdsurf::export::glb::GlbAnimation;
use mdsurf::export::stats_merge::{PartHeader, part_path};
use mdsurf::export::{self, MeshFormat, StatsRow, StatsWriter};

use mdsurf::scene::SceneBackend;
use mdsurf::surface::SurfaceParams;

use super::chunk::{ChunkSpec, check_chunk_count};
use super::interrupt::{catch_interrupts, interrupted};
use super::live_args::{LiveArgs, OverrunSkips, end_of_stream, read_held};
use super::measure_args::{MeasureArgs, Measurer};

use super::common::{
    Backend, FrameRange, InputArgs, ParamArgs, System, check_colour_frames, ms_since,
    set_vertex_mode,
};
use super::scene_args::{SceneArgs, bind_scene};
use super::transform_args::{FrameReader, TransformArgs, host_scene};

/// Arguments of `mdsurf surface`.
#[derive(clap::Args, Debug)]
pub struct SurfaceArgs {
    #[command(flatten)]
    pub input: InputArgs,
    #[command(flatten)]
    pub live: LiveArgs,
    /// Frames to process, START:STOP:STEP (STOP exclusive, parts optional), one index, or `all`.
    #[arg(long, value_name = "START:STOP:STEP")]
    pub frames: Option<FrameRange>,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub transforms: TransformArgs,
    /// Engine: cpu, gpu, or auto (the GPU when there is one).
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// Mesh output (.ply, .obj, .stl, .glb); with several frames a pattern such as
    /// `out_{frame}.ply` or `out_{frame:04}.ply` (the frame's index in the trajectory), with
    /// several surface representations `{rep}` (the representation's name). A .glb without
    /// `{frame}` holds all frames as an animation (one node per frame, shown in turn).
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Per-frame statistics CSV (area, volume, counts, timings).
    #[arg(long, value_name = "STATS.csv")]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub measure: MeasureArgs,
    /// Print only errors (no per-frame lines, progress bar or final summary).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print one line per frame (area, volume, counts, time) instead of the progress bar on a
    /// terminal, or of nothing per frame when stderr is a file or a pipe.
    #[arg(short, long, conflicts_with = "quiet")]
    pub verbose: bool,
    /// Do one block of the selected frames: I/N (0-based I of N contiguous blocks) or `slurm`
    /// (I = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, N = SLURM_ARRAY_TASK_COUNT). Meshes keep
    /// the global frame index; --stats goes to STATS.part-IIII-of-NNNN.csv (join them with
    /// `mdsurf merge STATS.csv`), and so do the per-residue, per-atom and interface tables
    /// (not the cavities').
    #[arg(long, value_name = "I/N|slurm")]
    pub chunk: Option<ChunkSpec>,
    /// Leave the ms_* timing columns of --stats empty, so that two runs (or a merged chunked
    /// run) give the same file byte for byte.
    #[arg(long)]
    pub no_timings: bool,
    /// Playback rate of an animated .glb in trajectory frames per second (frames keep the
    /// spacing of their simulation times).
    #[arg(long, value_name = "FPS", default_value_t = export::glb::DEFAULT_FPS,
          value_parser = parse_fps)]
    pub fps: f64,
}

fn parse_fps(s: &str) -> Result<f64, super::arg_error::ArgError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1000.0 => Ok(v),
        _ => Err(super::arg_error::ArgError::SurfaceFps(s.to_string())),
    }
}

/// Runs `mdsurf surface`.
pub fn run(args: SurfaceArgs) -> Result<()> {
    // Everything that can be checked before reading data is checked first.
    let params = args.params.params()?;
    let chunk = args.chunk.map(ChunkSpec::resolve).transpose()?;
    let output = args.output.as_deref().map(OutputPattern::new).transpose()?;
    if let Some(stats) = &args.stats {
        check_parent_dir(stats)?;
    }
    let inputs: Vec<PathBuf> = std::iter::once(args.input.top.clone())
        .chain(args.input.traj.clone())
        .collect();
    refuse_shared_paths(output.as_ref(), args.stats.as_deref(), &inputs)?;
    for path in args.measure.outputs() {
        check_parent_dir(path)?;
        refuse_shared_paths(None, Some(path), &inputs)?;
    }
    args.measure.check_chunk(chunk.is_some())?;

    let live = args.live.options(args.input.traj.as_deref())?;
    if live.is_some() && chunk.is_some() {
        bail!(
            "--chunk splits a trajectory's frames: a running simulation (--imd) has no fixed frames to split"
        );
    }
    let state = args.scene.load_state()?;
    let transforms = args.transforms.options(state.as_ref());

    let start_frame = args.frames.map(|r| r.start).unwrap_or(0);
    let (system, _) = System::open_or_follow(&args.input, live.as_ref(), start_frame)?;
    let mut reader = FrameReader::new(&system.trajectory, &transforms)?;
    // A running simulation may have pushed the start frame out already: then the oldest held.
    let (first_index, first) =
        read_held(start_frame.min(system.len() - 1), |i| reader.read_frame(i))?;
    let range = args.frames.unwrap_or_default();
    let frames = range.indices(system.selectable_len());
    if frames.is_empty() {
        bail!(
            "--frames {range} selects no frame of {} ({} frames)",
            system.frames_path.display(),
            system.len()
        );
    }
    let options = args.input.particles.options_for(&system.trajectory)?;
    check_colour_frames(&options, &frames)?;
    let topology = system.trajectory.topology();
    let choice = args.scene.representations(
        state,
        topology,
        &first,
        (&params, args.params.radius_set()),
        &options,
        args.quiet,
    )?;
    let mut reps = choice.reps.clone();
    args.params.apply_to_reps(&mut reps, choice.state.is_some());
    // Only visible surface representations are computed.
    reps.retain(|r| r.style.is_surface());
    let mut engine = host_scene(args.backend, reader.chain(), args.quiet)?;
    if let SceneBackend::Host(e) = engine.backend_mut() {
        // Without -o or a measurement of the mesh only area, volume and counts are reported:
        // the mesh need not be built.
        e.set_keep_mesh(output.is_some() || args.measure.keeps_meshes());
        // The interface splits the complex's density only where each side has its radius in
        // the complex; radii that follow exposure differ at the contact.
        let fixed_radii = args.params.radius_set().exposure().is_none();
        e.set_keep_density(args.measure.keeps_density() && fixed_radii);
        if reader.chain().periodic().is_none() {
            set_vertex_mode(e.as_mut(), args.params.vertex_mode());
        }
    }
    let files = system.frames_path.display().to_string();
    let layers = bind_scene(
        &mut engine,
        &reps,
        topology,
        &first,
        &options.radius_overrides,
        &files,
    )?;
    if layers.is_empty() {
        bail!("no visible surface representation to compute (the state file hides them all)");
    }
    let mut measurer = Measurer::new(
        &args.measure,
        topology,
        &first,
        &options.radius_overrides,
        &params,
        args.params.radius_set(),
        args.params.vertex_mode(),
    )?;
    measurer.set_periodic(reader.chain().periodic().is_some())?;
    // A .glb without {frame} takes every frame as an animation.
    let animate = output
        .as_ref()
        .is_some_and(|o| o.format == MeshFormat::Glb && !o.has_frame && frames.len() > 1);
    if animate && chunk.is_some() {
        bail!(
            "--chunk: an animated .glb needs every frame in one process; write one file per frame (-o surf_{{frame}}.glb) or run without --chunk"
        );
    }
    if let Some(out) = &output {
        if frames.len() > 1 && !out.has_frame && !animate {
            bail!(
                "-o {}: {} frames selected, so the output needs a {{frame}} pattern (e.g. surf_{{frame}}.{})",
                out.raw,
                frames.len(),
                out.format
            );
        }
        if layers.len() > 1 && !out.has_rep {
            let names: Vec<&str> = layers.iter().map(|l| l.rep.name.as_str()).collect();
            bail!(
                "-o {}: {} surface representations ({}), so the output needs a {{rep}} pattern (e.g. surf_{{rep}}.{}), or pick one with --select",
                out.raw,
                layers.len(),
                names.join(", "),
                out.format
            );
        }
    }
    choice.print_defaults();
    if args.transforms.any() && !args.quiet {
        reader.print_summary();
    }
    // A chunk does its block of the selection and writes its stats to a part file.
    let selection = [
        range.start,
        range
            .stop
            .unwrap_or(usize::MAX)
            .min(system.selectable_len()),
        range.step,
    ];
    if let Some(c) = chunk {
        check_chunk_count(c, frames.len())?;
    }
    let frames = match chunk {
        Some(c) => frames[c.block(frames.len())].to_vec(),
        None => frames,
    };
    let part = chunk.map(|c| PartHeader {
        index: c.index,
        count: c.count,
        selection,
        params: part_params(&args, &params, engine.name()),
    });
    let mut stats = match (&args.stats, &part) {
        (None, _) => None,
        (Some(path), None) => Some(StatsWriter::create(path)?),
        (Some(path), Some(h)) => Some(StatsWriter::create_with(
            &part_path(path, h.index, h.count),
            Some(h),
        )?),
    };
    let first = Arc::new(first);
    if let Some(mut header) = part {
        // The tables also depend on the measurement flags.
        let digest = md5::compute(format!("{:?}", args.measure).as_bytes());
        header
            .params
            .push(("measure".into(), format!("{digest:x}")[..16].to_string()));
        // A later chunk builds the exposure tables from the run's first frame, as one process.
        if header.index > 0 && measurer.needs_exposure() {
            let computed = engine
                .frame(topology, first_index, &first, &layers)
                .map_err(|e| anyhow!("{files}: {e}"))?;
            measurer.prime_exposure(topology, &first, &computed, &engine)?;
        }
        measurer.set_part(header);
    }
    if let Some(stats) = stats.as_mut() {
        stats.set_timings(!args.no_timings);
    }

    let mut movies = Vec::new();
    if let Some(out) = output.as_ref().filter(|_| animate) {
        for layer in &layers {
            movies.push(GlbAnimation::create(
                &out.path_for(0, &layer.rep.name),
                args.fps,
            )?);
        }
    }

    // A running simulation has no known length: one line per frame, no bar.
    let length = live.is_none().then_some(frames.len());
    let progress = Progress::new(length, args.quiet, args.verbose);
    // The loop's first frame is usually the one read above: it is taken, not read again (a
    // million atoms: a copy and a check of every position).
    let mut first = Some(first);
    let t_all = Instant::now();
    let mut failure = None;
    let mut ok_frames = 0usize;
    // Frames before this one left a running simulation's ring unread (skipped).
    let (mut resume_at, mut skips) = (0usize, OverrunSkips::up_to(frames.last().copied()));
    catch_interrupts();
    for &index in &frames {
        if index < resume_at {
            skips.pass_over();
            continue;
        }
        if interrupted() {
            failure = Some(anyhow!(
                "interrupted by a signal before frame {index} of {}",
                system.frames_path.display()
            ));
            break;
        }
        let rows = (|| -> Result<Vec<StatsRow>> {
            let t0 = Instant::now();
            let frame = match first.take_if(|_| index == first_index) {
                Some(frame) => frame,
                None => Arc::new(reader.read_frame(index)?),
            };
            let read_ms = ms_since(t0);
            let computed = engine
                .frame(topology, index, &frame, &layers)
                .map_err(|e| anyhow!("{files}: {e}"))?;
            for (k, layer) in computed.layers.iter().enumerate() {
                let mesh = &layer.output.mesh;
                if let Some(movie) = movies.get_mut(k) {
                    movie.add_frame(index, frame.time_ps, mesh)?;
                } else if let Some(out) = &output {
                    export::write_mesh(&out.path_for(index, &layer.rep.name), mesh)?;
                }
            }
            measurer
                .frame(topology, &frame, &computed, &engine, args.quiet)
                .map_err(|e| anyhow!("{files}: {e:#}"))?;
            let rows = StatsRow::of_scene(&computed, read_ms);
            Ok(rows)
        })();
        match rows {
            Ok(rows) => {
                ok_frames += 1;
                for row in &rows {
                    if let Some(stats) = stats.as_mut() {
                        stats.write_row(row)?;
                    }
                    progress.line(|| summary_line(row, layers.len() > 1));
                }
                progress.advance();
            }
            Err(err) if let Some(oldest) = skips.skip(&err, args.quiet) => resume_at = oldest,
            Err(err) => {
                // The end of a running simulation is the end of the run, not a failure.
                match end_of_stream(&err).filter(|_| ok_frames > 0) {
                    Some(end) if !args.quiet => eprintln!("{end}"),
                    Some(_) => {}
                    None => failure = Some(err),
                }
                break;
            }
        }
    }
    progress.finish();
    skips.finish(args.quiet);

    // Keep what the good frames produced; a run where no frame succeeded changes no file (a
    // chunk with an empty block writes its empty part, so the merge knows it ran).
    if let Some(stats) = stats
        && (stats.rows() > 0 || frames.is_empty())
    {
        stats.finish()?;
    }
    for movie in movies {
        if movie.frames() > 0 {
            movie.finish()?;
        }
    }
    if ok_frames > 0 {
        measurer.finish()?;
    }
    if let Some(err) = failure {
        if ok_frames == 0 {
            return Err(err);
        }
        let kept = match (&output, &args.stats) {
            (None, None) => "",
            _ => " and written",
        };
        bail!("{err:#} (the {ok_frames} frame(s) before it were processed{kept})");
    }
    if progress.shows_summary() {
        let secs = t_all.elapsed().as_secs_f64();
        eprintln!(
            "{} frame(s) in {:.2} s ({:.1} frames/s) on {}",
            ok_frames,
            secs,
            ok_frames as f64 / secs.max(1e-9),
            engine.name()
        );
    }
    Ok(())
}

/// The settings a stats part records so that `mdsurf merge` refuses parts of different runs:
/// H, R, I, quality, vertices and engine by name, everything else that can change the numbers
/// (files, particles, colours, radii, selection or state file, transformations) as a digest.
fn part_params(args: &SurfaceArgs, params: &SurfaceParams, engine: &str) -> Vec<(String, String)> {
    let inputs = format!(
        "{:?}|{:?}|{:?}|{:?}",
        args.input, args.params, args.scene, args.transforms
    );
    let digest = format!("{:x}", md5::compute(inputs.as_bytes()));
    [
        ("spacing", params.spacing.to_string()),
        ("radius_scale", params.radius_scale.to_string()),
        ("isovalue", params.isovalue.to_string()),
        ("quality", params.quality.to_string()),
        ("vertices", args.params.vertex_mode().to_string()),
        ("engine", engine.to_string()),
        ("inputs", digest[..16].to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// The one-line summary of a frame (and representation, when `with_rep`).
fn summary_line(r: &StatsRow, with_rep: bool) -> String {
    let time = r
        .time_ps
        .map(|t| format!("{t:>9.1} ps"))
        .unwrap_or_else(|| "        - ps".into());
    let rep = if with_rep {
        format!(" {:<12}", r.rep)
    } else {
        String::new()
    };
    format!(
        "frame {:>5}{rep} {time} {:>9} atoms  grid {}x{}x{}  {:>9} tris  area {:>11.1} Å²  volume {:>12.1} Å³  {:>8.1} ms",
        r.frame,
        r.atoms,
        r.dims[0],
        r.dims[1],
        r.dims[2],
        r.triangles,
        r.area,
        r.volume,
        r.total_ms
    )
}

/// Fails with one line when two outputs, or an output and an input, are one file (the second
/// write would silently replace the first, or the input).
pub(crate) fn refuse_shared_paths(
    output: Option<&OutputPattern>,
    stats: Option<&Path>,
    inputs: &[PathBuf],
) -> Result<()> {
    let mesh = output
        .filter(|o| !o.has_frame && !o.has_rep)
        .map(|o| o.path_for(0, ""));
    if let (Some(mesh), Some(stats)) = (&mesh, stats)
        && same_file(mesh, stats)
    {
        bail!(
            "-o {} and --stats {} are the same file: give them different names",
            mesh.display(),
            stats.display()
        );
    }
    for out in mesh.iter().map(PathBuf::as_path).chain(stats) {
        if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
            bail!(
                "{} is an input file: an output may not replace it",
                input.display()
            );
        }
    }
    Ok(())
}

/// True when `a` and `b` name the same file (after following symbolic links and resolving their
/// folders), whether or not it exists yet.
fn same_file(a: &Path, b: &Path) -> bool {
    let key = |p: &Path| {
        let p = export::resolve_links(p);
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
        p.file_name().map(|name| dir.join(name))
    };
    key(a).is_some() && key(a) == key(b)
}

/// Fails with a one-line message when `path`'s directory does not exist.
pub(crate) fn check_parent_dir(path: &Path) -> Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = dir
        && !dir.is_dir()
    {
        bail!(
            "cannot write {}: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}

/// A mesh output path, possibly with a `{frame}` or `{frame:0N}` placeholder.
#[derive(Debug, Clone)]
pub struct OutputPattern {
    raw: String,
    prefix: String,
    suffix: String,
    width: usize,
    has_frame: bool,
    has_rep: bool,
    format: MeshFormat,
}

impl OutputPattern {
    /// Parses `path`, checking its placeholder, format and directory.
    pub fn new(path: &Path) -> Result<OutputPattern> {
        let raw = path
            .to_str()
            .with_context(|| format!("-o {}: the path is not valid UTF-8", path.display()))?
            .to_string();
        let (prefix, suffix, width, has_frame) = match raw.find("{frame") {
            None => (raw.clone(), String::new(), 0, false),
            Some(at) => {
                let close = raw[at..]
                    .find('}')
                    .map(|c| at + c)
                    .ok_or_else(|| anyhow!("-o {raw}: unclosed {{frame placeholder"))?;
                let spec = &raw[at + "{frame".len()..close];
                let width = match spec {
                    "" => 0,
                    s => s
                        .strip_prefix(":0")
                        .and_then(|w| w.parse().ok())
                        .ok_or_else(|| {
                            anyhow!("-o {raw}: use {{frame}} or {{frame:0N}}, e.g. {{frame:04}}")
                        })?,
                };
                (
                    raw[..at].to_string(),
                    raw[close + 1..].to_string(),
                    width,
                    true,
                )
            }
        };
        if suffix.contains("{frame") {
            bail!("-o {raw}: only one {{frame}} placeholder is allowed");
        }
        let pattern = OutputPattern {
            format: MeshFormat::from_path(Path::new(&raw))?,
            has_rep: raw.contains("{rep}"),
            raw,
            prefix,
            suffix,
            width,
            has_frame,
        };
        check_parent_dir(&pattern.path_for(0, "rep"))?;
        Ok(pattern)
    }

    /// The output path of frame `index` of representation `rep` (its name, made safe for a
    /// file name).
    pub fn path_for(&self, index: usize, rep: &str) -> PathBuf {
        let path = if self.has_frame {
            format!(
                "{}{:0width$}{}",
                self.prefix,
                index,
                self.suffix,
                width = self.width
            )
        } else {
            self.prefix.clone()
        };
        let safe: String = rep
            .chars()
            .map(|c| {
                if c.is_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        PathBuf::from(path.replace("{rep}", &safe))
    }
}
