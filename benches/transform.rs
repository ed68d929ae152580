//! Criterion benchmarks of the per-frame transformations on adenylate kinase in water
//! (`tests/data/adk_oplsaa.gro` + `.xtc`, 47,681 atoms, triclinic box): make whole + centre
//! (protein) + fit (protein CA) on one frame, each step alone, and smoothing over ±5 frames
//! from transformed frames in memory. `cargo bench --bench transform`. Target: whole + centre +
//! fit within 3 ms per frame on 2 cores.

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use mdsurf::io;
use mdsurf::model::Frame;
use mdsurf::transform::{TransformChain, TransformOptions, smooth::smooth_frame};

fn transform(c: &mut Criterion) {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let trajectory = io::open(
        &data.join("adk_oplsaa.gro"),
        Some(&data.join("adk_oplsaa.xtc")),
    )
    .expect("adk_oplsaa reads");
    let topology = trajectory.topology();
    let first = trajectory.read_frame(0).expect("frame 0 reads");
    let frame = trajectory
        .read_frame(trajectory.len() - 1)
        .expect("last frame reads");
    let chain_for = |options: TransformOptions| {
        TransformChain::new(&options, topology, &first, None, "adk_oplsaa.xtc").expect("chain")
    };
    let all = chain_for(TransformOptions {
        whole: Some(true),
        center: Some("protein".into()),
        fit: Some("protein and name CA".into()),
        ..TransformOptions::default()
    });
    let steps = [
        ("whole + center + fit (adk, 47681 atoms)", all.clone()),
        (
            "whole (adk)",
            chain_for(TransformOptions {
                whole: Some(true),
                ..TransformOptions::default()
            }),
        ),
        (
            "center protein (adk, no whole)",
            chain_for(TransformOptions {
                whole: Some(false),
                center: Some("protein".into()),
                ..TransformOptions::default()
            }),
        ),
        (
            "fit protein CA (adk, no whole)",
            chain_for(TransformOptions {
                whole: Some(false),
                fit: Some("protein and name CA".into()),
                ..TransformOptions::default()
            }),
        ),
    ];
    for (name, chain) in &steps {
        c.bench_function(name, |b| {
            b.iter_batched_ref(
                || frame.clone(),
                |f| chain.apply(black_box(f)).expect("applies"),
                BatchSize::LargeInput,
            )
        });
    }

    let frames: Vec<Frame> = (0..trajectory.len())
        .map(|i| {
            let mut f = trajectory.read_frame(i).expect("frame reads");
            all.apply(&mut f).expect("applies");
            f
        })
        .collect();
    let len = frames.len();
    c.bench_function("smooth ±5 of transformed frames (adk)", |b| {
        b.iter(|| {
            black_box(smooth_frame(len / 2, len, 5, |j| Ok::<_, ()>(&frames[j])).expect("smooths"))
        })
    });
    c.bench_function("build chain: guessed bonds + molecules (adk)", |b| {
        b.iter(|| black_box(chain_for(TransformOptions::default())))
    });
}

criterion_group!(benches, transform);
criterion_main!(benches);
