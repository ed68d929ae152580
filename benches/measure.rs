//! Criterion benchmarks of what `surface --per-residue` adds to a frame, in one process on one
//! frame (`mdsurf bench --per-residue` times it between the frames' surfaces, where the caches
//! hold the surface's data instead): the area per vertex, per atom and per residue on adk in
//! water (47,681 atoms, `tests/data/adk_oplsaa.gro`) at the defaults (H = 1 Å, R = 1, I = 0.5,
//! quality medium), beside the CPU engine's frame. `cargo bench --bench measure`.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use mdsurf::io;
use mdsurf::measure::{atom_areas, residue_areas, vertex_areas};
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceParams};

fn per_residue(c: &mut Criterion) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let trajectory = io::open(&data.join("adk_oplsaa.gro"), None).expect("adk in water reads");
    let frame = trajectory.read_frame(0).expect("frame 0 reads");
    let topology = trajectory.topology();
    let particles =
        Particles::new(topology, &frame, &ParticleOptions::default()).expect("particles build");
    let positions = particles.positions(&frame).expect("positions");
    let atoms = AtomSet {
        positions: &positions,
        radii: particles.radii(),
        colours: Some(particles.colours()),
    };
    let params = SurfaceParams::default();
    let mut engine = CpuEngine::new();
    let output = engine.compute(&atoms, &params).expect("surface");
    let areas = atom_areas(&output.mesh, &atoms, &params).expect("atom areas");

    let mut group = c.benchmark_group("measure/adk_in_water");
    group.sample_size(20);
    group.bench_function("frame", |b| {
        b.iter(|| engine.compute(black_box(&atoms), &params).expect("surface"))
    });
    group.bench_function("vertex_areas", |b| {
        b.iter(|| vertex_areas(black_box(&output.mesh)).expect("vertex areas"))
    });
    group.bench_function("atom_areas", |b| {
        b.iter(|| atom_areas(black_box(&output.mesh), &atoms, &params).expect("atom areas"))
    });
    group.bench_function("residue_areas", |b| {
        b.iter(|| residue_areas(topology, particles.subset(), black_box(&areas)).expect("residues"))
    });
    group.finish();
}

criterion_group!(benches, per_residue);
criterion_main!(benches);
