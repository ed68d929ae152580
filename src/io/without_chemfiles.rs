//! The contained reader in a build without the `chemfiles` feature: there is no C++ reader to
//! contain, so a file our own readers leave to chemfiles (a TNG file; a PDB or XYZ file with
//! several frames, a cut compressed stream, or lines our fast readers do not take) fails with
//! one line naming the file and saying that this build reads it only with that feature. Same
//! calls as the real `contained::ContainedReader`, on a type that has no values.

use std::path::Path;

use glam::Vec3;

use super::IoError;
use super::format::FileFormat;
use crate::model::{Frame, Topology};

/// For `main`: a build without chemfiles has no reader mode; always `None`.
pub fn reader_main() -> Option<i32> {
    None
}

/// A file read through chemfiles, which this build cannot do: no value of it exists.
pub(crate) enum ContainedReader {}

impl ContainedReader {
    /// Always fails: the one-line error saying this build reads `path` (in `format`) only
    /// with the `chemfiles` feature.
    pub(crate) fn open(path: &Path, format: &FileFormat, _contain: bool) -> Result<Self, IoError> {
        Err(needs_chemfiles(path, format))
    }

    pub(crate) fn path(&self) -> &Path {
        match *self {}
    }

    pub(crate) fn base(&self) -> &'static str {
        match *self {}
    }

    pub(crate) fn len(&self) -> usize {
        match *self {}
    }

    pub(crate) fn truncated(&self) -> Option<(&str, bool)> {
        match *self {}
    }

    pub(crate) fn read_frame(&mut self, _index: usize) -> Result<Frame, IoError> {
        match *self {}
    }

    pub(crate) fn read_positions(&mut self, _index: usize) -> Result<Vec<Vec3>, IoError> {
        match *self {}
    }

    pub(crate) fn read_topology(&mut self, _index: usize) -> Result<Topology, IoError> {
        match *self {}
    }
}

/// The error for `path`, a file in `format` that only chemfiles reads.
fn needs_chemfiles(path: &Path, format: &FileFormat) -> IoError {
    let what = match format.base {
        "PDB" | "XYZ" => format!(
            "{} files like this one (several frames, a cut stream, or lines our reader leaves \
             to chemfiles)",
            format.base
        ),
        base => format!("{base} files"),
    };
    IoError::unreadable(
        path,
        format!("this build of mdsurf reads {what} only with the chemfiles feature"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tng_file_is_one_line_naming_file_and_feature() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("run.tng");
        std::fs::write(&path, b"GENERAL INFO").expect("write");
        let format = crate::io::detect(&path).expect("known format");
        let Err(error) = ContainedReader::open(&path, &format, true);
        let line = error.to_string();
        assert!(!line.contains('\n'), "{line}");
        assert!(line.starts_with(&path.display().to_string()), "{line}");
        assert!(
            line.contains("reads TNG files only with the chemfiles feature"),
            "{line}"
        );
    }
}
