//! The playhead: which frame is shown, play/pause, speed (frames per second), stride, and what
//! happens at the ends (stop, loop, bounce). [`Timeline::advance`] moves it with wall-clock time;
//! [`timeline_ui`] draws the controls and returns [`TimelineCmd`]s for the app to apply.

use super::state::Command;

/// What playback does at the last (or first) frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EndMode {
    /// Stop at the end.
    Once,
    /// Jump back to the first frame.
    #[default]
    Loop,
    /// Reverse direction.
    Bounce,
}

/// A change to the timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimelineCmd {
    /// Start or stop playing.
    SetPlaying(bool),
    /// Move by this many strides (negative: back).
    Step(i64),
    /// Go to the first frame.
    First,
    /// Go to the last frame.
    Last,
    /// Go to this frame.
    Seek(usize),
    /// Playback speed in frames per second.
    SetFps(f32),
    /// Frames advanced per step.
    SetStride(usize),
    /// End behaviour.
    SetEndMode(EndMode),
}

/// Playback state.
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Number of frames in the trajectory.
    pub len: usize,
    /// Frame shown (requested) now.
    pub current: usize,
    /// True while playing.
    pub playing: bool,
    /// Frames per second while playing.
    pub fps: f32,
    /// Frames advanced per step.
    pub stride: usize,
    /// End behaviour.
    pub end_mode: EndMode,
    /// +1 forward, -1 backward (bounce).
    direction: i64,
    /// Seconds accumulated towards the next step.
    pending_s: f64,
}

impl Timeline {
    /// A paused timeline at frame 0 of `len` frames.
    pub fn new(len: usize) -> Timeline {
        Timeline {
            len,
            current: 0,
            playing: false,
            fps: 20.0,
            stride: 1,
            end_mode: EndMode::Loop,
            direction: 1,
            pending_s: 0.0,
        }
    }

    fn last(&self) -> usize {
        self.len.saturating_sub(1)
    }

    /// Applies one command.
    pub fn apply(&mut self, cmd: TimelineCmd) {
        match cmd {
            TimelineCmd::SetPlaying(p) => {
                self.playing = p && self.len > 1;
                self.pending_s = 0.0;
            }
            TimelineCmd::Step(n) => self.step(n, false),
            TimelineCmd::First => self.current = 0,
            TimelineCmd::Last => self.current = self.last(),
            TimelineCmd::Seek(f) => self.current = f.min(self.last()),
            TimelineCmd::SetFps(f) => self.fps = f.clamp(0.5, 240.0),
            TimelineCmd::SetStride(s) => self.stride = s.clamp(1, self.len.max(1)),
            TimelineCmd::SetEndMode(m) => {
                self.end_mode = m;
                // Only bounce plays backwards.
                if m != EndMode::Bounce {
                    self.direction = 1;
                }
            }
        }
    }

    /// Moves `n` strides; while playing, the end mode decides what happens at the ends.
    fn step(&mut self, n: i64, playing: bool) {
        let last = self.last() as i64;
        let mut next = self.current as i64 + n * self.stride as i64;
        if playing && (next > last || next < 0) {
            match self.end_mode {
                EndMode::Once => {
                    next = next.clamp(0, last);
                    self.playing = false;
                }
                EndMode::Loop => next = if next > last { 0 } else { last },
                EndMode::Bounce => {
                    self.direction = -self.direction;
                    next =
                        (self.current as i64 + self.direction * self.stride as i64).clamp(0, last);
                }
            }
        }
        self.current = next.clamp(0, last) as usize;
    }

    /// Advances playback by `dt` seconds of wall-clock time and returns true when the frame
    /// changed. Steps that fall due while the surface is still being computed are skipped
    /// over (at most one step per call), so playback keeps pace by dropping frames.
    pub fn advance(&mut self, dt: f64) -> bool {
        if !self.playing || self.len < 2 {
            return false;
        }
        self.pending_s += dt;
        let period = 1.0 / self.fps.max(0.1) as f64;
        if self.pending_s < period {
            return false;
        }
        let steps = (self.pending_s / period).floor() as i64;
        self.pending_s -= steps as f64 * period;
        let before = self.current;
        self.step(steps * self.direction, true);
        self.current != before
    }

    /// Seconds until the next step is due (for scheduling repaints).
    pub fn until_next_s(&self) -> f64 {
        (1.0 / self.fps.max(0.1) as f64 - self.pending_s).max(0.0)
    }
}

/// The timeline bar: transport buttons, scrub slider, frame and time readout, speed, stride and
/// end mode. `on_screen` is the index of the frame on screen and its time in ps (when the
/// file records one); the time label belongs to that frame ([`time_label`]).
pub fn timeline_ui(
    ui: &mut egui::Ui,
    t: &Timeline,
    on_screen: Option<(usize, Option<f64>)>,
) -> Vec<Command> {
    let mut out = Vec::new();
    let mut cmd = |c: TimelineCmd| out.push(Command::Timeline(c));
    ui.horizontal(|ui| {
        if ui.button("|<").on_hover_text("first frame").clicked() {
            cmd(TimelineCmd::First);
        }
        if ui.button("<").on_hover_text("step back").clicked() {
            cmd(TimelineCmd::Step(-1));
        }
        let label = if t.playing { "Pause" } else { "Play" };
        if ui.button(label).clicked() {
            cmd(TimelineCmd::SetPlaying(!t.playing));
        }
        if ui.button(">").on_hover_text("step forward").clicked() {
            cmd(TimelineCmd::Step(1));
        }
        if ui.button(">|").on_hover_text("last frame").clicked() {
            cmd(TimelineCmd::Last);
        }
        let mut f = t.current;
        let max = t.len.saturating_sub(1).max(1);
        ui.spacing_mut().slider_width = (ui.available_width() - 560.0).max(100.0);
        if ui
            .add(egui::Slider::new(&mut f, 0..=max).text("frame"))
            .changed()
        {
            cmd(TimelineCmd::Seek(f));
        }
        ui.label(format!("/ {}", t.len.saturating_sub(1)));
        ui.label(time_label(t.current, on_screen));
        let mut fps = t.fps;
        if ui
            .add(
                egui::DragValue::new(&mut fps)
                    .range(0.5..=240.0)
                    .speed(0.5)
                    .suffix(" fps"),
            )
            .changed()
        {
            cmd(TimelineCmd::SetFps(fps));
        }
        let mut stride = t.stride;
        if ui
            .add(
                egui::DragValue::new(&mut stride)
                    .range(1..=1000)
                    .prefix("stride "),
            )
            .changed()
        {
            cmd(TimelineCmd::SetStride(stride));
        }
        let mut mode = t.end_mode;
        egui::ComboBox::from_label("at end")
            .selected_text(format!("{mode:?}"))
            .show_ui(ui, |ui| {
                for m in [EndMode::Once, EndMode::Loop, EndMode::Bounce] {
                    ui.selectable_value(&mut mode, m, format!("{m:?}"));
                }
            });
        if mode != t.end_mode {
            cmd(TimelineCmd::SetEndMode(mode));
        }
    });
    out
}

/// The time shown beside the frame slider: the time of the frame on screen, with that
/// frame's index when it is not the slider's `current` frame (while playback or a seek waits
/// for its surface), so a time is never shown beside another frame's number.
pub fn time_label(current: usize, on_screen: Option<(usize, Option<f64>)>) -> String {
    match on_screen {
        None => "t = ?".into(),
        Some((frame, time)) => {
            let t = time.map_or_else(|| "t = ?".into(), |p| format!("t = {p:.1} ps"));
            if frame == current {
                t
            } else {
                format!("{t} (frame {frame} on screen)")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_belongs_to_the_frame_on_screen() {
        assert_eq!(time_label(4, Some((4, Some(80000.0)))), "t = 80000.0 ps");
        assert_eq!(
            time_label(4, Some((3, Some(60000.0)))),
            "t = 60000.0 ps (frame 3 on screen)"
        );
        assert_eq!(time_label(0, Some((0, None))), "t = ?");
        assert_eq!(time_label(2, None), "t = ?");
    }

    #[test]
    fn loop_bounce_and_once_at_the_end() {
        let mut t = Timeline::new(4);
        t.apply(TimelineCmd::SetPlaying(true));
        t.apply(TimelineCmd::SetFps(10.0));
        let frames: Vec<usize> = (0..5)
            .map(|_| {
                t.advance(0.1);
                t.current
            })
            .collect();
        assert_eq!(frames, [1, 2, 3, 0, 1]);
        t.apply(TimelineCmd::SetEndMode(EndMode::Bounce));
        let frames: Vec<usize> = (0..4)
            .map(|_| {
                t.advance(0.1);
                t.current
            })
            .collect();
        assert_eq!(frames, [2, 3, 2, 1]);
        t.apply(TimelineCmd::SetEndMode(EndMode::Once));
        t.apply(TimelineCmd::Last);
        t.advance(0.1);
        assert!(!t.playing);
    }

    #[test]
    fn slow_compute_drops_frames_instead_of_slowing_down() {
        let mut t = Timeline::new(100);
        t.apply(TimelineCmd::SetPlaying(true));
        t.apply(TimelineCmd::SetFps(30.0));
        // One UI update after half a second: 15 frames are due, playback jumps over them.
        assert!(t.advance(0.5));
        assert_eq!(t.current, 15);
    }
}
