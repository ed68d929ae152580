//! Where the viewer's frames come from: a [`FrameSource`] is a topology plus random access to
//! frames. Files opened with [`crate::io::open`] are one; [`MemorySource`] (frames held in memory)
//! serves tests and generated systems. Files are read through a [`StreamedSource`]: a
//! [`FrameStreamer`] reader thread keeps a bounded cache filled around the playhead, so playback
//! reads from memory. The compute worker reads frames through this trait only.

use std::sync::Arc;
use std::time::Duration;

use crate::io::{FrameStreamer, StreamerOptions, Trajectory};
use crate::model::{Frame, Topology};

/// How long the worker waits for the reader thread to deliver one frame.
const READ_TIMEOUT: Duration = Duration::from_secs(120);

/// A trajectory the viewer can play.
pub trait FrameSource: Send + Sync {
    /// The constant part: names, elements, radii, residues, bonds.
    fn topology(&self) -> &Topology;
    /// Number of frames.
    fn len(&self) -> usize;
    /// True when there are no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Reads frame `index` (from 0); the error is one line naming the file and frame.
    fn read_frame(&self, index: usize) -> Result<Frame, String>;
    /// Short name for the window title and messages (file name).
    fn name(&self) -> String;
}

/// Frames held in memory.
#[derive(Debug, Clone)]
pub struct MemorySource {
    /// The topology.
    pub topology: Topology,
    /// The frames, in order.
    pub frames: Vec<Frame>,
    /// Name shown in the window.
    pub name: String,
}

impl FrameSource for MemorySource {
    fn topology(&self) -> &Topology {
        &self.topology
    }
    fn len(&self) -> usize {
        self.frames.len()
    }
    fn read_frame(&self, index: usize) -> Result<Frame, String> {
        self.frames.get(index).cloned().ok_or_else(|| {
            format!(
                "{}: no frame {index} (it has {})",
                self.name,
                self.frames.len()
            )
        })
    }
    fn name(&self) -> String {
        self.name.clone()
    }
}

impl FrameSource for crate::io::Trajectory {
    fn topology(&self) -> &Topology {
        crate::io::Trajectory::topology(self)
    }
    fn len(&self) -> usize {
        crate::io::Trajectory::len(self)
    }
    fn read_frame(&self, index: usize) -> Result<Frame, String> {
        crate::io::Trajectory::read_frame(self, index).map_err(|e| e.to_string())
    }
    fn name(&self) -> String {
        let p = self.path();
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    }
}

/// A trajectory read ahead by a [`FrameStreamer`]: each read moves the streamer's playhead
/// there, so the frames after it are prefetched while this one is computed; a frame already
/// in the cache is returned without touching the file. A frame that failed to read fails
/// again at once with the same message (the viewer shows it and playback goes on).
pub struct StreamedSource {
    streamer: FrameStreamer,
}

impl StreamedSource {
    /// Starts the reader thread for `trajectory` with cache and prefetch sizes `options`.
    pub fn new(trajectory: Trajectory, options: StreamerOptions) -> StreamedSource {
        StreamedSource {
            streamer: FrameStreamer::new(trajectory, options),
        }
    }

    /// The streamer (cache contents, failed frames, read count).
    pub fn streamer(&self) -> &FrameStreamer {
        &self.streamer
    }
}

impl FrameSource for StreamedSource {
    fn topology(&self) -> &Topology {
        self.streamer.trajectory().topology()
    }
    fn len(&self) -> usize {
        self.streamer.len()
    }
    fn read_frame(&self, index: usize) -> Result<Frame, String> {
        self.streamer.set_playhead(index);
        match self.streamer.wait(index, READ_TIMEOUT) {
            Some(Ok(frame)) => Ok(Frame::clone(&frame)),
            Some(Err(e)) => Err(format!("{e} (frame {index} skipped)")),
            None => Err(format!(
                "{}: frame {index} not read within {} s",
                self.name(),
                READ_TIMEOUT.as_secs()
            )),
        }
    }
    fn name(&self) -> String {
        FrameSource::name(self.streamer.trajectory())
    }
}

/// Opens `top` (and `traj`) from disk as a shared source read ahead by a [`StreamedSource`].
pub fn open_files(
    top: &std::path::Path,
    traj: Option<&std::path::Path>,
) -> Result<Arc<dyn FrameSource>, String> {
    // A reader that panics (it should not: see `io`) must give an error, not a dead thread
    // the window waits on forever.
    let opened = std::panic::catch_unwind(|| crate::io::open(top, traj)).unwrap_or_else(|_| {
        Err(crate::io::IoError::Unreadable {
            path: top.to_path_buf(),
            message: "the reader crashed on this file".into(),
        })
    });
    opened
        .map(|t| {
            Arc::new(StreamedSource::new(t, StreamerOptions::default())) as Arc<dyn FrameSource>
        })
        .map_err(|e| e.to_string())
}

/// A small test system: `residues` residues of three atoms each along a helix, moving a little
/// from frame to frame (`frames` frames, 1 ps apart). Element colours and radii are filled in.
pub fn helix_source(residues: usize, frames: usize) -> MemorySource {
    use glam::Vec3;
    let mut top = Topology::default();
    for r in 0..residues {
        for (name, el, radius) in [("N", "N", 1.4), ("CA", "C", 1.5), ("O", "O", 1.3)] {
            top.names.push(name.into());
            top.elements.push(el.into());
            top.radii.push(radius);
            top.residue_names.push("ALA".into());
            top.residue_ids.push(r as i64 + 1);
            top.residue_index.push(r as u32);
            top.chains.push("A".into());
            top.b_factors.push(0.0);
        }
    }
    let frames = (0..frames)
        .map(|f| {
            let phase = f as f32 * 0.15;
            let positions = (0..residues * 3)
                .map(|i| {
                    let t = i as f32 * 0.55;
                    Vec3::new(
                        4.0 * (t + phase).cos(),
                        4.0 * (t + phase).sin(),
                        i as f32 * 0.9,
                    )
                })
                .collect();
            Frame {
                index: f,
                time_ps: Some(f as f64),
                positions,
                cell: None,
            }
        })
        .collect();
    MemorySource {
        topology: top,
        frames,
        name: "helix".into(),
    }
}
