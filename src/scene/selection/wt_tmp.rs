#[test]
fn wt_timing() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let t = crate::io::open(&data.join("adk_oplsaa.gro"), None).unwrap();
    let f = t.read_frame(0).unwrap();
    eprintln!("cell {:?}", f.cell);
    let b = super::Selection::parse("within 5 of protein").unwrap().bind(t.topology());
    for _ in 0..3 { let s = std::time::Instant::now(); let n = b.indices(&f).len(); eprintln!("total {:?} {n}", s.elapsed()); }
}
