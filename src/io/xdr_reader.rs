//! Memory-safe readers for GROMACS XTC and TRR frames, used instead of chemfiles' C decoder
//! (xdrfile), which corrupts the heap on damaged data. The frames' offsets come from the header
//! walk in [`super::xdr`], which has already checked every header and that each frame fits in
//! the file; XTC frames are then decoded by the `molly` crate (pure Rust), TRR frames (plain XDR
//! reals) here. Positions and boxes are converted from nm to Å, times are in ps.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::Vec3;
use molly::XTCReader;
use molly::selection::AtomSelection;

use super::frame_checks::check_positions;
use super::prepare::Prepared;
use super::xdr::{Walk, trr_blocks};
use super::xdr_error::XdrError;
use super::{IoError, quiet};
use crate::model::Frame;

/// Å per nm.
const ANGSTROM_PER_NM: f32 = 10.0;

/// Which of the two GROMACS formats a file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum XdrKind {
    /// Compressed positions (`.xtc`).
    Xtc,
    /// Full-precision positions, velocities and forces (`.trr`).
    Trr,
}

/// Where an [`XdrReader`] reads bytes: a file, or a URL read through range requests
/// (`super::http`).
pub(crate) trait ByteSource: Read + Seek + Send {}

impl<T: Read + Seek + Send> ByteSource for T {}

/// One open XTC or TRR file with the offsets of its readable frames.
pub(crate) struct XdrReader {
    path: PathBuf,
    kind: XdrKind,
    natoms: usize,
    /// Byte offset of each readable frame.
    offsets: Vec<u64>,
    /// The open file or remote source (molly's reader wraps it; TRR frames are read from it
    /// directly).
    reader: XTCReader<Box<dyn ByteSource>>,
    /// The file's size in bytes.
    size: u64,
    /// True when the bytes come from a URL (range requests), not a file.
    remote: bool,
    /// Keeps a decompressed copy alive while it is read.
    _copy: Option<tempfile::TempDir>,
    /// Decoded XTC frame, reused between reads.
    xtc_frame: molly::Frame,
    /// Scratch for molly's decoder, reused between reads.
    scratch: Vec<u8>,
}

impl XdrReader {
    /// A reader of the frames `walk` found sound in `prepared` (the user's file `path`, or its
    /// decompressed copy).
    pub(crate) fn new(
        path: &Path,
        prepared: Prepared,
        kind: XdrKind,
        walk: &Walk,
    ) -> Result<Self, IoError> {
        let file = File::open(&prepared.open_path)
            .map_err(|e| IoError::unreadable(path, e.to_string()))?;
        let size = file
            .metadata()
            .map_err(|e| IoError::unreadable(path, e.to_string()))?
            .len();
        let mut reader = Self::from_source(path, Box::new(file), size, kind, walk);
        reader._copy = prepared.temp;
        reader.remote = false;
        Ok(reader)
    }

    /// A reader of the frames `walk` found sound in `source` (`size` bytes), which holds the
    /// user's file `path`: a URL read through range requests ([`XdrReader::is_remote`]).
    pub(crate) fn from_source(
        path: &Path,
        source: Box<dyn ByteSource>,
        size: u64,
        kind: XdrKind,
        walk: &Walk,
    ) -> Self {
        XdrReader {
            path: path.to_path_buf(),
            kind,
            natoms: walk.natoms,
            offsets: walk.offsets.clone(),
            reader: XTCReader::new(source),
            size,
            remote: true,
            _copy: None,
            xtc_frame: molly::Frame::default(),
            scratch: Vec::new(),
        }
    }

    /// The file read.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// True when the frames are read from a URL (through range requests).
    pub(crate) fn is_remote(&self) -> bool {
        self.remote
    }

    /// The format name, as chemfiles spells it (`XTC`, `TRR`).
    pub(crate) fn base(&self) -> &'static str {
        match self.kind {
            XdrKind::Xtc => "XTC",
            XdrKind::Trr => "TRR",
        }
    }

    /// Number of readable frames.
    pub(crate) fn len(&self) -> usize {
        self.offsets.len()
    }

    /// Reads frame `index` (from 0): positions and box in Å, time in ps.
    pub(crate) fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        let Some(&offset) = self.offsets.get(index) else {
            return Err(IoError::FrameOutOfRange {
                path: self.path.clone(),
                frame: index,
                len: self.offsets.len(),
            });
        };
        let parts = match self.kind {
            XdrKind::Xtc => self.read_xtc(offset),
            XdrKind::Trr => read_trr(&mut self.reader.file, self.size, self.natoms, offset),
        };
        let (positions, cell, time) =
            parts.map_err(|message| IoError::bad_frame(&self.path, index, message))?;
        check_positions(&self.path, index, &positions)?;
        Ok(Frame {
            index,
            time_ps: time.is_finite().then_some(time),
            positions,
            cell,
        })
    }

    fn read_xtc(&mut self, offset: u64) -> Result<FrameParts, XdrError> {
        let (reader, frame, scratch) = (&mut self.reader, &mut self.xtc_frame, &mut self.scratch);
        // The header walk has checked this frame's header and size; a panic inside the decoder
        // on damaged compressed data is the last line of defence, reported as damage.
        let read = quiet::silenced(|| {
            reader.file.seek(SeekFrom::Start(offset))?;
            reader.read_frame_with_scratch(frame, scratch, &AtomSelection::All)
        })
        .map_err(|()| XdrError::CompressedDamaged)?;
        read.map_err(|e| XdrError::Decode(std::sync::Arc::new(e)))?;
        if frame.positions.len() != 3 * self.natoms {
            return Err(XdrError::DecodedAtoms {
                decoded: frame.positions.len() / 3,
                expected: self.natoms,
            });
        }
        let positions = frame
            .positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]) * ANGSTROM_PER_NM)
            .collect();
        let b = frame.boxvec;
        // molly keeps the box as columns = the box vectors a, b, c.
        let rows: [Vec3; 3] =
            std::array::from_fn(|k| Vec3::new(b[3 * k], b[3 * k + 1], b[3 * k + 2]));
        Ok((positions, cell_from_rows(rows), f64::from(frame.time)))
    }
}

/// Positions (Å), box rows (Å) and time (ps) of one frame.
type FrameParts = (Vec<Vec3>, Option<[Vec3; 3]>, f64);

/// A box of all zeros means no box (GROMACS writes one for a non-periodic run).
fn cell_from_rows(rows_nm: [Vec3; 3]) -> Option<[Vec3; 3]> {
    let rows = rows_nm.map(|r| r * ANGSTROM_PER_NM);
    (rows.iter().all(|r| r.is_finite()) && rows.iter().any(|r| *r != Vec3::ZERO)).then_some(rows)
}

/// Reads the TRR frame at `offset`: its positions (`natoms` of them), box and time.
fn read_trr(
    file: &mut (impl Read + Seek),
    size: u64,
    natoms: usize,
    offset: u64,
) -> Result<FrameParts, XdrError> {
    let blocks = trr_blocks(file, size, offset)?;
    let x_at = blocks.x_at.ok_or(XdrError::NoPositions)?;
    let time = reals(file, blocks.time_at, 1, blocks.real)?[0];
    let cell = match blocks.box_at {
        Some(at) => {
            let b = reals(file, at, 9, blocks.real)?;
            let rows = std::array::from_fn(|k| {
                Vec3::new(b[3 * k] as f32, b[3 * k + 1] as f32, b[3 * k + 2] as f32)
            });
            cell_from_rows(rows)
        }
        None => None,
    };
    let x = reals(file, x_at, 3 * natoms, blocks.real)?;
    let positions = x
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * ANGSTROM_PER_NM)
        .collect();
    Ok((positions, cell, time))
}

/// Reads `count` big-endian reals of `real` bytes (4 or 8) at `offset`.
fn reals(
    file: &mut (impl Read + Seek),
    offset: u64,
    count: usize,
    real: u64,
) -> Result<Vec<f64>, XdrError> {
    let mut bytes = vec![0u8; count * real as usize];
    file.seek(SeekFrom::Start(offset))
        .and_then(|_| file.read_exact(&mut bytes))
        .map_err(|e| XdrError::FrameData(std::sync::Arc::new(e)))?;
    Ok(if real == 8 {
        bytes
            .chunks_exact(8)
            .map(|c| f64::from_be_bytes(c.try_into().unwrap_or([0; 8])))
            .collect()
    } else {
        bytes
            .chunks_exact(4)
            .map(|c| f64::from(f32::from_be_bytes(c.try_into().unwrap_or([0; 4]))))
            .collect()
    })
}
