//! What reading XTC in Rust costs against chemfiles' C decoder: every frame of
//! `tests/data/adk_oplsaa.xtc` (47,681 atoms, 10 frames) read through `mdsurf::io` (the header
//! walk, then molly's decoder, nm -> Å, coordinate checks) and through chemfiles directly.
//! `cargo bench --bench read`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn read_xtc(c: &mut Criterion) {
    let (gro, xtc) = (data("adk_oplsaa.gro"), data("adk_oplsaa.xtc"));
    let ours = mdsurf::io::open(&gro, Some(&xtc)).expect("opens");
    let frames = ours.len();
    let mut group = c.benchmark_group("read adk_oplsaa.xtc, every frame");
    group.sample_size(20);
    group.bench_function("mdsurf (walk + molly)", |b| {
        b.iter(|| {
            for k in 0..frames {
                black_box(ours.read_frame(k).expect("frame"));
            }
        })
    });
    group.bench_function("chemfiles (xdrfile C)", |b| {
        let mut t = chemfiles::Trajectory::open(&xtc, 'r').expect("opens");
        let mut frame = chemfiles::Frame::new();
        b.iter(|| {
            for k in 0..frames {
                t.read_step(k, &mut frame).expect("frame");
                black_box(frame.positions());
            }
        })
    });
    group.bench_function("open with mdsurf (walk + first frames)", |b| {
        b.iter(|| black_box(mdsurf::io::open(&gro, Some(&xtc)).expect("opens").len()))
    });
    group.finish();
}

criterion_group!(benches, read_xtc);
criterion_main!(benches);
