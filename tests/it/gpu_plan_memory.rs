//! GPU memory known without a device: the byte count of `mdsurf::gpu::plan::BufferPlan` equals
//! what the engine holds (`GpuEngine::gpu_bytes`) after frames on a real protein, a synthetic
//! tiled system and a forced multi-slab frame whose mesh overflowed its first buffers; the
//! device-free Table 1 sizing matches the engine on a small row and is what `mdsurf bench
//! --table1 --plan-only` prints; and the paper's largest row (22.8M atoms at H = 4) fits an
//! 80 GB GPU under the limits wgpu reports on NVIDIA.

use std::path::Path;

use mdsurf::gpu::engine::{Changes, EngineOptions};
use mdsurf::gpu::plan::{
    BYTES_PER_ATOM, BufferPlan, DEFAULT_HEADROOM, DeviceLimits, MeshCapacity, count_reached_bricks,
    first_mesh_want, settled_brick_slots,
};
use mdsurf::gpu::table1::{
    GPU_80GB, MeshSizing, PAPER_ROWS, PaperRow, Structure, Table1Options, plan_rows, run_rows,
};
use mdsurf::gpu::{GpuContext, GpuEngine};

use crate::gpu_support::context;
use mdsurf::surface::{AtomSet, SurfaceParams};
use mdsurf::synthetic::SyntheticSystem;

fn structure(path: &str) -> Structure {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    Structure::from_file(&file, None).expect("structure")
}

/// Runs two frames of `atoms` (the second re-runs Marching Cubes only, in buffers grown after
/// the first) and checks the device-free count against the engine's; returns the slabs used.
fn estimate_matches(
    ctx: &GpuContext,
    options: impl FnOnce(EngineOptions) -> EngineOptions,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> usize {
    let mut engine = GpuEngine::with_context(ctx.clone()).expect("engine");
    let defaults = engine.options();
    let limits = ctx.device_limits();
    // The device-free sizing assumes the engine's defaults.
    assert_eq!(defaults.volume_budget, limits.volume_budget());
    assert_eq!(defaults.headroom, DEFAULT_HEADROOM);
    let opts = options(defaults);
    engine.set_options(opts);
    let full = engine
        .run_blocking(atoms, params, Changes::ALL)
        .expect("frame");
    let stats = engine
        .run_blocking(atoms, params, Changes::default())
        .expect("second frame");
    assert!(!stats.overflow && stats.triangle_count > 0, "{stats:?}");
    let plan = engine.plan().expect("plan").clone();
    let first = opts
        .initial_mesh_capacity
        .map(|(v, t)| (v as u64, t as u64))
        .unwrap_or_else(|| first_mesh_want(&plan));
    let counts = (stats.vertex_count as u64, stats.triangle_count as u64);
    let mesh = MeshCapacity::settled(first, counts, opts.headroom, limits.max_binding());
    let n = atoms.positions.len() as u64;
    let with_colour = atoms.colours.is_some();
    // On sparse bricks the density and colour buffers hold the reached bricks' slots; the host
    // counts the bricks the GPU reaches.
    let host = count_reached_bricks(
        &plan,
        atoms.positions,
        atoms.radii,
        params.radius_scale,
        params.cutoff(),
    );
    let slots = opts.sparse_bricks.then(|| {
        assert_eq!(host.total(), stats.reached_bricks as u64, "reached bricks");
        // The density pass (of the full frame) reports the slots it needed.
        assert_eq!(
            host.slab_need(&plan),
            full.brick_slots as u64,
            "brick slots"
        );
        settled_brick_slots(&plan, host.slab_need(&plan), limits.max_binding())
    });
    let memory = BufferPlan::new(&plan, n, with_colour, mesh, slots, &limits).fresh_memory();
    assert_eq!(memory.total(), engine.gpu_bytes(), "{memory:?}");
    assert!(memory.atoms >= n * BYTES_PER_ATOM && memory.mesh > 0 && memory.volumes > 0);
    plan.slabs.len()
}

#[test]
fn gpu_memory_estimate_equals_the_engine_on_1hpv() {
    let Some(ctx) = context() else { return };
    let s = structure("tests/data/1hpv.pdb");
    let atoms = AtomSet {
        positions: &s.positions,
        radii: &s.radii,
        colours: s.colours.as_deref(),
    };
    let slabs = estimate_matches(&ctx, |o| o, &atoms, &SurfaceParams::default());
    assert_eq!(slabs, 1);
}

#[test]
fn gpu_memory_estimate_equals_the_engine_on_a_synthetic_system() {
    let Some(ctx) = context() else { return };
    let s = structure("tests/data/1hpv.pdb");
    let n = 3 * s.positions.len() + 100;
    let system = SyntheticSystem::tile(&s.positions, &s.radii, None, n).expect("tiling");
    let positions = system.frame(0);
    let atoms = AtomSet {
        positions: &positions,
        radii: system.radii(),
        colours: None,
    };
    let params = SurfaceParams {
        spacing: 1.5,
        ..SurfaceParams::default()
    };
    estimate_matches(&ctx, |o| o, &atoms, &params);
}

#[test]
fn gpu_memory_estimate_equals_the_engine_over_slabs_after_an_overflow() {
    let Some(ctx) = context() else { return };
    let s = structure("tests/data/1hpv.pdb");
    let atoms = AtomSet {
        positions: &s.positions,
        radii: &s.radii,
        colours: s.colours.as_deref(),
    };
    let params = SurfaceParams {
        spacing: 1.5,
        ..SurfaceParams::default()
    };
    // Slabs of 6 layers, and mesh buffers far too small for the first frame: it overflows,
    // the buffers grow by the engine's rule and Marching Cubes re-runs.
    let slabs = estimate_matches(
        &ctx,
        |o| EngineOptions {
            max_slab_layers: Some(6),
            initial_mesh_capacity: Some((64, 64)),
            ..o
        },
        &atoms,
        &params,
    );
    assert!(slabs > 2, "{slabs} slabs");
}

#[test]
fn gpu_table1_plan_equals_the_engine_on_a_small_row() {
    let Some(ctx) = context() else { return };
    let demo = structure("assets/md_1u19.gro");
    let row = PaperRow {
        atoms: 12_000,
        spacing: 2.0,
        t_sort: 0.001,
        t_d: 0.001,
        t_mc: 0.001,
    };
    let opts = Table1Options {
        repeats: 1,
        ..Default::default()
    };
    let run = run_rows(&ctx, &demo, &[row], &opts, |_| {}).expect("table row");
    let limits = ctx.device_limits();
    let planned = plan_rows(
        &demo,
        &[row],
        &opts,
        &limits,
        MeshSizing::CpuSurface,
        |_| {},
    )
    .expect("plan");
    let (r, p) = (&run[0], &planned[0]);
    assert_eq!((p.atoms, p.grid, p.slabs), (r.atoms, r.grid, r.slabs));
    assert_eq!(p.memory.total(), r.gpu_bytes, "{p:?}");
    // The bound (mesh buffers at the largest binding) is at least the sized memory.
    assert!(p.bound.total() >= p.memory.total());
}

/// The table rows (whitespace-separated fields) `mdsurf bench --table1 --plan-only --backend
/// cpu EXTRA...` prints; the command must succeed.
fn plan_only_rows(extra: &[&str]) -> Vec<Vec<String>> {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["bench", "--table1", "--plan-only", "--backend", "cpu"];
    args.extend_from_slice(extra);
    let run = crate::cli_common::mdsurf(dir.path(), &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    run.stdout
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .collect()
}

/// No GPU needed: the paper's largest row, 22.8M atoms at H = 4, sized under the limits wgpu
/// reports on an 80 GB NVIDIA GPU with every mesh buffer at its largest (`--mesh-bound`: an
/// upper bound for any surface; the CPU surface takes too long for a test), fits 80 GB. Run
/// through the binary, so that the test process never holds 22.8M atoms (children inherit
/// its peak memory in `wait4`, which `io_mutants` reads).
#[test]
fn gpu_table1_largest_row_fits_80_gb() {
    let rows = plan_only_rows(&["--mesh-bound"]);
    let row = rows
        .iter()
        .find(|r| r.first().map(String::as_str) == Some("22800000"))
        .unwrap_or_else(|| panic!("no 22.8M row in {rows:?}"));
    // atoms H grid slabs vertices triangles | atoms cells volumes bricks mesh fixed |
    // total bound fits
    assert_eq!(row.len(), 17, "{row:?}");
    assert_eq!(row[1], "4.0");
    let voxels: u64 = row[2]
        .split('x')
        .map(|d| d.parse::<u64>().unwrap())
        .product();
    assert!(voxels > 1_000_000, "{row:?}");
    let mib = |s: &String| s.parse::<f64>().unwrap();
    let atoms_mib = (22_800_000 * BYTES_PER_ATOM) as f64 / (1u64 << 20) as f64;
    assert!(mib(&row[7]) >= atoms_mib.floor(), "{row:?}");
    assert_eq!(row[14], row[15], "with --mesh-bound the total is the bound");
    let limit_mib = GPU_80GB as f64 / (1u64 << 20) as f64;
    assert!(mib(&row[15]) <= limit_mib, "{} MiB > 80 GB", row[15]);
    assert_eq!(row[16], "yes");
}

/// No GPU needed: `mdsurf bench --table1 --plan-only` prints the library's sizing of each row
/// (here the smallest, on the bundled demo's first trajectory frame, as the command tiles it).
#[test]
fn gpu_table1_plan_only_command_prints_the_plan() {
    let rows = plan_only_rows(&["--max-atoms", "150k"]);
    assert_eq!(rows.len(), 1, "{rows:?}");
    let row = &rows[0];
    assert_eq!(row[0], "147976");
    assert_eq!(row.last().map(String::as_str), Some("yes"));

    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let demo = Structure::from_file(
        &root.join("assets/md_1u19.gro"),
        Some(&root.join("assets/md_1u19.xtc")),
    )
    .expect("demo");
    let planned = plan_rows(
        &demo,
        &PAPER_ROWS[..1],
        &Table1Options::default(),
        &DeviceLimits::NVIDIA_80GB,
        MeshSizing::CpuSurface,
        |_| {},
    )
    .expect("plan");
    let p = &planned[0];
    let mib = |b: u64| format!("{:.0}", b as f64 / (1u64 << 20) as f64);
    let total_and_bound = &row[row.len() - 3..row.len() - 1];
    assert_eq!(
        total_and_bound,
        [mib(p.memory.total()), mib(p.bound.total())],
        "{row:?}"
    );
    let counts = p.counts.expect("CPU counts");
    assert_eq!(row[4..6], [counts.0.to_string(), counts.1.to_string()]);

    let dir = tempfile::tempdir().unwrap();
    let alone = crate::cli_common::mdsurf(dir.path(), &["bench", "--plan-only"]);
    assert_eq!(alone.code, 2, "{}", alone.stderr);
}
