//! Reading the whole of one file, every frame, with the reader a user's run would use: the
//! entry point of the fuzz targets in `fuzz/` (one per reader), and a quick check of a file.
//! A file with atom names opens as its own trajectory ([`super::open`]: topology, checks,
//! first frame); a coordinate-only file (XTC, TRR, DCD, Amber NetCDF) is read by its reader
//! alone, with no topology to match. Any failure is a one-line [`IoError`], never a panic.

use std::path::Path;

use super::frame_checks::check_positions;
use super::prepare::prepare;
use super::xdr_reader::{XdrKind, XdrReader};
use super::{IoError, detect, native, xdr};

/// At most this many frames are read (a small file's header may announce millions).
pub const MAX_FRAMES: usize = 4096;

/// What reading a whole file found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WholeFile {
    /// Atoms of the topology (0 for a coordinate-only file).
    pub atoms: usize,
    /// Readable frames.
    pub frames: usize,
    /// Frames read without error (at most [`MAX_FRAMES`]).
    pub frames_read: usize,
    /// True when the file's last frames are damaged (cut or corrupt).
    pub damaged: bool,
}

/// Opens `path` (its format from its name, as [`super::detect`] decides) and reads its frames,
/// up to [`MAX_FRAMES`], stopping at the first that fails; fails when the file cannot be
/// opened. Every error is a one-line [`IoError`] naming the file.
pub fn read_whole_file(path: &Path) -> Result<WholeFile, IoError> {
    let format = detect(path)?;
    let kind = match format.base {
        "XTC" => Some(XdrKind::Xtc),
        "TRR" => Some(XdrKind::Trr),
        _ => None,
    };
    if let Some(kind) = kind {
        let prepared = prepare(path, &format)?;
        let walk = xdr::walk(&prepared.open_path, format.base)
            .map_err(|reason| IoError::bad_frame(path, 0, reason))?
            .ok_or_else(|| IoError::unreadable(path, "not an XTC or TRR file"))?;
        let mut reader = XdrReader::new(path, prepared, kind, &walk)?;
        let frames = reader.len();
        let frames_read = count_read(frames, |i| reader.read_frame(i).map(drop));
        return Ok(WholeFile {
            atoms: 0,
            frames,
            frames_read,
            damaged: walk.damage.is_some(),
        });
    }
    if !format.has_names
        && let Some(open) = native::opener(&format)
    {
        let mut frames = open(path, prepare(path, &format)?)?.frames;
        let len = frames.len();
        let frames_read = count_read(len, |i| {
            let frame = frames.read_frame(i)?;
            check_positions(path, i, &frame.positions)
        });
        return Ok(WholeFile {
            atoms: 0,
            frames: len,
            frames_read,
            damaged: frames.damage().is_some(),
        });
    }
    let trajectory = super::open(path, None)?;
    let frames = trajectory.len();
    let frames_read = count_read(frames, |i| trajectory.read_frame(i).map(drop));
    Ok(WholeFile {
        atoms: trajectory.topology().len(),
        frames,
        frames_read,
        damaged: trajectory.damage().is_some(),
    })
}

/// How many of the first `len` frames (at most [`MAX_FRAMES`]) `read` reads, in order, before
/// the first failure.
fn count_read(len: usize, mut read: impl FnMut(usize) -> Result<(), IoError>) -> usize {
    (0..len.min(MAX_FRAMES))
        .take_while(|&i| read(i).is_ok())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(name)
    }

    #[test]
    fn reads_every_frame_of_named_and_coordinate_files() {
        let gro = read_whole_file(&data("adk_oplsaa.gro")).expect("GRO");
        assert_eq!((gro.frames, gro.frames_read), (1, 1));
        assert!(gro.atoms > 40_000, "{gro:?}");
        let xtc = read_whole_file(&data("adk_oplsaa.xtc")).expect("XTC");
        assert_eq!(xtc.frames_read, xtc.frames.min(MAX_FRAMES));
        assert!(xtc.frames > 1 && !xtc.damaged, "{xtc:?}");
        let dcd = read_whole_file(&data("adk_dims.dcd")).expect("DCD");
        assert!(
            dcd.frames > 1 && dcd.frames_read == dcd.frames.min(MAX_FRAMES),
            "{dcd:?}"
        );
    }

    #[test]
    fn a_cut_xtc_is_damaged_not_a_panic() {
        let dir = tempfile::tempdir().expect("tempdir");
        let cut = dir.path().join("cut.xtc");
        let bytes = std::fs::read(data("adk_oplsaa.xtc")).expect("read");
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
        let read = read_whole_file(&cut).expect("the first frames are sound");
        assert!(read.damaged && read.frames_read == read.frames, "{read:?}");
        std::fs::write(&cut, &bytes[..10]).expect("write");
        let error = read_whole_file(&cut).expect_err("no sound frame");
        assert!(
            error.to_string().starts_with(&cut.display().to_string()),
            "{error}"
        );
    }
}
