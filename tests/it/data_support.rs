//! Where the integration tests find the real structures and trajectories: `tests/data` in the
//! repository (copies of `tests/data`; see its README for sources, licences and atom/frame
//! counts). A missing
//! file fails the test with a message; it is never skipped. Also a small damaged trajectory the
//! tests write themselves.

use std::path::{Path, PathBuf};

/// The shared data folder, with a trailing slash.
pub const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/");

/// Path of the data file `name`; panics with a clear message when it is missing.
pub fn data(name: &str) -> PathBuf {
    let path = Path::new(DATA).join(name);
    assert!(
        path.is_file(),
        "test data {} is missing (see tests/data/README.md)",
        path.display()
    );
    path
}

/// The text of the gzip-compressed data file `name`.
#[allow(dead_code)] // not every test file that includes this module reads one
pub fn gunzipped(name: &str) -> String {
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut flate2::read::GzDecoder::new(std::fs::File::open(data(name)).expect("open")),
        &mut text,
    )
    .expect("gzip text");
    text
}

/// A 3-frame PDB + DCD pair whose frame 1 has a NaN coordinate.
#[allow(dead_code)] // not every test file that includes this module writes one
pub fn nan_trajectory(dir: &Path) -> mdsurf::io::Trajectory {
    let make = |k: usize, bad: bool| {
        let mut f = chemfiles::Frame::new();
        for i in 0..10 {
            let y = if bad && k == 1 && i == 4 {
                f64::NAN
            } else {
                i as f64 * 1.2 + k as f64 * 0.1
            };
            f.add_atom(&chemfiles::Atom::new("O"), [i as f64, y, 0.0], None);
        }
        f
    };
    let (top, traj) = (dir.join("t.pdb"), dir.join("t.dcd"));
    chemfiles::Trajectory::open(&top, 'w')
        .expect("pdb")
        .write(&make(0, false))
        .expect("write");
    let mut t = chemfiles::Trajectory::open(&traj, 'w').expect("dcd");
    (0..3).for_each(|k| t.write(&make(k, true)).expect("write"));
    drop(t);
    mdsurf::io::open(&top, Some(&traj)).expect("open")
}
