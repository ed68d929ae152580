//! What every fuzz target does: the input becomes a file with the extension of the target's
//! format (mdsurf picks the reader by the file name), which `mdsurf::io::read_whole_file` opens
//! and reads frame by frame. Errors are the expected outcome for most inputs; a panic, an abort,
//! a sanitizer report, a time-out or an out-of-memory is a finding.

use std::cell::RefCell;

thread_local! {
    /// One folder per process (in memory when `/dev/shm` exists), reused for every input.
    static DIR: RefCell<Option<tempfile::TempDir>> = const { RefCell::new(None) };
}

/// Writes `data` to `input.<ext>` and reads it whole; the result is dropped.
pub fn read_as(ext: &str, data: &[u8]) {
    let path = DIR.with(|dir| {
        let mut dir = dir.borrow_mut();
        let dir = dir.get_or_insert_with(|| {
            let shm = std::path::Path::new("/dev/shm");
            let made = if shm.is_dir() {
                tempfile::tempdir_in(shm)
            } else {
                tempfile::tempdir()
            };
            made.expect("a temporary folder")
        });
        dir.path().join(format!("input.{ext}"))
    });
    std::fs::write(&path, data).expect("the input file is written");
    let _ = mdsurf::io::read_whole_file(&path);
}
