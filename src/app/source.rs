//! Where the viewer's frames come from: a [`FrameSource`] is a topology plus random access to
//! frames. Files opened with [`crate::io::open`] are one; [`MemorySource`] (frames held in memory)
//! serves tests and generated systems. Files are read through a [`StreamedSource`]: a
//! [`FrameStreamer`] reader thread keeps a bounded cache filled around the playhead, so playback
//! reads from memory. The compute worker reads frames through this trait only.

use std::sync::Arc;
use std::time::Duration;

use crate::io::{
    FrameHook, FrameStreamer, IoError, LiveAction, LiveControlError, StreamerOptions, Trajectory,
};
use crate::model::{Frame, Topology};
use crate::transform::{TransformChain, TransformError, TransformOptions};

impl From<crate::transform::ChainSetupError> for SourceError {
    fn from(error: crate::transform::ChainSetupError) -> SourceError {
        use crate::transform::ChainSetupError as E;
        match error {
            E::Io(e) => SourceError::Io(e),
            E::FitReference(e) => SourceError::FitReference(e),
            E::Transform(e) => SourceError::Transform(e),
        }
    }
}

/// How long the worker waits for the reader thread to deliver one frame.
const READ_TIMEOUT: Duration = Duration::from_secs(120);

/// Why a source cannot be opened or a frame of it read; one line naming the file and frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SourceError {
    /// Opening the files or reading a frame failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A frame past the end of a source held in memory.
    #[error("{name}: no frame {index} (it has {len})")]
    NoFrame {
        /// The source's name.
        name: String,
        /// The frame asked for (from 0).
        index: usize,
        /// How many frames it holds.
        len: usize,
    },
    /// A streamed frame that failed to read (or to transform): playback skips it.
    #[error("{source} (frame {index} skipped)")]
    Skipped {
        /// The frame (from 0).
        index: usize,
        /// Why it failed, naming the file.
        source: IoError,
    },
    /// The reader thread did not deliver a frame in time.
    #[error("{name}: frame {index} not read within {seconds} s")]
    Timeout {
        /// The source's name.
        name: String,
        /// The frame (from 0).
        index: usize,
        /// How long the worker waited (s).
        seconds: u64,
    },
    /// The topology file asked for as the `--fit` reference cannot be read.
    #[error("fit reference: {0}")]
    FitReference(IoError),
    /// The frame transformations (whole, centre, fit, periodic) cannot be set up.
    #[error(transparent)]
    Transform(#[from] TransformError),
}

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
    /// Reads frame `index` (from 0); the error is one line naming the file and frame. The
    /// frame is shared, not copied: a streamed file hands out the frame its cache holds.
    fn read_frame(&self, index: usize) -> Result<Arc<Frame>, SourceError>;
    /// Short name for the window title and messages (file name).
    fn name(&self) -> String;
    /// The images shown when surfaces are periodic (`--periodic`), else `None`.
    fn periodic(&self) -> Option<crate::transform::Replicate> {
        None
    }
    /// True when the frames come from a running simulation: [`FrameSource::len`] grows as
    /// they arrive.
    fn is_live(&self) -> bool {
        false
    }
    /// For a running simulation whose stream has ended: why, in one line.
    fn live_ended(&self) -> Option<String> {
        None
    }
    /// Pauses, resumes or detaches from the running simulation the frames come from.
    fn live_control(&self, _action: LiveAction) -> Result<(), LiveControlError> {
        Err(LiveControlError::NotImd)
    }
    /// True while [`FrameSource::live_control`] can reach a running simulation (`--imd`).
    fn live_controllable(&self) -> bool {
        false
    }
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
    fn read_frame(&self, index: usize) -> Result<Arc<Frame>, SourceError> {
        self.frames
            .get(index)
            .cloned()
            .map(Arc::new)
            .ok_or_else(|| SourceError::NoFrame {
                name: self.name.clone(),
                index,
                len: self.frames.len(),
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
    fn read_frame(&self, index: usize) -> Result<Arc<Frame>, SourceError> {
        Ok(Arc::new(crate::io::Trajectory::read_frame(self, index)?))
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
    /// Half-width of the smoothing window (0: none).
    smooth: usize,
    /// Periodic surfaces and their images (`None`: off).
    periodic: Option<crate::transform::Replicate>,
}

impl StreamedSource {
    /// Starts the reader thread for `trajectory` with cache and prefetch sizes `options`.
    pub fn new(trajectory: Trajectory, options: StreamerOptions) -> StreamedSource {
        StreamedSource {
            streamer: FrameStreamer::new(trajectory, options),
            smooth: 0,
            periodic: None,
        }
    }

    /// Like [`StreamedSource::new`], with every frame made whole, centred and fitted by `chain`
    /// on the reader thread (so the cache holds transformed frames) and smoothed over the
    /// chain's window when read. The prefetch window grows to cover the smoothing window.
    pub fn transformed(
        trajectory: Trajectory,
        mut options: StreamerOptions,
        chain: TransformChain,
    ) -> StreamedSource {
        let smooth = chain.smooth();
        let periodic = chain.periodic();
        options.behind = options.behind.max(smooth);
        options.ahead = options.ahead.max(smooth + 1);
        options.capacity = options.capacity.max(options.behind + options.ahead + 2);
        let hook: Option<FrameHook> = (!chain.is_identity()).then(|| {
            Arc::new(move |frame: &mut Frame| {
                chain
                    .apply(frame)
                    .map_err(|e| Box::new(e.at_frame()) as crate::io::FrameHookError)
            }) as FrameHook
        });
        StreamedSource {
            streamer: FrameStreamer::with_hook(trajectory, options, hook),
            smooth,
            periodic,
        }
    }

    fn read_one(&self, index: usize) -> Result<Arc<Frame>, SourceError> {
        match self.streamer.wait(index, READ_TIMEOUT) {
            Some(Ok(frame)) => Ok(frame),
            Some(Err(source)) => Err(SourceError::Skipped { index, source }),
            None => Err(SourceError::Timeout {
                name: self.name(),
                index,
                seconds: READ_TIMEOUT.as_secs(),
            }),
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
    fn read_frame(&self, index: usize) -> Result<Arc<Frame>, SourceError> {
        self.streamer.set_playhead(index);
        if self.smooth == 0 {
            return self.read_one(index);
        }
        crate::transform::smooth::smooth_frame(index, self.len(), self.smooth, |j| self.read_one(j))
            .map(Arc::new)
    }
    fn name(&self) -> String {
        FrameSource::name(self.streamer.trajectory())
    }
    fn periodic(&self) -> Option<crate::transform::Replicate> {
        self.periodic
    }
    fn is_live(&self) -> bool {
        self.streamer.trajectory().is_live()
    }
    fn live_ended(&self) -> Option<String> {
        self.streamer.trajectory().live_ended()
    }
    fn live_control(&self, action: LiveAction) -> Result<(), LiveControlError> {
        self.streamer.trajectory().live_control(action)
    }
    fn live_controllable(&self) -> bool {
        self.streamer.trajectory().live_controllable()
    }
}

/// Opens `top` (and `traj`) from disk as a shared source read ahead by a [`StreamedSource`].
pub fn open_files(
    top: &std::path::Path,
    traj: Option<&std::path::Path>,
) -> Result<Arc<dyn FrameSource>, SourceError> {
    open_files_with(top, traj, &TransformOptions::default())
}

/// Like [`open_files`], with the frames made whole, centred, fitted and smoothed as
/// `transforms` ask (the errors of a bad option are one line).
pub fn open_files_with(
    top: &std::path::Path,
    traj: Option<&std::path::Path>,
    transforms: &TransformOptions,
) -> Result<Arc<dyn FrameSource>, SourceError> {
    // A reader that panics (it should not: see `io`) must give an error, not a dead thread
    // the window waits on forever.
    let opened = std::panic::catch_unwind(|| crate::io::open(top, traj)).unwrap_or_else(|_| {
        Err(crate::io::IoError::Unreadable {
            path: top.to_path_buf(),
            message: "the reader crashed on this file".into(),
        })
    });
    streamed(opened?, transforms)
}

/// Like [`open_files_with`], with the frames coming as they arrive from a running simulation
/// or a file being written (see [`crate::io::open_growing`]); `top` holds the atoms.
pub fn open_live_with(
    top: &std::path::Path,
    live: &crate::io::LiveSource,
    transforms: &TransformOptions,
) -> Result<Arc<dyn FrameSource>, SourceError> {
    let trajectory = crate::io::open_growing(top, live)?;
    streamed(trajectory, transforms)
}

/// `trajectory` read ahead by a [`StreamedSource`], its frames transformed as `transforms`
/// ask.
fn streamed(
    trajectory: Trajectory,
    transforms: &TransformOptions,
) -> Result<Arc<dyn FrameSource>, SourceError> {
    let chain = crate::transform::chain_for(transforms, &trajectory)?;
    Ok(Arc::new(StreamedSource::transformed(
        trajectory,
        StreamerOptions::default(),
        chain,
    )))
}

/// A small test system: `residues` residues of three atoms each along a helix, moving a little
/// from frame to frame (`frames` frames, 1 ps apart). Element colours and radii are filled in.
#[cfg(any(test, feature = "test-hooks"))]
pub fn helix_source(residues: usize, frames: usize) -> MemorySource {
    use glam::Vec3;
    let mut top = Topology::default();
    for r in 0..residues {
        for (name, el, radius) in [("N", "N", 1.4), ("CA", "C", 1.5), ("O", "O", 1.3)] {
            top.names.push(name);
            top.elements.push(el);
            top.radii.push(radius);
            top.residue_names.push("ALA");
            top.residue_ids.push(r as i64 + 1);
            top.residue_index.push(r as u32);
            top.chains.push("A");
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
