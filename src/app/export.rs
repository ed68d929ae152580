//! Pictures out of the viewer: the movie plan (a frame range, a turntable, or both) and its
//! step list, the progress of a running export, and the numbered file names. The window layer
//! renders each step with the same offscreen renderer as screenshots (`render_to_rgba`) and
//! writes it as a numbered PNG or into one movie file, an H.264 MP4 or an animated GIF
//! ([`crate::export::movie`]).

use std::path::{Path, PathBuf};

use crate::export::movie::{Movie, MovieFormat};
use crate::export::video::VideoQuality;

/// A movie's file, frame rate and quality (instead of a PNG sequence).
#[derive(Debug, Clone, PartialEq)]
pub struct VideoPlan {
    /// The `.mp4` or `.gif` file written (atomically: no partial file on cancel or failure).
    pub path: PathBuf,
    /// Frames per second.
    pub fps: f64,
    /// Encoder quality preset.
    pub quality: VideoQuality,
}

impl Default for VideoPlan {
    fn default() -> Self {
        VideoPlan {
            path: PathBuf::from("mdsurf-movie.mp4"),
            fps: 24.0,
            quality: VideoQuality::default(),
        }
    }
}

/// What a movie export records.
#[derive(Debug, Clone, PartialEq)]
pub struct MoviePlan {
    /// First and last trajectory frame (inclusive), or `None` to stay on the current frame.
    pub frames: Option<(usize, usize)>,
    /// Trajectory frames advanced per movie frame.
    pub stride: usize,
    /// Camera turn per movie frame in degrees (0: no turntable).
    pub degrees_per_frame: f32,
    /// Movie frames when `frames` is `None` (a pure turntable).
    pub turntable_frames: usize,
    /// Image size in pixels.
    pub size: [u32; 2],
    /// Folder the numbered PNGs go to (when `video` is `None`).
    pub dir: PathBuf,
    /// Write one movie file (MP4 or GIF, by its name) instead of numbered PNGs.
    pub video: Option<VideoPlan>,
}

impl Default for MoviePlan {
    fn default() -> Self {
        MoviePlan {
            frames: None,
            stride: 1,
            degrees_per_frame: 2.0,
            turntable_frames: 180,
            size: [1280, 720],
            dir: PathBuf::from("mdsurf-movie"),
            video: None,
        }
    }
}

/// One image of a movie: which trajectory frame, how far the camera has turned (degrees), and
/// the file to write.
#[derive(Debug, Clone, PartialEq)]
pub struct MovieStep {
    /// Trajectory frame.
    pub frame: usize,
    /// Camera turn from the start in degrees.
    pub degrees: f32,
    /// Output PNG.
    pub path: PathBuf,
}

/// `dir/frame_00042.png` for movie frame 42.
pub fn numbered_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(format!("frame_{index:05}.png"))
}

impl MoviePlan {
    /// The steps of this plan; `current` is the frame used when the plan has no range.
    pub fn steps(&self, current: usize) -> Vec<MovieStep> {
        let frames: Vec<usize> = match self.frames {
            Some((a, b)) if a <= b => (a..=b).step_by(self.stride.max(1)).collect(),
            Some((a, b)) => (b..=a).rev().step_by(self.stride.max(1)).collect(),
            None => vec![current; self.turntable_frames.max(1)],
        };
        frames
            .into_iter()
            .enumerate()
            .map(|(i, frame)| MovieStep {
                frame,
                degrees: self.degrees_per_frame * i as f32,
                path: numbered_path(&self.dir, i),
            })
            .collect()
    }
}

/// A running export.
pub struct MovieJob {
    /// All steps.
    pub steps: Vec<MovieStep>,
    /// Steps written so far.
    pub done: usize,
    /// Camera yaw at the start (radians).
    pub start_yaw: f32,
    /// Image size in pixels.
    pub size: [u32; 2],
    /// The movie file being written, or `None` for numbered PNGs. Dropping the job (cancel, a
    /// failed image) deletes its temporary file.
    pub video: Option<Movie>,
}

impl MovieJob {
    /// Fraction done, 0 to 1.
    pub fn progress(&self) -> f32 {
        self.done as f32 / self.steps.len().max(1) as f32
    }

    /// The next step, or `None` when finished.
    pub fn next(&self) -> Option<&MovieStep> {
        self.steps.get(self.done)
    }
}

/// Controls for screenshots and movies; edits `plan` (UI scratch) and returns commands.
pub fn export_ui(
    ui: &mut egui::Ui,
    plan: &mut MoviePlan,
    shot_scale: &mut u32,
    frames: usize,
    job: Option<&MovieJob>,
) -> Vec<super::state::Command> {
    use super::state::Command;
    let mut out = Vec::new();
    ui.heading("Export");
    ui.horizontal(|ui| {
        ui.add(egui::Slider::new(shot_scale, 1..=4).text("× window"));
        if ui.button("Screenshot…").clicked() {
            out.push(Command::Screenshot {
                scale: *shot_scale,
                size: None,
                path: None,
            });
        }
    });
    if ui.button("Screenshot 3840×2160…").clicked() {
        out.push(Command::Screenshot {
            scale: 1,
            size: Some([3840, 2160]),
            path: None,
        });
    }
    ui.separator();
    let mut range = plan.frames.is_some();
    ui.checkbox(&mut range, "trajectory range");
    if range {
        let last = frames.saturating_sub(1);
        let (mut a, mut b) = plan.frames.unwrap_or((0, last));
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut a).range(0..=last).prefix("from "));
            ui.add(egui::DragValue::new(&mut b).range(0..=last).prefix("to "));
            ui.add(
                egui::DragValue::new(&mut plan.stride)
                    .range(1..=1000)
                    .prefix("stride "),
            );
        });
        plan.frames = Some((a, b));
    } else {
        plan.frames = None;
        ui.add(
            egui::DragValue::new(&mut plan.turntable_frames)
                .range(1..=3600)
                .prefix("images "),
        );
    }
    ui.add(
        egui::DragValue::new(&mut plan.degrees_per_frame)
            .range(-90.0..=90.0)
            .prefix("turn ")
            .suffix(" °/image"),
    );
    ui.horizontal(|ui| {
        ui.add(
            egui::DragValue::new(&mut plan.size[0])
                .range(16..=8192)
                .prefix("w "),
        );
        ui.add(
            egui::DragValue::new(&mut plan.size[1])
                .range(16..=8192)
                .prefix("h "),
        );
    });
    let format_now = plan
        .video
        .as_ref()
        .map(|v| MovieFormat::of(&v.path).unwrap_or(MovieFormat::Mp4));
    let mut format = format_now;
    ui.horizontal(|ui| {
        ui.radio_value(&mut format, Some(MovieFormat::Mp4), "MP4 (H.264)");
        ui.radio_value(&mut format, Some(MovieFormat::Gif), "GIF");
        ui.radio_value(&mut format, None, "PNG sequence");
    });
    if format != format_now {
        plan.video = format.map(|f| {
            let mut video = plan.video.take().unwrap_or_default();
            video.path.set_extension(match f {
                MovieFormat::Mp4 => "mp4",
                MovieFormat::Gif => "gif",
            });
            video
        });
    }
    match plan.video.as_mut() {
        Some(video) => {
            let mut file = video.path.display().to_string();
            if ui
                .add(egui::TextEdit::singleline(&mut file).hint_text("movie.mp4"))
                .changed()
            {
                video.path = PathBuf::from(file);
            }
            ui.horizontal(|ui| {
                // A GIF's delays are hundredths of a second: at most 50 frames per second.
                let max_fps = match format {
                    Some(MovieFormat::Gif) => crate::export::gif_movie::GIF_MAX_FPS,
                    _ => 240.0,
                };
                ui.add(
                    egui::DragValue::new(&mut video.fps)
                        .range(1.0..=max_fps)
                        .suffix(" fps"),
                );
                egui::ComboBox::from_label("quality")
                    .selected_text(video.quality.name())
                    .show_ui(ui, |ui| {
                        for q in VideoQuality::ALL {
                            ui.selectable_value(&mut video.quality, q, q.name());
                        }
                    });
            });
        }
        None => {
            let mut dir = plan.dir.display().to_string();
            if ui
                .add(egui::TextEdit::singleline(&mut dir).hint_text("output folder"))
                .changed()
            {
                plan.dir = PathBuf::from(dir);
            }
        }
    }
    match job {
        Some(j) => {
            ui.add(egui::ProgressBar::new(j.progress()).text(format!(
                "{}/{}",
                j.done,
                j.steps.len()
            )));
            if ui.button("Cancel").clicked() {
                out.push(Command::CancelMovie);
            }
        }
        None => {
            let label = match format {
                Some(MovieFormat::Mp4) => "Export movie (MP4)",
                Some(MovieFormat::Gif) => "Export movie (GIF)",
                None => "Export movie (PNG sequence)",
            };
            if ui.button(label).clicked() {
                out.push(Command::StartMovie(plan.clone()));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_cover_range_and_turn() {
        let plan = MoviePlan {
            frames: Some((2, 8)),
            stride: 3,
            degrees_per_frame: 10.0,
            dir: "m".into(),
            ..Default::default()
        };
        let s = plan.steps(0);
        assert_eq!(s.iter().map(|s| s.frame).collect::<Vec<_>>(), [2, 5, 8]);
        assert_eq!(s[2].degrees, 20.0);
        assert_eq!(s[1].path, Path::new("m/frame_00001.png"));
        let turn = MoviePlan {
            turntable_frames: 4,
            ..Default::default()
        }
        .steps(7);
        assert_eq!(turn.len(), 4);
        assert!(turn.iter().all(|s| s.frame == 7));
    }
}
