//! The viewer's state as a state file and back: the representations, camera, look and
//! timeline of an [`AppCore`]. The window (File → Save view / Open view) and headless console
//! scripts (`mdsurf render --script`) share these; the window adds its frame transformations.

use super::state::{AppCore, Command};
use super::timeline::TimelineCmd;
use crate::scene::state_file::{CameraState, LookError, LookState, StateFile, TrajectoryState};

impl AppCore {
    /// The view as a state file: representations, camera, look and timeline (the frame
    /// transformations are the caller's to add).
    pub fn view_state(&self) -> StateFile {
        let mut state = StateFile::new(self.reps.clone());
        // A camera not fitted yet (no frame computed) is saved as "fit the scene".
        state.camera = Some(CameraState::from_camera(&self.camera, self.fit_pending));
        state.look = LookState::from_settings(&self.render);
        state.trajectory = TrajectoryState {
            frame: self.timeline.current,
            stride: self.timeline.stride,
            fps: self.timeline.fps,
            ..TrajectoryState::default()
        };
        state
    }

    /// Applies a (checked) state file's look, camera, timeline and representations; the look
    /// is applied first, and a bad one changes nothing. The frame transformations are the
    /// caller's.
    pub fn apply_view_state(&mut self, state: StateFile) -> Result<(), LookError> {
        state.look.apply(&mut self.render)?;
        if let Some(cam) = state.camera {
            cam.apply(&mut self.camera);
            self.fit_pending = cam.fit;
            self.orient_pending = false;
        }
        self.timeline.stride = state.trajectory.stride.max(1);
        self.timeline.fps = state.trajectory.fps;
        self.apply(Command::SetReps(state.representations));
        self.apply(Command::Timeline(TimelineCmd::Seek(state.trajectory.frame)));
        Ok(())
    }
}
