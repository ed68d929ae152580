//! Files given as URLs (`http://`, `https://`) to [`super::open`]. A topology file is small: it
//! is downloaded whole into a temporary folder (kept as long as the trajectory) and opened as
//! a local file. An XTC, TRR, DCD or Amber NetCDF trajectory (not compressed) is read in place
//! through range requests ([`RangeSource`]): XTC and TRR frame headers are walked first (only
//! their blocks are fetched; a progress bar on stderr when it is a terminal), DCD and NetCDF
//! frames lie at offsets the header gives (nothing but the header is read at open); then each
//! frame is fetched when read. Any other trajectory (TNG, read by the TNG library; a compressed
//! file; LAMMPS, XYZ, ...) cannot be read in place: it is downloaded whole into the temporary
//! folder, with a note on stderr naming its size, and opened as a local file.

use std::io::IsTerminal;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use super::frame_source::FrameSource;
use super::{Damage, Readers, Trajectory, check_walk_atoms, open_with};
use crate::io::format::{FileFormat, detect_name};
use crate::io::http::{self, READ_AHEAD_BYTES, RangeSource};
use crate::io::positioned_frames::Bytes;
use crate::io::xdr_reader::{XdrKind, XdrReader};
use crate::io::{IoError, dcd_frames, netcdf, xdr};

/// True when `top` or `traj` is a URL.
pub(super) fn is_remote(top: &Path, traj: Option<&Path>) -> bool {
    http::url_of(top).is_some() || traj.is_some_and(|t| http::url_of(t).is_some())
}

/// True when a trajectory in `format` is read in place over HTTP (range requests); the others
/// are downloaded whole.
fn read_in_place(format: &FileFormat) -> bool {
    format.chemfiles == format.base && matches!(format.base, "XTC" | "TRR" | "DCD" | "Amber NetCDF")
}

/// [`super::open`] where `top` or `traj` is a URL.
pub(super) fn open(top: &Path, traj: Option<&Path>) -> Result<Trajectory, IoError> {
    // An unknown extension is refused before anything is downloaded.
    detect_name(top)?;
    let traj_format = traj.map(detect_name).transpose()?;
    let mut folder = None;
    let local_top = match http::url_of(top) {
        Some(url) => http::download(top, url, download_folder(&mut folder, top)?, None)?,
        None => top.to_path_buf(),
    };
    let local_traj = match (traj, &traj_format) {
        (Some(path), Some(format)) => match http::url_of(path) {
            Some(url) if !read_in_place(format) => {
                let why = if format.chemfiles != format.base {
                    "a compressed file is read from a local copy".to_string()
                } else {
                    format!("{} files are read from a local copy", format.base)
                };
                // Its own folder: a topology of the same file name stays as it is.
                let dir = download_folder(&mut folder, path)?.join("trajectory");
                std::fs::create_dir(&dir).map_err(|e| IoError::unreadable(path, e))?;
                Some(http::download(path, url, &dir, Some(&why))?)
            }
            _ => Some(path.to_path_buf()),
        },
        _ => None,
    };
    // (local copy, URL) of what was downloaded: errors name the URL the user gave.
    let mut downloaded = Vec::new();
    if local_top != top {
        downloaded.push((local_top.clone(), top.to_path_buf()));
    }
    if let (Some(local), Some(given)) = (&local_traj, traj)
        && local != given
    {
        downloaded.push((local.clone(), given.to_path_buf()));
    }
    let rename = |e: IoError| {
        downloaded
            .iter()
            .fold(e, |e, (local, url)| e.renamed(local, url))
    };
    let mut trajectory =
        open_with(&local_top, local_traj.as_deref(), Readers::Ours).map_err(rename)?;
    trajectory.topology_path = top.to_path_buf();
    trajectory.frames_path = traj.unwrap_or(top).to_path_buf();
    trajectory._download = folder;
    if let Some(damage) = trajectory.damage.take() {
        trajectory.damage = Some(Damage {
            frame: damage.frame,
            error: rename(damage.error),
        });
    }
    trajectory.downloaded = downloaded;
    Ok(trajectory)
}

/// The temporary folder downloads go to (made on first use; removed with the trajectory).
fn download_folder<'a>(
    folder: &'a mut Option<tempfile::TempDir>,
    path: &Path,
) -> Result<&'a Path, IoError> {
    if folder.is_none() {
        let dir = tempfile::Builder::new()
            .prefix("mdsurf-http")
            .tempdir()
            .map_err(|e| IoError::unreadable(path, format!("no temporary folder: {e}")))?;
        *folder = Some(dir);
    }
    Ok(folder.as_ref().map(|d| d.path()).unwrap_or(Path::new(".")))
}

/// The frames of the trajectory at the URL `path` (XTC, TRR, DCD or Amber NetCDF; see
/// [`read_in_place`]), for a topology `top` of `topology_atoms` atoms: a reader over range
/// requests, and the header walk of an XTC or TRR file.
pub(super) fn open_frames(
    path: &Path,
    top: &Path,
    topology_atoms: usize,
) -> Result<(FrameSource, Option<xdr::Walk>), IoError> {
    let url = http::url_of(path).unwrap_or_default();
    let format = detect_name(path)?;
    let kind = match format.base {
        _ if !read_in_place(&format) => {
            return Err(IoError::unreadable(
                path,
                "only XTC, TRR, DCD and Amber NetCDF trajectories are read over HTTP in place",
            ));
        }
        "XTC" => XdrKind::Xtc,
        "TRR" => XdrKind::Trr,
        // Frames at offsets the header gives: the header is read, then the frames asked for.
        base => {
            let mut source = RangeSource::open(path, url)?;
            source.set_read_ahead(READ_AHEAD_BYTES);
            let size = source.size();
            let open = match base {
                "DCD" => dcd_frames::open,
                _ => netcdf::open,
            };
            let bytes = Bytes::Remote {
                source: Box::new(source),
                total: size,
            };
            let opened = open(path, bytes)?;
            return Ok((FrameSource::Native(opened.frames), None));
        }
    };
    let mut source = RangeSource::open(path, url)?;
    let size = source.size();
    let bar = index_bar(url, size);
    let walked = xdr::walk_source(&mut source, size, format.base, &mut |at| {
        bar.set_position(at)
    });
    bar.finish_and_clear();
    let walk = walked
        .map_err(|reason| match reason.remote() {
            Some(network) => IoError::unreadable(path, network),
            None => IoError::bad_frame(path, 0, reason),
        })?
        .ok_or_else(|| IoError::unreadable(path, "not an XTC or TRR file"))?;
    check_walk_atoms(top, topology_atoms, path, &walk)?;
    source.set_read_ahead(READ_AHEAD_BYTES);
    let reader = XdrReader::from_source(path, Box::new(source), size, kind, &walk);
    Ok((FrameSource::Xdr(reader), Some(walk)))
}

/// A bar of the bytes walked while the frame index builds, on stderr when it is a terminal
/// (hidden otherwise).
fn index_bar(url: &str, size: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(size);
    if let Ok(style) =
        ProgressStyle::with_template("indexing {msg} {bar:30} {bytes}/{total_bytes} {eta}")
    {
        bar.set_style(style);
    }
    bar.set_message(http::file_name(url).to_string());
    bar
}
