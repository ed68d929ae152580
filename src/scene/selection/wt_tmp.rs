#[test]
fn wt_timing() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let t = crate::io::open(&data.join("adk_oplsaa.gro"), None).unwrap();
    let f = t.read_frame(0).unwrap();
    let prot = super::Selection::parse("protein").unwrap().bind(t.topology()).indices(&f);
    let all = vec![true; f.positions.len()];
    let b = super::Selection::parse("within 5 of protein").unwrap().bind(t.topology());
    for _ in 0..3 { let s = std::time::Instant::now(); let n = b.indices(&f).len(); eprintln!("total {:?} {n}", s.elapsed()); }
    for _ in 0..3 { let s = std::time::Instant::now(); let n = super::within::within(&f.positions, f.cell.as_ref(), &prot, &all, 5.0); eprintln!("within {:?} {}", s.elapsed(), n.len()); }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| for _ in 0..3 { let s = std::time::Instant::now(); let n = super::within::within(&f.positions, f.cell.as_ref(), &prot, &all, 5.0); eprintln!("within 1thread {:?} {}", s.elapsed(), n.len()); });
    let s = std::time::Instant::now(); let mut k = 0.0f32; for p in &f.positions { k += (glam::Mat3::IDENTITY * *p).floor().x; } eprintln!("loop {:?} {k}", s.elapsed());
}
#[test]
fn wt_count() {
    use std::sync::atomic::Ordering::Relaxed;
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let t = crate::io::open(&data.join("adk_oplsaa.gro"), None).unwrap();
    let f = t.read_frame(0).unwrap();
    let prot = super::Selection::parse("protein").unwrap().bind(t.topology()).indices(&f);
    let all = vec![true; f.positions.len()];
    let s = std::time::Instant::now(); let n = super::within::within(&f.positions, f.cell.as_ref(), &prot, &all, 5.0); eprintln!("within {:?} {}", s.elapsed(), n.len());
    use super::within::*;
    eprintln!("near {} rows {} pts {} own {}", NEAR.load(Relaxed), ROWS.load(Relaxed), PTS.load(Relaxed), OWN.load(Relaxed));
}
