//! Criterion benchmarks of the surface engines, stage by stage: the CPU reference (binning +
//! density, Marching Cubes) and, where an adapter exists, the GPU engine's whole frame.
//!
//! Cases: the bundled demo (rhodopsin, 5,547 atoms) at H = 1 Å, and a synthetic 200,000-atom
//! system tiled from it. `cargo bench --bench surface`; `mdsurf bench` gives the same stages as
//! medians without criterion, and `mdsurf bench --table1` the paper's Table 1 rows.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use mdsurf::io;
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::surface::{
    AtomSet, CpuEngine, GridSpec, Quality, SurfaceEngine, SurfaceParams, density, marching_cubes,
};
use mdsurf::synthetic::SyntheticSystem;

/// Atoms of the synthetic case.
const SYNTHETIC_ATOMS: usize = 200_000;

/// Positions (Å), radii (Å) and colours of the demo's first frame.
fn demo_atoms() -> (Vec<glam::Vec3>, Vec<f32>, Vec<[f32; 3]>) {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let trajectory = io::open(
        &assets.join("md_1u19.gro"),
        Some(&assets.join("md_1u19.xtc")),
    )
    .expect("the bundled demo trajectory reads");
    let frame = trajectory.read_frame(0).expect("demo frame 0 reads");
    let particles = Particles::new(trajectory.topology(), &frame, &ParticleOptions::default())
        .expect("demo particles build");
    let positions = particles.positions(&frame).expect("demo positions");
    (
        positions,
        particles.radii().to_vec(),
        particles.colours().to_vec(),
    )
}

/// Benchmarks the CPU stages on one system under `params`.
fn bench_cpu_stages(c: &mut Criterion, label: &str, atoms: &AtomSet<'_>, params: &SurfaceParams) {
    let grid = GridSpec::for_atoms(atoms.positions, atoms.radii, params).expect("grid");
    let mut group = c.benchmark_group(format!("cpu/{label}"));
    group.sample_size(10);
    group.bench_function("density", |b| {
        b.iter(|| density::compute(black_box(atoms), params, &grid).expect("density"))
    });
    let volume = density::compute(atoms, params, &grid).expect("density");
    group.bench_function("marching_cubes", |b| {
        b.iter(|| marching_cubes::extract(&grid, black_box(&volume), params.isovalue))
    });
    let mut engine = CpuEngine::new();
    group.bench_function("frame", |b| {
        b.iter(|| engine.compute(black_box(atoms), params).expect("surface"))
    });
    group.finish();
}

/// Benchmarks the GPU engine's whole frame (upload to mesh counters), when an adapter exists.
fn bench_gpu_frame(c: &mut Criterion, label: &str, atoms: &AtomSet<'_>, params: &SurfaceParams) {
    let mut engine = match mdsurf::gpu::GpuEngine::new() {
        Ok(engine) => engine,
        Err(err) => {
            eprintln!("no GPU benchmark: {err}");
            return;
        }
    };
    let mut group = c.benchmark_group(format!("gpu/{label}"));
    group.sample_size(10);
    group.bench_function("frame", |b| {
        b.iter(|| engine.compute(black_box(atoms), params).expect("surface"))
    });
    group.finish();
}

fn surfaces(c: &mut Criterion) {
    let params = SurfaceParams {
        spacing: 1.0,
        radius_scale: 1.0,
        isovalue: 0.5,
        quality: Quality::High,
    };
    let (positions, radii, colours) = demo_atoms();
    let demo = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: Some(&colours),
    };
    bench_cpu_stages(c, "demo", &demo, &params);
    bench_gpu_frame(c, "demo", &demo, &params);

    let synthetic = SyntheticSystem::tile(&positions, &radii, Some(&colours), SYNTHETIC_ATOMS)
        .expect("synthetic system");
    let tiled = synthetic.frame(0);
    let big = AtomSet {
        positions: &tiled,
        radii: synthetic.radii(),
        colours: synthetic.colours(),
    };
    bench_cpu_stages(c, "synthetic_200k", &big, &params);
    bench_gpu_frame(c, "synthetic_200k", &big, &params);
}

criterion_group!(benches, surfaces);
criterion_main!(benches);
