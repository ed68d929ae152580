//! Where a [`super::Trajectory`]'s frames come from: the reader behind it (chemfiles in its
//! process, one of our native readers, our XTC/TRR reader, or frames held in memory) and the
//! first frame of the topology file as its reader gave it.

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::io::IoError;
use crate::io::contained::ContainedReader;
use crate::io::frame_checks::check_positions;
use crate::io::native::NativeFrames;
use crate::io::xdr_reader::XdrReader;
use crate::model::Frame;

/// Frame 0 of the topology file as the reader gave it: a whole frame (fast path) or positions.
pub(super) enum FirstFrame {
    Read(Frame),
    Positions(Vec<Vec3>),
}

impl FirstFrame {
    /// Positions in Å.
    pub(super) fn positions(&self) -> &[Vec3] {
        match self {
            FirstFrame::Read(frame) => &frame.positions,
            FirstFrame::Positions(p) => p,
        }
    }

    /// The frame (the fast path always gives one; positions alone become a frame without box).
    pub(super) fn into_frame(self) -> Frame {
        match self {
            FirstFrame::Read(frame) => frame,
            FirstFrame::Positions(positions) => Frame {
                positions,
                ..Frame::default()
            },
        }
    }
}

/// Where frames come from: chemfiles, our own readers for XTC and TRR, or the frames a reader
/// of our own read with the topology (kept in memory: the one frame of a fast-read file, the
/// models of an mmCIF file).
pub(super) enum FrameSource {
    Chem(ContainedReader),
    Native(Box<dyn NativeFrames>),
    Xdr(XdrReader),
    Memory {
        path: PathBuf,
        base: &'static str,
        frames: Vec<Frame>,
        /// Why the compressed file ends early, when it does (its last frame is then cut).
        truncated: Option<String>,
    },
}

impl FrameSource {
    pub(super) fn path(&self) -> &Path {
        match self {
            FrameSource::Chem(r) => r.path(),
            FrameSource::Native(r) => r.path(),
            FrameSource::Xdr(r) => r.path(),
            FrameSource::Memory { path, .. } => path,
        }
    }

    pub(super) fn base(&self) -> &'static str {
        match self {
            FrameSource::Chem(r) => r.base(),
            FrameSource::Native(r) => r.base(),
            FrameSource::Xdr(r) => r.base(),
            FrameSource::Memory { base, .. } => base,
        }
    }

    pub(super) fn len(&self) -> usize {
        match self {
            FrameSource::Chem(r) => r.len(),
            FrameSource::Native(r) => r.len(),
            FrameSource::Xdr(r) => r.len(),
            FrameSource::Memory { frames, .. } => frames.len(),
        }
    }

    /// True when the frames come from a URL (through range requests).
    pub(super) fn is_remote(&self) -> bool {
        match self {
            FrameSource::Xdr(r) => r.is_remote(),
            FrameSource::Native(r) => r.is_remote(),
            FrameSource::Chem(_) | FrameSource::Memory { .. } => false,
        }
    }

    pub(super) fn truncated(&self) -> Option<(&str, bool)> {
        match self {
            FrameSource::Chem(r) => r.truncated(),
            FrameSource::Memory { truncated, .. } => truncated.as_deref().map(|t| (t, false)),
            FrameSource::Xdr(_) | FrameSource::Native(_) => None,
        }
    }

    pub(super) fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        match self {
            FrameSource::Chem(r) => r.read_frame(index),
            FrameSource::Native(r) => {
                let frame = r.read_frame(index)?;
                check_positions(r.path(), index, &frame.positions)?;
                Ok(frame)
            }
            FrameSource::Xdr(r) => r.read_frame(index),
            FrameSource::Memory { path, frames, .. } => {
                let Some(frame) = frames.get(index) else {
                    return Err(IoError::FrameOutOfRange {
                        path: path.clone(),
                        frame: index,
                        len: frames.len(),
                    });
                };
                check_positions(path, index, &frame.positions)?;
                Ok(frame.clone())
            }
        }
    }
}
