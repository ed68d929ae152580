//! `mdsurf bench`: times each stage (read, upload, bin, density, Marching Cubes) as medians over
//! repeats, per backend, on the bundled demo, on a file given, and on synthetic tiled systems
//! (`--synthetic N`) and hollow shells (`--synthetic-shell N`, also on the dense CPU engine and
//! the dense GPU path),
//! and prints an aligned table (optionally a CSV too); `--table1` runs the
//! GPU engine's reproduction of the paper's Table 1 (`--table1 --plan-only`: its GPU memory per
//! row, sized without a device). Speed claims of the project are measured
//! here, never in tests.

use std::time::Instant;

use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use mdsurf::export::write_atomic;
use mdsurf::measure;
use mdsurf::model::Particles;
use mdsurf::surface::periodic::{PeriodicEngine, Replicate};
use mdsurf::surface::{CpuEngine, RadiusSet, StageTimings, SurfaceParams};
use mdsurf::synthetic::SyntheticSystem;

use super::bench_table::{Table, peak_rss_bytes};
use mdsurf::surface::VertexMode;

use super::common::{
    BenchBackend, BenchEngine, InputArgs, System, demo_files, engines_for, ms_since,
};

pub use super::bench_args::BenchArgs;

/// Where a case's frames come from.
enum Source {
    /// A real trajectory.
    Real(Box<System>),
    /// A tiled system with per-frame jitter.
    Synthetic(SyntheticSystem),
}

/// One benchmark case.
struct Case {
    label: String,
    source: Source,
    params: SurfaceParams,
    /// Also time the dense CPU engine (every grid sample), to show what sparse bricks save.
    dense_too: bool,
}

/// Medians of one case on one engine.
#[derive(Debug, Clone, Default)]
pub struct BenchResult {
    /// Case label.
    pub case: String,
    /// Engine name.
    pub backend: String,
    /// Particles per frame.
    pub atoms: usize,
    /// Grid spacing H in Å.
    pub spacing: f32,
    /// Grid samples per axis (of the last timed frame).
    pub dims: [u32; 3],
    /// Triangles (of the last timed frame).
    pub triangles: usize,
    /// Median time to read (or generate) a frame, ms.
    pub read_ms: f64,
    /// Median stage times, ms.
    pub stages: StageTimings,
    /// Median wall time of `compute` (all stages plus any readback), ms.
    pub compute_wall_ms: f64,
    /// Median time of the area per atom and per residue on the frame's mesh (`--per-residue`),
    /// ms; not part of `compute_wall_ms`.
    pub per_residue_ms: Option<f64>,
    /// Frames per second including reading.
    pub fps: f64,
    /// GPU memory held by the engine's buffers in bytes (GPU engine only).
    pub gpu_bytes: Option<u64>,
    /// Peak resident memory of the process so far, bytes.
    pub peak_rss: Option<u64>,
    /// GPU objects (buffers, bind groups, textures) the engine created per frame after the
    /// first one (GPU engine only; 0 in steady state).
    pub gpu_objects_per_frame: Option<f64>,
    /// Bricks of the grid that atoms reach and the surface crosses (sparse engines only; of
    /// the last timed frame).
    pub bricks: Option<mdsurf::surface::BrickStats>,
    /// True when `bricks.active` was counted (CPU engine). The GPU engine marches every
    /// reached brick and does not count the crossed ones, so its table cell is "-".
    pub bricks_active_counted: bool,
}

/// Says on stderr which case is being timed (not with `-q`).
fn progress(args: &BenchArgs, what: &str) {
    if !args.quiet {
        eprintln!("timing {what} ...");
    }
}

/// Runs `mdsurf bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    let params = args.params.params()?;
    if args.viewer {
        return super::bench_viewer::run(&args);
    }
    if args.table1 {
        print_table1(&args)?;
        if args.top.is_none() && args.synthetic.is_empty() && args.synthetic_shell.is_empty() {
            return Ok(());
        }
    }
    if args.periodic {
        check_periodic(&args)?;
    }
    let backend = if args.periodic {
        BenchBackend::Cpu
    } else {
        args.backend
    };
    let mut engines = engines_for(backend)?;
    for engine in &mut engines {
        if let BenchEngine::Gpu(gpu) = engine {
            gpu.set_options(mdsurf::gpu::EngineOptions {
                density_gather: args.density_gather.into(),
                ..gpu.options()
            });
        }
    }
    let cases = build_cases(&args, params)?;
    let beads = |case: &Case| matches!(&case.source, Source::Real(sys) if sys.particles.is_beads());
    if args.per_residue && cases.iter().any(beads) {
        bail!("--per-residue measures atoms, and these particles are coarse-grained beads");
    }
    if args.per_residue && !cases.iter().any(|c| matches!(c.source, Source::Real(_))) {
        bail!(
            "--per-residue needs a file's residues: give TOP [TRAJ] (synthetic systems have none)"
        );
    }
    let mut results = Vec::new();
    let mut refine_notes = Vec::new();
    for case in cases {
        let Case {
            label,
            mut source,
            params,
            dense_too,
        } = case;
        for engine in engines.iter_mut() {
            let name = engine.name().to_string();
            progress(&args, &format!("{label} on {name}"));
            let mode = args.params.vertex_mode();
            engine.engine().set_vertices(mode);
            let mut r = time_case(&mut source, engine, &params, &args)
                .map_err(|e| anyhow!("{label} on {name}: {e:#}"))?;
            r.case = label.clone();
            if mode == VertexMode::Refined {
                // The refinement's cost: the same case with interpolated vertices.
                engine.engine().set_vertices(VertexMode::Interpolated);
                let mut base = time_case(&mut source, engine, &params, &args)
                    .map_err(|e| anyhow!("{label} on {name}: {e:#}"))?;
                engine.engine().set_vertices(mode);
                let got = engine.engine().vertices();
                let extra = r.compute_wall_ms - base.compute_wall_ms;
                refine_notes.push(format!(
                    "{label} on {name}: refined vertices ({got}) cost {extra:.2} ms per frame, \
                     {:.0} % of the interpolated frame ({:.2} ms)",
                    100.0 * extra / base.compute_wall_ms.max(1e-9),
                    base.compute_wall_ms
                ));
                r.case = format!("{label} refined");
                base.case = format!("{label} interpolated");
                results.push(r);
                results.push(base);
                continue;
            }
            if let Some(ms) = r.per_residue_ms {
                refine_notes.push(format!(
                    "{label} on {name}: per-residue areas cost {ms:.2} ms per frame, {:.0} % of \
                     the frame's compute ({:.2} ms)",
                    100.0 * ms / r.compute_wall_ms.max(1e-9),
                    r.compute_wall_ms
                ));
            }
            let sparse_ms = dense_too.then_some(r.compute_wall_ms);
            results.push(r);
            if let (Some(sparse_ms), BenchEngine::Gpu(gpu)) = (sparse_ms, &mut *engine) {
                // The same GPU engine on the dense path (every voxel sampled and classified).
                progress(&args, &format!("{label} on the dense gpu path"));
                let sparse_opts = gpu.options();
                gpu.set_options(mdsurf::gpu::EngineOptions {
                    sparse_bricks: false,
                    ..sparse_opts
                });
                let dense = time_case(&mut source, engine, &params, &args);
                if let BenchEngine::Gpu(gpu) = &mut *engine {
                    gpu.set_options(sparse_opts);
                }
                let mut d = dense.map_err(|e| anyhow!("{label} on dense gpu: {e:#}"))?;
                d.case = format!("{label} dense");
                refine_notes.push(format!(
                    "{label} on gpu: sparse bricks {sparse_ms:.1} ms per frame, dense {:.1} ms \
                     ({:.1}x)",
                    d.compute_wall_ms,
                    d.compute_wall_ms / sparse_ms.max(1e-9)
                ));
                results.push(d);
            } else if let Some(sparse_ms) = sparse_ms {
                progress(&args, &format!("{label} on the dense cpu engine"));
                let mut dense = BenchEngine::Cpu(Box::new(CpuEngine::dense()));
                dense.engine().set_vertices(mode);
                let mut d = time_case(&mut source, &mut dense, &params, &args)
                    .map_err(|e| anyhow!("{label} on dense cpu: {e:#}"))?;
                d.case = format!("{label} dense");
                refine_notes.push(format!(
                    "{label}: sparse bricks {sparse_ms:.1} ms per frame, dense {:.1} ms \
                     ({:.1}x)",
                    d.compute_wall_ms,
                    d.compute_wall_ms / sparse_ms.max(1e-9)
                ));
                results.push(d);
            }
        }
    }
    let table = Table::from_results(&results);
    println!("{}", table.to_text());
    for note in &refine_notes {
        println!("{note}");
    }
    if let Some(csv) = &args.csv {
        let text = table.to_csv();
        write_atomic(csv, |w| w.write_all(text.as_bytes()))?;
    }
    Ok(())
}

/// Runs the GPU engine's Table 1 reproduction (tiling TOP or the demo) and prints its table;
/// with `--plan-only` prints each row's GPU memory, sized without a device.
fn print_table1(args: &BenchArgs) -> Result<()> {
    if args.backend == BenchBackend::Cpu && !args.plan_only {
        bail!("--table1 times the GPU engine; use --backend gpu or all");
    }
    let (top, traj) = match &args.top {
        Some(top) => (top.clone(), args.traj.clone()),
        None => {
            let (gro, xtc) = demo_files()?;
            (gro, Some(xtc))
        }
    };
    let opts = mdsurf::gpu::table1::Table1Options {
        repeats: args.repeats as usize,
        max_atoms: args.max_atoms,
        colours: !args.no_color,
        density_gather: args.density_gather.into(),
    };
    let text = if args.plan_only {
        let sizing = if args.mesh_bound {
            mdsurf::gpu::table1::MeshSizing::Largest
        } else {
            mdsurf::gpu::table1::MeshSizing::CpuSurface
        };
        mdsurf::gpu::table1::table1_plan(&top, traj.as_deref(), &opts, sizing)
    } else {
        mdsurf::gpu::table1::table1(&top, traj.as_deref(), &opts)
    }
    .map_err(|e| anyhow!("--table1: {e}"))?;
    println!("{text}");
    Ok(())
}

/// The cases the arguments ask for, in order: the file (or demo), then synthetic sizes.
fn build_cases(args: &BenchArgs, params: SurfaceParams) -> Result<Vec<Case>> {
    let input = match &args.top {
        Some(top) => InputArgs {
            top: top.clone(),
            traj: args.traj.clone(),
            particles: args.particles.clone(),
        },
        None => {
            let (gro, xtc) = demo_files()?;
            InputArgs {
                top: gro,
                traj: Some(xtc),
                particles: args.particles.clone(),
            }
        }
    };
    let (mut system, first) = System::open(&input, 0)?;
    // The preset's radii (and their exposure, frame by frame), as `surface` gives them.
    let radius_set = args.params.radius_set();
    if radius_set != RadiusSet::default() {
        let options = radius_set.particle_options(input.particles.options_for(&system.trajectory)?);
        system.particles = Particles::new(system.trajectory.topology(), &first, &options)?;
    }
    let mut cases = Vec::new();
    let name = input
        .traj
        .as_ref()
        .unwrap_or(&input.top)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();

    // The structure synthetic systems are tiled from: the first frame's particles.
    let base_positions = system.particles.positions(&first)?;
    let base_radii = system.particles.radii().to_vec();
    let base_colours = system.particles.colours().to_vec();
    let colours = (!args.no_color).then_some(base_colours.as_slice());
    let tile = |n: usize| -> Result<SyntheticSystem> {
        Ok(SyntheticSystem::tile(
            &base_positions,
            &base_radii,
            colours,
            n,
        )?)
    };

    let shells: Vec<SyntheticSystem> = args
        .synthetic_shell
        .iter()
        .map(|&n| SyntheticSystem::shell(&base_radii, colours, n))
        .collect::<Result<_, _>>()?;
    if args.top.is_some() || (args.synthetic.is_empty() && args.synthetic_shell.is_empty()) {
        cases.push(Case {
            label: name.clone(),
            source: Source::Real(Box::new(system)),
            params,
            dense_too: false,
        });
    }
    for &n in &args.synthetic {
        cases.push(Case {
            label: format!("synthetic {n} ({name})"),
            source: Source::Synthetic(tile(n)?),
            params,
            dense_too: false,
        });
    }
    for (shell, &n) in shells.into_iter().zip(&args.synthetic_shell) {
        cases.push(Case {
            label: format!("shell {n}"),
            source: Source::Synthetic(shell),
            params,
            dense_too: true,
        });
    }
    Ok(cases)
}

/// Refuses `--periodic` where it cannot apply: it times the file's case on the CPU periodic
/// engine, whose vertices are interpolated.
fn check_periodic(args: &BenchArgs) -> Result<()> {
    if args.backend == BenchBackend::Gpu {
        bail!(
            "--periodic: the periodic surface is computed on the CPU (the GPU engine has no periodic path); use --backend cpu"
        );
    }
    if !args.synthetic.is_empty() || !args.synthetic_shell.is_empty() || args.table1 {
        bail!(
            "--periodic times the file's case; synthetic systems and --table1 have no periodic box"
        );
    }
    if args.params.vertex_mode() == VertexMode::Refined {
        bail!(
            "--periodic: the periodic engine interpolates its vertices (no --vertices refined or --preset ses)"
        );
    }
    Ok(())
}

/// Times one case on one engine: `warmup` untimed frames, then `repeats` timed ones (with
/// `--periodic`, on the CPU periodic engine in each frame's box instead of `engine`).
fn time_case(
    source: &mut Source,
    engine: &mut BenchEngine,
    params: &SurfaceParams,
    args: &BenchArgs,
) -> Result<BenchResult> {
    let mut positions: Vec<Vec3> = Vec::new();
    let (mut reads, mut walls, mut computes) = (Vec::new(), Vec::new(), Vec::new());
    let mut per_residue = Vec::new();
    let mut stages: Vec<StageTimings> = Vec::new();
    // Only the last frame's grid and triangle count are kept: holding its mesh while the next
    // frame computes would double the peak memory that the table reports.
    let (mut last_dims, mut last_triangles) = ([0u32; 3], 0usize);
    let total = args.warmup + args.repeats;
    let gpu_objects = |e: &BenchEngine| match e {
        BenchEngine::Gpu(g) => Some(g.objects_created().total()),
        BenchEngine::Cpu(_) => None,
    };
    let mut objects_after_first = None;
    let mut periodic = args.periodic.then(PeriodicEngine::new);
    let single_frame = matches!(&*source, Source::Real(sys) if sys.len() == 1);
    for i in 0..total as usize {
        let t0 = Instant::now();
        let (cell, read_ms) = read_frame(source, i, &mut positions)?;
        let t1 = Instant::now();
        // Radii that follow exposure (`--preset ses`): the GPU engine counts them on the
        // device from the particles' own radii; the CPU engine gets the host's.
        let gpu_exposure = match &mut *engine {
            BenchEngine::Gpu(gpu) => gpu.set_exposure(match &*source {
                Source::Real(sys) => sys.particles.exposure(),
                Source::Synthetic(_) => None,
            }),
            BenchEngine::Cpu(_) => false,
        };
        let frame_radii = match source {
            Source::Real(sys) if !gpu_exposure => sys.particles.frame_radii(&positions),
            _ => None,
        };
        let atoms = match &*source {
            Source::Real(sys) => {
                let mut set = sys.particles.atom_set(&positions);
                if let Some(r) = &frame_radii {
                    set.radii = r;
                }
                if args.no_color {
                    set.colours = None;
                }
                set
            }
            Source::Synthetic(s) => mdsurf::surface::AtomSet {
                positions: &positions,
                radii: s.radii(),
                colours: s.colours(),
            },
        };
        // A single-frame file repeats its atoms; the GPU engine would then skip upload,
        // binning and density. Every timed frame is a full one, as on the CPU.
        if let (true, BenchEngine::Gpu(gpu)) = (single_frame, &mut *engine) {
            gpu.forget_inputs();
        }
        let output = match periodic.as_mut() {
            Some(p) => p.compute_in_cell(cell.as_ref(), &atoms, params, Replicate::default())?,
            None => engine.engine().compute(&atoms, params)?,
        };
        let compute_ms = ms_since(t1);
        let wall_ms = ms_since(t0);
        // What `surface --per-residue` adds to the frame (file cases; synthetic ones have no
        // residues).
        let per_residue_ms = match &*source {
            Source::Real(sys) if args.per_residue => {
                let t2 = Instant::now();
                let effective = engine.engine().vertices().effective(params);
                let areas = measure::atom_areas_of(&output, &atoms, &effective)?;
                let topology = sys.trajectory.topology();
                let residues = measure::residue_areas(topology, sys.particles.subset(), &areas)?;
                std::hint::black_box(residues);
                Some(ms_since(t2))
            }
            _ => None,
        };
        (last_dims, last_triangles) = (output.grid.dims, output.triangle_count());
        if i == 0 {
            objects_after_first = gpu_objects(engine);
        }
        if i >= args.warmup as usize {
            reads.push(read_ms);
            computes.push(compute_ms);
            per_residue.extend(per_residue_ms);
            walls.push(wall_ms);
            stages.push(output.timings);
        }
    }
    let med = |f: &dyn Fn(&StageTimings) -> f64| median(stages.iter().map(f).collect());
    let wall = median(walls);
    Ok(BenchResult {
        case: String::new(),
        backend: match periodic {
            Some(_) => format!("{} periodic", engine.name()),
            None => engine.name().to_string(),
        },
        gpu_bytes: engine.gpu_bytes(),
        atoms: positions.len(),
        spacing: params.spacing,
        dims: last_dims,
        triangles: last_triangles,
        read_ms: median(reads),
        stages: StageTimings {
            exposure_ms: med(&|s| s.exposure_ms),
            upload_ms: med(&|s| s.upload_ms),
            bin_ms: med(&|s| s.bin_ms),
            density_ms: med(&|s| s.density_ms),
            mc_ms: med(&|s| s.mc_ms),
        },
        compute_wall_ms: median(computes),
        per_residue_ms: (!per_residue.is_empty()).then(|| median(per_residue)),
        fps: 1e3 / wall.max(1e-9),
        peak_rss: peak_rss_bytes(),
        bricks: match engine {
            BenchEngine::Cpu(e) => e.brick_stats(),
            BenchEngine::Gpu(e) => e.brick_stats(),
        },
        bricks_active_counted: matches!(engine, BenchEngine::Cpu(_)),
        gpu_objects_per_frame: gpu_objects(engine)
            .zip(objects_after_first)
            .map(|(now, first)| now.saturating_sub(first) as f64 / (total as f64 - 1.0).max(1.0)),
    })
}

/// Reads (or generates) the positions of the `i`-th timed frame; returns the frame's box
/// (rows a, b, c in Å; synthetic systems have none) and the time in ms.
fn read_frame(
    source: &mut Source,
    i: usize,
    out: &mut Vec<Vec3>,
) -> Result<(Option<[Vec3; 3]>, f64)> {
    match source {
        Source::Real(sys) => {
            let len = sys.len();
            if len == 0 {
                bail!("{}: no frames", sys.frames_path.display());
            }
            let (frame, ms) = sys.read_positions(i % len, out)?;
            Ok((frame.cell, ms))
        }
        Source::Synthetic(s) => {
            let t0 = Instant::now();
            s.frame_into(i, out);
            Ok((None, ms_since(t0)))
        }
    }
}

/// Median of `v` (0 for an empty list).
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::super::bench_args::parse_count;
    use super::*;

    #[test]
    fn counts_parse_with_suffixes() {
        assert_eq!(parse_count("1000000"), Ok(1_000_000));
        assert_eq!(parse_count("1e6"), Ok(1_000_000));
        assert_eq!(parse_count("2.37M"), Ok(2_370_000));
        assert_eq!(parse_count("950k"), Ok(950_000));
        assert!(parse_count("0").is_err());
        assert!(parse_count("lots").is_err());
    }

    #[test]
    fn median_of_even_and_odd() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(vec![]), 0.0);
    }
}
