//! Files given as URLs (`http://`, `https://`) to [`super::open`]. A topology file is small: it
//! is downloaded whole into a temporary folder (kept as long as the trajectory) and opened as
//! a local file. An XTC or TRR trajectory is read in place through range requests
//! ([`RangeSource`]): its frame headers are walked first (only their blocks are fetched; a
//! progress bar on stderr when it is a terminal), then each frame is fetched when read. Other
//! trajectory formats over HTTP are refused with one line.

use std::io::IsTerminal;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use super::frame_source::FrameSource;
use super::{Readers, Trajectory, check_walk_atoms, open_with};
use crate::io::format::detect_name;
use crate::io::http::{self, READ_AHEAD_BYTES, RangeSource};
use crate::io::xdr_reader::{XdrKind, XdrReader};
use crate::io::{IoError, xdr};

/// True when `top` or `traj` is a URL.
pub(super) fn is_remote(top: &Path, traj: Option<&Path>) -> bool {
    http::url_of(top).is_some() || traj.is_some_and(|t| http::url_of(t).is_some())
}

/// [`super::open`] where `top` or `traj` is a URL.
pub(super) fn open(top: &Path, traj: Option<&Path>) -> Result<Trajectory, IoError> {
    let mut download = None;
    let local_top = match http::url_of(top) {
        Some(url) => {
            // An unknown extension is refused before anything is downloaded.
            detect_name(top)?;
            let dir = tempfile::Builder::new()
                .prefix("mdsurf-http")
                .tempdir()
                .map_err(|e| IoError::unreadable(top, format!("no temporary folder: {e}")))?;
            let file = http::download(top, url, dir.path())?;
            download = Some(dir);
            file
        }
        None => top.to_path_buf(),
    };
    let mut trajectory = open_with(&local_top, traj, Readers::Ours)?;
    trajectory.topology_path = top.to_path_buf();
    if traj.is_none() {
        trajectory.frames_path = top.to_path_buf();
    }
    trajectory._download = download;
    Ok(trajectory)
}

/// The frames of the XTC or TRR file at the URL `path`, for a topology `top` of
/// `topology_atoms` atoms: its header walk and a reader over range requests.
pub(super) fn open_frames(
    path: &Path,
    top: &Path,
    topology_atoms: usize,
) -> Result<(FrameSource, xdr::Walk), IoError> {
    let url = http::url_of(path).unwrap_or_default();
    let format = detect_name(path)?;
    let kind = match format.base {
        _ if format.chemfiles != format.base => None,
        "XTC" => Some(XdrKind::Xtc),
        "TRR" => Some(XdrKind::Trr),
        _ => None,
    };
    let Some(kind) = kind else {
        return Err(IoError::unreadable(
            path,
            "only XTC and TRR trajectories (and topology files) can be read over HTTP",
        ));
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
    Ok((FrameSource::Xdr(reader), walk))
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
