//! Criterion benchmarks of what `surface --per-residue` adds to a frame, in one process on one
//! frame (`mdsurf bench --per-residue` times it between the frames' surfaces, where the caches
//! hold the surface's data instead): the area per vertex, per atom and per residue on adk in
//! water (47,681 atoms, `tests/data/adk_oplsaa.gro`) at the defaults (H = 1 Å, R = 1, I = 0.5,
//! quality medium), beside the CPU engine's frame. And what the buried area adds to a frame
//! whose surface is the complex (`interface_on`, no per-atom areas): its two sides with the
//! complex's density at hand (the larger side by difference), without it (both sampled), and
//! the two sides as surfaces of their own (the "two extra surfaces"), on adenylate
//! kinase's two domains (a dense grid) and on 7ddo's ACE2 and spike RBD (sparse bricks).
//! `cargo bench --bench measure`.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use mdsurf::io;
use mdsurf::measure::interface::Complex;
use mdsurf::measure::{atom_areas, interface_on, residue_areas, vertex_areas};
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::selection::Selection;
use mdsurf::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceOutput, SurfaceParams};

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

/// The positions (Å) and radii (Å) of the atoms `selection` picks in `file`'s first frame.
fn side(file: &str, selection: &str) -> (Vec<Vec3>, Vec<f32>) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let trajectory = io::open(&data.join(file), None).expect("the structure reads");
    let frame = trajectory.read_frame(0).expect("frame 0 reads");
    let topology = trajectory.topology();
    let particles =
        Particles::new(topology, &frame, &ParticleOptions::default()).expect("particles build");
    let positions = particles.positions(&frame).expect("positions");
    let picked = Selection::parse(selection)
        .expect("the selection parses")
        .bind(topology)
        .indices(&frame);
    let radii = particles.radii();
    picked
        .iter()
        .map(|&i| (positions[i as usize], radii[i as usize]))
        .unzip()
}

fn interface_sides(c: &mut Criterion) {
    let cases = [
        (
            "adk_domains",
            "adk_open.pdb",
            "protein and resid 1:59",
            "protein and resid 60:214",
        ),
        (
            "7ddo_ace2_rbd",
            "7ddo.pdb.gz",
            "protein and chain A",
            "protein and chain C",
        ),
    ];
    let params = SurfaceParams::default();
    for (name, file, sel_a, sel_b) in cases {
        let (a, b) = (side(file, sel_a), side(file, sel_b));
        let positions: Vec<Vec3> = a.0.iter().chain(&b.0).copied().collect();
        let radii: Vec<f32> = a.1.iter().chain(&b.1).copied().collect();
        let (set_a, set_b, both) = (set(&a.0, &a.1), set(&b.0, &b.1), set(&positions, &radii));
        let mut shown = CpuEngine::new();
        shown.set_keep_mesh(false);
        shown.set_keep_density(true);
        let with_density = shown.compute(&both, &params).expect("the complex");
        let without_density = without_density(&with_density);
        let a_at: Vec<u32> = (0..set_a.len() as u32).collect();
        let b_at: Vec<u32> = (set_a.len() as u32..both.len() as u32).collect();
        let complex = |output| Complex {
            output,
            atoms: both,
            a_at: &a_at,
            b_at: &b_at,
        };
        let mut engine = CpuEngine::new();
        let mut group = c.benchmark_group(format!("interface/{name}"));
        group.sample_size(20);
        group.bench_function("sides_by_difference", |bench| {
            let complex = complex(&with_density);
            bench.iter(|| interface_on(&mut engine, &set_a, &set_b, &complex, &params, false))
        });
        group.bench_function("sides_sampled", |bench| {
            let complex = complex(&without_density);
            bench.iter(|| interface_on(&mut engine, &set_a, &set_b, &complex, &params, false))
        });
        let mut own = CpuEngine::new();
        own.set_keep_mesh(false);
        group.bench_function("two_surfaces_of_their_own", |bench| {
            bench.iter(|| {
                let area_a = own.compute(black_box(&set_a), &params).expect("A").area;
                area_a + own.compute(black_box(&set_b), &params).expect("B").area
            })
        });
        group.finish();
    }
}

/// The atoms at `positions` (Å) with `radii` (Å), without colours.
fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

/// `output` without its kept density.
fn without_density(output: &SurfaceOutput) -> SurfaceOutput {
    SurfaceOutput {
        density: None,
        ..output.clone()
    }
}

criterion_group!(benches, per_residue, interface_sides);
criterion_main!(benches);
