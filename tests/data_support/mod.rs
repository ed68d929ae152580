//! Where the integration tests find the real structures and trajectories: `../shared/data`
//! beside the crate (see its README for sources, licences and atom/frame counts). A missing
//! file fails the test with a message; it is never skipped.

use std::path::{Path, PathBuf};

/// The shared data folder, with a trailing slash.
pub const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/");

/// Path of the data file `name`; panics with a clear message when it is missing.
pub fn data(name: &str) -> PathBuf {
    let path = Path::new(DATA).join(name);
    assert!(
        path.is_file(),
        "test data {} is missing (see ../shared/data/README.md)",
        path.display()
    );
    path
}
