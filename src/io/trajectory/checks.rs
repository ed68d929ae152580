//! The checks [`super::open`] runs once a trajectory is open: the XTC/TRR header walk, damage
//! our readers found, a compressed stream cut short, PDB models, a DCD whose size disagrees
//! with its header, and the last frames probed for damage. Each shortens the readable frames
//! to the sound ones and records where the file breaks ([`Damage`]).

use super::{Damage, FrameSource, TAIL_PROBE, Trajectory};
use crate::io::format::detect;
use crate::io::prepare::read_all;
use crate::io::{IoError, dcd, pdb_models, xdr};

impl Trajectory {
    /// Limits the readable frames to those the XTC/TRR header walk found sound.
    pub(super) fn apply_walk(&mut self, walk: xdr::Walk) -> Result<(), IoError> {
        if walk.frames < self.len || walk.damage.is_some() {
            let frame = walk.frames.min(self.len);
            let message = walk
                .damage
                .unwrap_or_else(|| "the frame headers end here".to_string());
            let error = IoError::bad_frame(&self.frames_path, frame, message);
            if frame == 0 {
                return Err(error);
            }
            self.len = frame;
            self.damage = Some(Damage { frame, error });
        }
        Ok(())
    }

    /// Limits the readable frames to those our reader found sound when it indexed the file.
    pub(super) fn apply_native_damage(&mut self) -> Result<(), IoError> {
        let found = match &*self.lock() {
            FrameSource::Native(reader) => reader.damage().map(|e| (reader.len(), e.clone())),
            _ => None,
        };
        let Some((frame, error)) = found else {
            return Ok(());
        };
        if frame == 0 {
            return Err(error);
        }
        self.len = self.len.min(frame);
        self.damage = Some(Damage { frame, error });
        Ok(())
    }

    /// A compressed file whose stream is cut: its last decompressed frame is incomplete, so it
    /// is the damage (even when its text happens to parse).
    pub(super) fn mark_truncated_stream(&mut self) -> Result<(), IoError> {
        let Some((reason, removed)) = self.lock().truncated().map(|(t, r)| (t.to_string(), r))
        else {
            return Ok(());
        };
        let frame = if removed {
            self.len
        } else {
            self.len.saturating_sub(1)
        };
        let error = IoError::bad_frame(&self.frames_path, frame, reason);
        if frame == 0 {
            return Err(error);
        }
        self.len = frame;
        self.damage = Some(Damage { frame, error });
        Ok(())
    }

    /// A PDB file that ends inside a model: the whole models before it are the trajectory and
    /// the cut one is the damage (chemfiles dropped it, or read it with fewer atoms, silently);
    /// an error when no model is whole.
    pub(super) fn check_pdb_models(&mut self) -> Result<(), IoError> {
        let Ok(format) = detect(&self.frames_path) else {
            return Ok(());
        };
        if format.base != "PDB" {
            return Ok(());
        }
        let Ok((bytes, _)) = read_all(&self.frames_path, &format) else {
            return Ok(());
        };
        let Some((whole, message)) = pdb_models::cut_model(&bytes) else {
            return Ok(());
        };
        let error = IoError::bad_frame(&self.frames_path, whole, message);
        if whole == 0 {
            return Err(error);
        }
        if whole < self.len || (whole == self.len && self.damage.is_none()) {
            self.len = whole;
            self.damage = Some(Damage {
                frame: whole,
                error,
            });
        }
        Ok(())
    }

    /// A DCD file whose size leaves a partial frame after the last complete one was truncated:
    /// chemfiles drops that frame silently, this records it as [`Damage`].
    pub(super) fn check_dcd_size(&mut self) {
        if self.damage.is_some() || self.lock().base() != "DCD" {
            return;
        }
        let Some(tail) = dcd::measure(&self.frames_path) else {
            return;
        };
        if tail.trailing > 0 && tail.complete == self.len {
            let message = format!(
                "the file ends inside this frame (truncated: {} of {} bytes)",
                tail.trailing, tail.frame_bytes
            );
            let error = IoError::bad_frame(&self.frames_path, self.len, message);
            self.damage = Some(Damage {
                frame: self.len,
                error,
            });
        }
    }

    /// Checks the last few frames; if some fail to read, the readable length ends at the first
    /// failing one (a truncated file) and the failure is kept as [`Damage`]. Not for a file
    /// read over HTTP: each probe would be a download (its headers were walked, so a cut file
    /// is already found), and a network failure is no damage.
    pub(super) fn probe_tail(&mut self) {
        if self.lock().is_remote() {
            return;
        }
        let start = self.len.saturating_sub(TAIL_PROBE).max(1);
        let mut first_bad = None;
        for index in start..self.len {
            let result = self.lock().read_frame(index);
            if let Err(error) = result
                && !matches!(
                    error,
                    IoError::NonFiniteCoordinate { .. } | IoError::AbsurdCoordinate { .. }
                )
            {
                first_bad = Some((index, error));
                break;
            }
        }
        if let Some((frame, error)) = first_bad {
            self.len = frame;
            self.damage = Some(Damage { frame, error });
        }
    }
}
