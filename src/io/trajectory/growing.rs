//! Trajectories whose frames keep coming: a simulation sending them over IMD ([`open_live`])
//! or a file an engine is still writing ([`open_following`]). Both open the structure as
//! [`open`] does and read frames through a [`NativeFrames`] source that grows.

use std::path::Path;
use std::sync::Mutex;

use super::{FrameSource, Trajectory, open};
use crate::io::IoError;
use crate::io::follow::{FollowOptions, FollowedFrames};
use crate::io::live::{
    LiveAction, LiveControlError, LiveFrames, LiveOptions, LiveSource, read_held,
};

/// Opens the structure `top` (a file with atom names, as for [`open`]) with its frames coming
/// from the simulation running at `options.address` over IMD (see `live`): frame `i` is the
/// `i`-th step the engine sent, read waits for it, and [`Trajectory::len`] is
/// [`LIVE_FRAMES_UNBOUNDED`](super::LIVE_FRAMES_UNBOUNDED) (the run's end shows as [`IoError::LiveEnded`]). The engine must
/// send the coordinates of every atom of `top` (GROMACS: `IMD-group = System`). IMD version 2
/// sends no box or time: frames carry the box of `top`, and times counted from its time
/// (version 3 engines may send both, which the frames then carry).
pub fn open_live(top: &Path, options: &LiveOptions) -> Result<Trajectory, IoError> {
    let structure = open(top, None)?;
    let start = structure.read_frame(0)?;
    let frames = LiveFrames::connect(options, structure.topology.len(), &start)?;
    let live = Some(frames.count());
    let source = FrameSource::Native(Box::new(frames));
    let trajectory = Trajectory {
        frames_path: source.path().to_path_buf(),
        len: source.len(),
        reader: Mutex::new(source),
        damage: None,
        live,
        ..structure
    };
    // Waits for the first frame: a wrong atom count is reported at once (on the oldest frame
    // held when a fast engine has already pushed frame 0 out).
    read_held(0, |i| trajectory.read_frame(i), IoError::oldest_held)?;
    Ok(trajectory)
}

/// Opens the structure `top` with the frames of `options.path`, a file an engine is still
/// writing: frames appended later appear as they are completed (see `follow`), and
/// [`Trajectory::len`] is [`LIVE_FRAMES_UNBOUNDED`](super::LIVE_FRAMES_UNBOUNDED) (the end
/// shows as [`IoError::LiveEnded`] once the file stops growing).
pub fn open_following(top: &Path, options: &FollowOptions) -> Result<Trajectory, IoError> {
    let opened = open(top, Some(&options.path))?;
    let topology = opened.topology.clone();
    let frames = FollowedFrames::start(top, opened, options)?;
    let live = Some(frames.count());
    let source = FrameSource::Native(Box::new(frames));
    Ok(Trajectory {
        topology,
        topology_path: top.to_path_buf(),
        frames_path: options.path.clone(),
        len: source.len(),
        reader: Mutex::new(source),
        damage: None,
        live,
        _download: None,
        downloaded: Vec::new(),
    })
}

/// Opens `top` with frames from a source that grows while it is read: a running simulation
/// ([`open_live`]) or a file being written ([`open_following`]).
pub fn open_growing(top: &Path, source: &LiveSource) -> Result<Trajectory, IoError> {
    match source {
        LiveSource::Imd(options) => open_live(top, options),
        LiveSource::Follow(options) => open_following(top, options),
    }
}

impl Trajectory {
    /// True when the frames come from a running simulation or a growing file
    /// ([`open_growing`]).
    pub fn is_live(&self) -> bool {
        self.live.is_some()
    }

    /// For a running simulation whose stream has ended (the run finished, the engine was
    /// killed, the connection dropped): one line saying so, with the frames received.
    pub fn live_ended(&self) -> Option<String> {
        let live = self.live.as_ref()?;
        let reason = live.ended()?;
        Some(format!(
            "{}: the simulation stream ended after {} frames ({reason})",
            self.frames_path.display(),
            live.received()
        ))
    }

    /// Pauses, resumes or detaches from the running simulation the frames come from (`--imd`);
    /// an error for any other source.
    pub fn live_control(&self, action: LiveAction) -> Result<(), LiveControlError> {
        match &self.live {
            Some(live) => live.control(action),
            None => Err(LiveControlError::NotImd),
        }
    }

    /// True while the frames come from a running simulation over IMD that can still be
    /// paused or detached ([`Trajectory::live_control`]).
    pub fn live_controllable(&self) -> bool {
        self.live.as_ref().is_some_and(|live| live.controllable())
    }

    /// Frames readable now without waiting: [`Trajectory::len`], or for a running simulation
    /// the frames received so far (never blocks on a read in progress).
    pub fn available(&self) -> usize {
        self.live
            .as_ref()
            .map_or(self.len, |live| live.received().min(self.len))
    }
}
