//! Trajectory readers of our own, in Rust, for the formats MD users write most (GRO, LAMMPS
//! dump, DCD, Amber NetCDF): no C or C++ parser sees the bytes of these files in the process
//! that holds the user's work. Each reader indexes its file when it opens (where every frame
//! starts, and where the file stops being readable), then reads any frame on request.
//!
//! [`opener`] says which formats have one; [`super::trajectory`] uses it before falling back to
//! chemfiles in a reader process (`contained`). Each reader is compared with chemfiles on every
//! file of its format in `tests/data`.

use std::path::Path;

use super::IoError;
use super::format::FileFormat;
use super::positioned_frames::Bytes;
use super::prepare::Prepared;
use super::{dcd_frames, gro, lammps, netcdf};
use crate::model::{Frame, Topology};

/// An open trajectory file read by one of our readers: random access to its frames.
pub(crate) trait NativeFrames: Send {
    /// The file as the user named it (for messages).
    fn path(&self) -> &Path;

    /// The format's name, as [`FileFormat::base`] spells it (`GRO`).
    fn base(&self) -> &'static str;

    /// Number of readable frames (the frames before [`NativeFrames::damage`]).
    fn len(&self) -> usize;

    /// Where the file stops being readable, when it does: an error naming frame
    /// [`NativeFrames::len`] (a cut or damaged frame), found when the file was indexed.
    fn damage(&self) -> Option<&IoError>;

    /// True when the frames are read from a URL (through range requests), not a file.
    fn is_remote(&self) -> bool {
        false
    }

    /// Reads frame `index` (from 0, below [`NativeFrames::len`]): positions in Å, box in Å,
    /// time in ps. Fails with a one-line [`IoError`] naming the file and frame.
    fn read_frame(&mut self, index: usize) -> Result<Frame, IoError>;
}

/// A file opened by one of our readers.
pub(crate) struct NativeOpen {
    /// The atoms, for formats that carry names (GRO, LAMMPS dump): as the chemfiles path leaves
    /// them before [`Topology::complete_elements_and_radii`] (radii still 0). `None` for
    /// coordinate-only formats (DCD, NetCDF).
    pub topology: Option<Topology>,
    /// The frames.
    pub frames: Box<dyn NativeFrames>,
}

/// Opens `path` (the user's file; `prepared` holds the bytes to read, decompressed when the file
/// was compressed, and must be kept alive by the reader).
pub(crate) type Opener = fn(path: &Path, prepared: Prepared) -> Result<NativeOpen, IoError>;

/// Our reader for `format`, or `None` when the format is left to chemfiles.
pub(crate) fn opener(format: &FileFormat) -> Option<Opener> {
    if std::env::var_os("MDSURF_NO_NATIVE_READ").is_some() {
        return None;
    }
    match format.base {
        "DCD" => Some(|path, prepared| dcd_frames::open(path, Bytes::Local(prepared))),
        "Amber NetCDF" => Some(|path, prepared| netcdf::open(path, Bytes::Local(prepared))),
        "GRO" => Some(gro::open),
        "LAMMPS" => Some(lammps::open),
        _ => None,
    }
}
