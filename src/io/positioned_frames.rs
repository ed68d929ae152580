//! Trajectories whose frames lie at offsets computed from the header (DCD, Amber NetCDF): the
//! part every such reader shares. [`PositionedFrames`] holds the bytes (a local file or a URL,
//! [`Positioned`]), the number of frames found whole when the file opened, and the damage after
//! them; it answers [`NativeFrames`] once for every format. A format adds only a
//! [`FrameDecoder`]: how to read frame `k` from the bytes.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::IoError;
use super::native::{NativeFrames, NativeOpen};
use super::positioned::Positioned;
use super::prepare::Prepared;
use super::xdr_reader::ByteSource;
use crate::model::Frame;

/// What a format adds to [`PositionedFrames`]: reading one frame at its offsets.
pub(crate) trait FrameDecoder: Send + 'static {
    /// The format's name, as `FileFormat::base` spells it (`DCD`).
    const BASE: &'static str;
    /// Why a frame could not be read (one line once wrapped with the file and frame).
    type Error: std::fmt::Display;

    /// Reads frame `index` from `bytes`: positions in Å, box in Å, time in ps. `index` is below
    /// the frame count found when the file opened.
    fn read(&mut self, bytes: &Positioned, index: usize) -> Result<Frame, Self::Error>;
}

/// Where the bytes of a file opened by a positioned reader come from.
pub(crate) enum Bytes {
    /// The local file `Prepared::open_path` (the user's file, or its decompressed copy, which
    /// the reader keeps alive).
    Local(Prepared),
    /// `total` bytes read through range requests from a URL.
    #[cfg_attr(not(feature = "app"), allow(dead_code))]
    Remote {
        source: Box<dyn ByteSource>,
        total: u64,
    },
}

impl Bytes {
    /// Opens the bytes: the source to read, its length in bytes, and the copy to keep alive.
    /// Errors name `path`.
    pub(crate) fn open(self, path: &Path) -> Result<(Positioned, u64, Option<Prepared>), IoError> {
        match self {
            Bytes::Local(prepared) => {
                let (bytes, total) = Positioned::open_file(path, &prepared.open_path)?;
                Ok((bytes, total, Some(prepared)))
            }
            Bytes::Remote { source, total } => {
                Ok((Positioned::Source(Mutex::new(source)), total, None))
            }
        }
    }
}

/// An open file of a positioned format: its bytes, its readable frames and its decoder.
pub(crate) struct PositionedFrames<D> {
    /// The file as the user named it (for messages).
    path: PathBuf,
    bytes: Positioned,
    /// Frames found whole when the file opened.
    len: usize,
    /// Why frame `len` cannot be read, when the file holds more than `len` frames' bytes.
    damage: Option<IoError>,
    decoder: D,
    /// Keeps a decompressed copy alive (none over HTTP).
    _prepared: Option<Prepared>,
}

impl<D: FrameDecoder> PositionedFrames<D> {
    /// The opened file `path`: `len` readable frames in `bytes`, then `damage` (the reason
    /// frame `len` cannot be read), read by `decoder`. Fails with the damage, or with "no
    /// frames", when not even frame 0 can be read.
    pub(crate) fn open(
        path: &Path,
        (bytes, prepared): (Positioned, Option<Prepared>),
        len: usize,
        damage: Option<D::Error>,
        decoder: D,
        no_frames: impl std::fmt::Display,
    ) -> Result<NativeOpen, IoError> {
        let damage = damage.map(|reason| IoError::bad_frame(path, len, reason));
        if len == 0 {
            return Err(damage.unwrap_or_else(|| IoError::unreadable(path, no_frames)));
        }
        Ok(NativeOpen {
            topology: None,
            frames: Box::new(PositionedFrames {
                path: path.to_path_buf(),
                bytes,
                len,
                damage,
                decoder,
                _prepared: prepared,
            }),
        })
    }
}

impl<D: FrameDecoder> NativeFrames for PositionedFrames<D> {
    fn path(&self) -> &Path {
        &self.path
    }

    fn base(&self) -> &'static str {
        D::BASE
    }

    fn len(&self) -> usize {
        self.len
    }

    fn damage(&self) -> Option<&IoError> {
        self.damage.as_ref()
    }

    fn is_remote(&self) -> bool {
        self.bytes.is_remote()
    }

    fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        if index >= self.len {
            return Err(IoError::FrameOutOfRange {
                path: self.path.clone(),
                frame: index,
                len: self.len,
            });
        }
        let frame = self
            .decoder
            .read(&self.bytes, index)
            .map_err(|reason| IoError::bad_frame(&self.path, index, reason))?;
        Ok(Frame { index, ..frame })
    }
}
