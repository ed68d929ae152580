//! [`open`] and [`Trajectory`]: a topology file plus an optional trajectory file become one
//! thread-safe source of frames with random access. Frames are read on demand (one at a time,
//! under an interior mutex), checked against the topology's atom count and for finite
//! coordinates.
//!
//! - `frame_source`: the reader behind a trajectory (chemfiles, ours, XTC/TRR, memory).
//! - `checks`: what `open` checks once the files are open (damage, cut streams, models).
//! - `growing`: trajectories whose frames keep coming (IMD, a file being written).

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use super::contained::ContainedReader;
use super::format::{FileFormat, detect};
use super::frame_checks::check_positions;
use super::live::LiveCount;
use super::native;
use super::prepare::{prepare, read_all};
use super::xdr_reader::{XdrKind, XdrReader};
use super::{IoError, fast, mmcif, wwpdb, xdr};

use crate::model::{Frame, Topology, sizing};

mod checks;
mod frame_source;
mod growing;
#[cfg(feature = "app")]
mod remote;

use frame_source::{FirstFrame, FrameSource};
pub use growing::{open_following, open_growing, open_live};

/// How many frames at the end of a file are probed for damage when it opens (a truncated
/// file loses its last frame or two; probing every frame of a long trajectory would be slow).
const TAIL_PROBE: usize = 4;

/// Where a damaged (truncated or corrupt) trajectory stops being readable.
#[derive(Debug, Clone, PartialEq)]
pub struct Damage {
    /// Index of the first unreadable frame (from 0); equal to [`Trajectory::len`].
    pub frame: usize,
    /// The error reading it gives.
    pub error: IoError,
}

/// A structure and its frames, read lazily from disk.
///
/// `Send + Sync`: frames may be read from any thread (reads are serialised by a mutex).
pub struct Trajectory {
    topology: Topology,
    topology_path: PathBuf,
    frames_path: PathBuf,
    reader: Mutex<FrameSource>,
    len: usize,
    damage: Option<Damage>,
    /// Frames received so far, for a running simulation ([`open_live`]).
    live: Option<LiveCount>,
    /// The folder holding a topology downloaded from a URL, kept while the trajectory lives.
    _download: Option<tempfile::TempDir>,
    /// (local copy, URL) of each downloaded file: errors name the URL.
    downloaded: Vec<(PathBuf, PathBuf)>,
}

impl std::fmt::Debug for Trajectory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Trajectory")
            .field("topology", &self.topology_path)
            .field("frames", &self.frames_path)
            .field("atoms", &self.topology.len())
            .field("len", &self.len)
            .field("damage", &self.damage)
            .finish()
    }
}

/// Opens `top` (a structure file with atom names: PDB, mmCIF, GRO, LAMMPS dump, XYZ, TNG, ...)
/// and, when given, `traj` (the frames: XTC, TRR, DCD, NetCDF, or any format above). Without
/// `traj` the frames come from `top` itself (a multi-model PDB, a GRO or LAMMPS trajectory).
///
/// Fails with a one-line [`IoError`] when a file is missing, has an unknown extension, cannot be
/// parsed, holds no atoms or frames, or when the two files disagree on the atom count. A
/// trajectory whose last frames are damaged (truncated) still opens: [`Trajectory::len`] counts
/// the good frames and [`Trajectory::damage`] says where it breaks.
///
/// mmCIF files (plain or compressed) are read by our own reader (`mmcif`), never by chemfiles;
/// large plain PDB and XYZ files by our fast readers (see `fast`); every other file by
/// chemfiles, in a reader process (see `contained`: a crash there is an error naming the frame;
/// one on the last frames, probed at open, makes them [`Damage`]). Setting the environment
/// variable `MDSURF_NO_FAST_READ` sends PDB and XYZ files to chemfiles too, and
/// `MDSURF_IN_PROCESS_READ` runs chemfiles in this process (for timing the paths against each
/// other).
pub fn open(top: &Path, traj: Option<&Path>) -> Result<Trajectory, IoError> {
    #[cfg(feature = "app")]
    if remote::is_remote(top, traj) {
        return remote::open(top, traj);
    }
    open_with(top, traj, Readers::Ours)
}

/// [`open`] with every file read through chemfiles, never a fast reader and never our mmCIF
/// reader, and chemfiles run in this process, not in a reader process: the reference those
/// readers are tested against (tests and benchmarks only; chemfiles' mmCIF reader crashes on
/// some legal files, and a damaged file can crash this process).
#[cfg(feature = "chemfiles")]
pub fn open_via_chemfiles(top: &Path, traj: Option<&Path>) -> Result<Trajectory, IoError> {
    open_with(top, traj, Readers::ChemfilesInProcess)
}

/// [`open`] with the formats our native readers take (GRO, LAMMPS dump, DCD, Amber NetCDF)
/// read by chemfiles in its reader process instead, as before those readers existed: how the
/// tests reach the reader process's crash handling with files that crash chemfiles. The same
/// as `open` under the environment variable `MDSURF_NO_NATIVE_READ`.
#[cfg(feature = "chemfiles")]
pub fn open_via_reader_process(top: &Path, traj: Option<&Path>) -> Result<Trajectory, IoError> {
    open_with(top, traj, Readers::ChemfilesContained)
}

/// Which readers [`open_with`] may use (without the `chemfiles` feature, always `Ours`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(feature = "chemfiles"), allow(dead_code))]
enum Readers {
    /// Ours (mmCIF, fast PDB/XYZ, XTC/TRR, the native readers), chemfiles in a reader process
    /// for the rest.
    Ours,
    /// Ours except the native readers; chemfiles in a reader process for the rest.
    ChemfilesContained,
    /// Chemfiles in this process for every file but XTC/TRR.
    ChemfilesInProcess,
}

/// True when `path` is a file our own readers read: an mmCIF file, or a plain single-frame PDB
/// or XYZ file a fast reader reproduces exactly; false for every other file, which goes through
/// chemfiles.
pub fn reads_fast(path: &Path) -> Result<bool, IoError> {
    let format = detect(path)?;
    Ok(format.base == "mmCIF" || fast::read(path, &format).is_some())
}

/// Reads the mmCIF file `path` with our reader: every model as a frame, and why a compressed
/// stream ends early when it does.
fn read_cif(path: &Path, format: &FileFormat) -> Result<(mmcif::CifRead, Option<String>), IoError> {
    let (bytes, truncated) = read_all(path, format)?;
    Ok((mmcif::read(path, &bytes)?, truncated))
}

/// Opens with the `readers` allowed (see [`Readers`]).
fn open_with(top: &Path, traj: Option<&Path>, readers: Readers) -> Result<Trajectory, IoError> {
    let allow_fast = readers != Readers::ChemfilesInProcess;
    let native_for = |format: &FileFormat| match readers {
        Readers::Ours => native::opener(format),
        _ => None,
    };
    let top_format = detect(top)?;
    if traj.is_none() && !top_format.has_names {
        return Err(IoError::NeedsTopology {
            path: top.to_path_buf(),
        });
    }
    // mmCIF files: our reader. Large plain PDB and XYZ files: read once, in Rust (see `fast`).
    // Everything else through chemfiles.
    let mut later_models = None;
    let ours = if allow_fast && top_format.base == "mmCIF" {
        let (read, truncated) = read_cif(top, &top_format)?;
        let mut frames = read.frames.into_iter();
        let first = frames.next().unwrap_or_default();
        later_models = Some((frames.collect::<Vec<_>>(), truncated));
        Some(fast::FastRead {
            topology: read.topology,
            frame: first,
        })
    } else {
        allow_fast.then(|| fast::read(top, &top_format)).flatten()
    };
    let native_top = native_for(&top_format);
    let (mut topology, first, top_reader) = match (ours, native_top) {
        (Some(read), _) => (read.topology, FirstFrame::Read(read.frame), None),
        (None, Some(open)) => {
            let opened = open(top, prepare(top, &top_format)?)?;
            let mut frames = opened.frames;
            let topology = opened.topology.unwrap_or_default();
            let first = match (frames.len(), frames.damage()) {
                (0, Some(damage)) => return Err(damage.clone()),
                _ => frames.read_frame(0)?,
            };
            let source = FrameSource::Native(frames);
            (topology, FirstFrame::Read(first), Some(source))
        }
        (None, None) => {
            let mut reader = ContainedReader::open(top, &top_format, allow_fast)?;
            let topology = reader.read_topology(0)?;
            let positions = if topology.is_empty() {
                Vec::new()
            } else {
                reader.read_positions(0)?
            };
            let source = FrameSource::Chem(reader);
            (topology, FirstFrame::Positions(positions), Some(source))
        }
    };
    if topology.is_empty() {
        return Err(IoError::Empty {
            path: top.to_path_buf(),
            what: "no atoms",
        });
    }
    if let (Some(format), FirstFrame::Positions(first)) = (top_format.wwpdb, &first) {
        wwpdb::enrich(top, format, &mut topology, first);
        if format == super::format::WwFormat::Pdb {
            super::conect::apply_conect(top, &mut topology);
        }
    }
    topology.complete_elements_and_radii();
    sizing::fit_untyped_radii(&mut topology, first.positions());
    let mut walk = None;
    let reader = match (traj, top_reader, first) {
        (None, Some(reader), _) => reader,
        (None, None, first) => {
            let (later, truncated) = later_models.unwrap_or_default();
            let mut frames = vec![first.into_frame()];
            frames.extend(later);
            FrameSource::Memory {
                path: top.to_path_buf(),
                base: top_format.base,
                frames,
                truncated,
            }
        }
        #[cfg(feature = "app")]
        (Some(path), _, _) if super::http::url_of(path).is_some() => {
            let (source, w) = remote::open_frames(path, top, topology.len())?;
            walk = w;
            source
        }
        (Some(path), top_reader, _) => {
            let format = detect(path)?;
            drop(top_reader);
            // XTC and TRR (also compressed): the frame headers are checked, then the frames
            // are read in Rust.
            let kind = match format.base {
                "XTC" => Some(XdrKind::Xtc),
                "TRR" => Some(XdrKind::Trr),
                _ => None,
            };
            match kind {
                // An mmCIF trajectory: every model, read by our reader.
                None if allow_fast && format.base == "mmCIF" => {
                    let (read, truncated) = read_cif(path, &format)?;
                    FrameSource::Memory {
                        path: path.to_path_buf(),
                        base: format.base,
                        frames: read.frames,
                        truncated,
                    }
                }
                Some(kind) => {
                    let prepared = prepare(path, &format)?;
                    let w = xdr::walk(&prepared.open_path, format.base)
                        .map_err(|reason| IoError::bad_frame(path, 0, reason))?
                        .ok_or_else(|| IoError::unreadable(path, "not an XTC or TRR file"))?;
                    check_walk_atoms(top, topology.len(), path, &w)?;
                    let reader = XdrReader::new(path, prepared, kind, &w)?;
                    walk = Some(w);
                    FrameSource::Xdr(reader)
                }
                None => match native_for(&format) {
                    Some(open) => FrameSource::Native(open(path, prepare(path, &format)?)?.frames),
                    None => FrameSource::Chem(ContainedReader::open(path, &format, allow_fast)?),
                },
            }
        }
    };
    let mut trajectory = Trajectory {
        topology,
        topology_path: top.to_path_buf(),
        frames_path: reader.path().to_path_buf(),
        len: reader.len(),
        reader: Mutex::new(reader),
        damage: None,
        live: None,
        _download: None,
        downloaded: Vec::new(),
    };
    if let Some(w) = walk {
        trajectory.apply_walk(w)?;
    }
    trajectory.apply_native_damage()?;
    trajectory.mark_truncated_stream()?;
    trajectory.check_pdb_models()?;
    // A count mismatch is reported at once, not at the first frame the user asks for.
    trajectory.check_first_frame()?;
    trajectory.probe_tail();
    trajectory.check_dcd_size();
    Ok(trajectory)
}

/// Fails unless the XTC/TRR file `path` (its header walk `walk`) has as many atoms as the
/// topology `top` (`topology_atoms`).
fn check_walk_atoms(
    top: &Path,
    topology_atoms: usize,
    path: &Path,
    walk: &xdr::Walk,
) -> Result<(), IoError> {
    if walk.natoms != topology_atoms {
        return Err(IoError::AtomCountMismatch {
            topology: top.to_path_buf(),
            topology_atoms,
            trajectory: path.to_path_buf(),
            trajectory_atoms: walk.natoms,
            frame: 0,
        });
    }
    Ok(())
}

impl Trajectory {
    /// The atoms (constant over the trajectory).
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The file the frames are read from (the trajectory file, or the topology file when it is
    /// its own trajectory).
    pub fn path(&self) -> &Path {
        &self.frames_path
    }

    /// The topology file.
    pub fn topology_path(&self) -> &Path {
        &self.topology_path
    }

    /// Number of readable frames (frames from [`Trajectory::damage`] on are not counted).
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there is no readable frame (never the case for an opened trajectory).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Where the file is damaged, if its last frames could not be read when it was opened.
    pub fn damage(&self) -> Option<&Damage> {
        self.damage.as_ref()
    }

    /// Reads frame `index` (from 0): positions in Å, box in Å, time in ps.
    ///
    /// Fails with [`IoError::FrameOutOfRange`] past the end, the damage error at the damaged
    /// frame, [`IoError::BadFrame`] for an unreadable frame, [`IoError::AtomCountMismatch`] when
    /// the frame's atom count differs from the topology's, and
    /// [`IoError::NonFiniteCoordinate`] (naming frame and atom) for NaN or infinite positions.
    pub fn read_frame(&self, index: usize) -> Result<Frame, IoError> {
        if let Some(damage) = &self.damage
            && index == damage.frame
        {
            return Err(damage.error.clone());
        }
        if index >= self.len {
            return Err(IoError::FrameOutOfRange {
                path: self.frames_path.clone(),
                frame: index,
                len: self.len,
            });
        }
        let frame = self
            .lock()
            .read_frame(index)
            .map_err(|e| self.named_as_given(e))?;
        self.check_fits(&frame, index)?;
        Ok(frame)
    }

    /// `error` naming the URLs of downloaded files instead of their local copies.
    fn named_as_given(&self, error: IoError) -> IoError {
        self.downloaded
            .iter()
            .fold(error, |e, (local, url)| e.renamed(local, url))
    }

    /// Fails unless `frame` (frame `index`) has one position per topology atom.
    fn check_fits(&self, frame: &Frame, index: usize) -> Result<(), IoError> {
        if frame.positions.len() != self.topology.len() {
            return Err(IoError::AtomCountMismatch {
                topology: self.topology_path.clone(),
                topology_atoms: self.topology.len(),
                trajectory: self.frames_path.clone(),
                trajectory_atoms: frame.positions.len(),
                frame: index,
            });
        }
        Ok(())
    }

    /// What [`Trajectory::read_frame`]`(0)` checks, without handing the frame out: a frame
    /// held in memory (read at open) is checked in place, not copied.
    fn check_first_frame(&self) -> Result<(), IoError> {
        if let FrameSource::Memory { path, frames, .. } = &*self.lock()
            && let Some(frame) = frames.first()
        {
            check_positions(path, 0, &frame.positions)?;
            return self.check_fits(frame, 0);
        }
        self.read_frame(0).map(drop)
    }

    /// Reads frames `start..end` (clamped to the readable frames) one after the other, calling
    /// `visit` with each result; stops early when `visit` returns false.
    pub fn for_each_frame(
        &self,
        start: usize,
        end: usize,
        mut visit: impl FnMut(Result<Frame, IoError>) -> bool,
    ) {
        for index in start..end.min(self.len) {
            if !visit(self.read_frame(index)) {
                break;
            }
        }
    }

    fn lock(&self) -> MutexGuard<'_, FrameSource> {
        // A panic while holding the lock cannot leave our state inconsistent (the reader is
        // re-positioned on every read), so a poisoned lock is still usable.
        self.reader
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}
