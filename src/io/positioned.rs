//! Bytes read at given offsets, from a local file or from any `Read + Seek` source (a URL read
//! through range requests, `super::http`): what our DCD and Amber NetCDF readers read from, so
//! that they read a file over HTTP as they read it on disk. A local file is read with
//! positioned reads (`pread`), exactly as before; another source is read under a lock, after
//! a seek.

use std::fs::File;
use std::io::{self, SeekFrom};
use std::os::unix::fs::FileExt;
use std::sync::Mutex;

use super::IoError;
use super::xdr_reader::ByteSource;

/// Where a reader's bytes are: a file, or another source of `size` bytes.
pub(crate) enum Positioned {
    /// A local file (or a decompressed copy).
    File(File),
    /// A source read by seeking (a URL read through range requests).
    Source(Mutex<Box<dyn ByteSource>>),
}

impl Positioned {
    /// The local file at `open_path` (the user's file `path`, or its decompressed copy) and its
    /// length in bytes; errors name `path`.
    pub(crate) fn open_file(
        path: &std::path::Path,
        open_path: &std::path::Path,
    ) -> Result<(Positioned, u64), IoError> {
        let file = File::open(open_path).map_err(|e| IoError::NotFound {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let total = file
            .metadata()
            .map_err(|e| IoError::unreadable(path, e))?
            .len();
        Ok((Positioned::File(file), total))
    }

    /// Fills `buf` with the bytes at `offset` (bytes from the start).
    pub(crate) fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> io::Result<()> {
        match self {
            Positioned::File(file) => file.read_exact_at(buf, offset),
            Positioned::Source(source) => {
                let mut source = source
                    .lock()
                    .map_err(|_| io::Error::other("a reader of this source panicked"))?;
                source.seek(SeekFrom::Start(offset))?;
                source.read_exact(buf)
            }
        }
    }

    /// True when the bytes do not come from a local file (a URL).
    pub(crate) fn is_remote(&self) -> bool {
        matches!(self, Positioned::Source(_))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn a_file_and_a_source_read_the_same_bytes() {
        let bytes: Vec<u8> = (0..=255u8).cycle().take(10_000).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.bin");
        std::fs::write(&path, &bytes).unwrap();
        let file = Positioned::File(File::open(&path).unwrap());
        let source = Positioned::Source(Mutex::new(Box::new(Cursor::new(bytes.clone()))));
        assert!(!file.is_remote() && source.is_remote());
        for (offset, len) in [(0u64, 10usize), (9_990, 10), (4_000, 300)] {
            let (mut a, mut b) = (vec![0u8; len], vec![0u8; len]);
            file.read_exact_at(&mut a, offset).unwrap();
            source.read_exact_at(&mut b, offset).unwrap();
            assert_eq!(a, b);
            assert_eq!(a[..], bytes[offset as usize..offset as usize + len]);
        }
        let mut past = [0u8; 20];
        assert!(file.read_exact_at(&mut past, 9_990).is_err());
        assert!(source.read_exact_at(&mut past, 9_990).is_err());
    }
}
