use std::path::Path;
const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/");
fn try_cut(top: &str, traj: &str, ext: &str, keep: f64) {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(Path::new(DATA).join(traj)).unwrap();
    let n = (bytes.len() as f64 * keep) as usize;
    let p = dir.path().join(format!("cut.{ext}"));
    std::fs::write(&p, &bytes[..n]).unwrap();
    match mdsurf::io::open(&Path::new(DATA).join(top), Some(&p)) {
        Ok(t) => {
            println!(
                "{traj} keep {keep}: len {} damage {:?}",
                t.len(),
                t.damage().map(|d| d.error.to_string())
            );
            let last = t.len() - 1;
            println!(
                "  last {:?}",
                t.read_frame(last)
                    .map(|f| f.positions.len())
                    .map_err(|e| e.to_string())
            );
        }
        Err(e) => println!("{traj} keep {keep}: ERR {e}"),
    }
    println!("  warnings {:?}", mdsurf::io::take_warnings());
}
#[test]
fn scratch() {
    for k in [0.999, 0.95, 0.5, 0.001] {
        try_cut("md_1u19.gro", "md_1u19.xtc", "xtc", k);
    }
    for k in [0.999, 0.95, 0.5, 0.001] {
        try_cut("adk_open.pdb", "adk_dims.dcd", "dcd", k);
    }
}
