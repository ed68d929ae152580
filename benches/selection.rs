//! Criterion benchmarks of the selection language on adenylate kinase in water
//! (`tests/data/adk_oplsaa.gro`, 47,681 atoms, triclinic box): `within 5 of protein` per frame
//! (the cell-grid search with periodic images), a constant selection (cached mask), and parsing
//! plus binding. `cargo bench --bench selection`.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use mdsurf::io;
use mdsurf::selection::Selection;

fn selection(c: &mut Criterion) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let trajectory = io::open(&data.join("adk_oplsaa.gro"), None).expect("adk_oplsaa.gro reads");
    let frame = trajectory.read_frame(0).expect("frame 0 reads");
    let topology = trajectory.topology();

    let within = Selection::parse("within 5 of protein").expect("parses");
    let bound = within.bind(topology);
    c.bench_function("within 5 of protein (adk, 47681 atoms)", |b| {
        b.iter(|| black_box(bound.indices(black_box(&frame))))
    });

    let water = Selection::parse("water and within 3.5 of (protein and name NZ OE1 OE2)")
        .expect("parses")
        .bind(topology);
    c.bench_function("water near charged side chains (adk)", |b| {
        b.iter(|| black_box(water.indices(black_box(&frame))))
    });

    let constant = Selection::parse("protein and not hydrogen")
        .expect("parses")
        .bind(topology);
    c.bench_function("constant selection per frame (adk)", |b| {
        b.iter(|| black_box(constant.indices(black_box(&frame))))
    });

    c.bench_function(
        "parse + bind 'backbone or resname SOL and name OW' (adk)",
        |b| {
            b.iter(|| {
                let s = Selection::parse(black_box("backbone or resname SOL and name OW"));
                black_box(s.expect("parses").bind(topology))
            })
        },
    );
}

criterion_group!(benches, selection);
criterion_main!(benches);
