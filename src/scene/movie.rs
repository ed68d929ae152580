//! Camera scripts: the `[movie]` section of a state file, an ordered list of segments (play
//! frames, hold, turn, zoom, fly to a saved view, fade a representation), turned into one
//! [`Shot`] per image: which trajectory frame, where the camera is (relative to the camera the
//! picture starts from) and which representations are faded. `mdsurf render --state` renders
//! the shots; a chunk of a job array renders its block of them with the same camera per image
//! as one run, since every shot depends only on the script.
//!
//! ```toml
//! [movie]
//! fps = 24                      # images per second of the timed segments and of the MP4
//!
//! [[movie.view]]                # a named view to fly to
//! name = "top"
//! yaw_deg = 0.0
//! pitch_deg = 80.0
//! zoom = 1.5                    # > 1: closer than the fitted camera
//!
//! [[movie.segment]]
//! kind = "play"                 # frames 0, 2, ..., 40
//! from = 0
//! to = 40
//! step = 2
//!
//! [[movie.segment]]
//! kind = "turn"                 # half a turn about the screen's vertical axis in 3 s
//! degrees = 180.0
//! axis = "vertical"
//! seconds = 3.0
//!
//! [[movie.segment]]
//! kind = "fly"
//! view = "top"
//! seconds = 2.0
//!
//! [[movie.segment]]
//! kind = "fade"
//! rep = "membrane"
//! to = 0.0
//! seconds = 1.0
//! ```
//!
//! Turns are linear in angle (a constant spin, as a turntable); fly and zoom ease in and out
//! (smoothstep), and a zoom is geometric (each image closer by the same factor). The last image
//! of a segment shows exactly its target (angle, view, zoom or opacity).

use serde::{Deserialize, Serialize};

/// The `[movie]` section: timing, named views and the segments in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MovieScript {
    /// Images per second: the timed segments last `seconds * fps` images; the MP4's frame rate
    /// unless `--fps` says otherwise.
    #[serde(default = "default_fps")]
    pub fps: f64,
    /// Named views that `fly` segments go to.
    #[serde(default, rename = "view", skip_serializing_if = "Vec::is_empty")]
    pub views: Vec<MovieView>,
    /// The segments, played in order.
    #[serde(default, rename = "segment")]
    pub segments: Vec<Segment>,
}

fn default_fps() -> f64 {
    24.0
}

/// A named camera direction and zoom.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MovieView {
    /// Name that `fly` segments use.
    pub name: String,
    /// Rotation about the vertical axis (degrees).
    #[serde(default)]
    pub yaw_deg: f32,
    /// Elevation (degrees, -89 to 89).
    #[serde(default)]
    pub pitch_deg: f32,
    /// Distance factor relative to the fitted camera: 2 is twice as close.
    #[serde(default = "one")]
    pub zoom: f32,
}

fn one() -> f32 {
    1.0
}

fn one_frame() -> usize {
    1
}

/// The screen axis a turn goes about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TurnAxis {
    /// The screen's vertical axis (a turntable: yaw).
    #[default]
    Vertical,
    /// The screen's horizontal axis (a tilt: pitch).
    Horizontal,
}

/// One step of a camera script.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Segment {
    /// Plays trajectory frames `from` to `to` (both included; backwards when `to < from`),
    /// every `step`-th one, one image each.
    Play {
        /// First frame (from 0).
        from: usize,
        /// Last frame.
        to: usize,
        /// Frames advanced per image.
        #[serde(default = "one_frame")]
        step: usize,
    },
    /// Holds the picture for `seconds`.
    Hold {
        /// Duration in seconds.
        seconds: f64,
    },
    /// Turns the camera by `degrees` about a screen axis in `seconds`.
    Turn {
        /// Angle in degrees (negative: the other way).
        degrees: f32,
        /// The axis.
        #[serde(default)]
        axis: TurnAxis,
        /// Duration in seconds.
        seconds: f64,
    },
    /// Moves closer by `factor` (0.5: twice as far) in `seconds`.
    Zoom {
        /// Distance factor, > 0.
        factor: f32,
        /// Duration in seconds.
        seconds: f64,
    },
    /// Flies to the named view in `seconds`.
    Fly {
        /// Name of a `[[movie.view]]`.
        view: String,
        /// Duration in seconds.
        seconds: f64,
    },
    /// Fades representation `rep` to opacity `to` in `seconds`.
    Fade {
        /// Representation name.
        rep: String,
        /// Target opacity 0..1 (0 hides it).
        to: f32,
        /// Duration in seconds.
        seconds: f64,
    },
}

/// The camera of one image, relative to the camera the movie starts from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShotCamera {
    /// Rotation about the vertical axis (degrees), added to the start camera's.
    pub yaw_deg: f32,
    /// Elevation (degrees), added to the start camera's.
    pub pitch_deg: f32,
    /// Distance factor: the start distance divided by this.
    pub zoom: f32,
}

/// One image of a movie.
#[derive(Debug, Clone, PartialEq)]
pub struct Shot {
    /// Trajectory frame shown.
    pub frame: usize,
    /// Where the camera is.
    pub camera: ShotCamera,
    /// Representations whose opacity the script changed, with that opacity (0..1).
    pub opacity: Vec<(String, f32)>,
}

/// Why a script cannot be played; each names the segment (from 1) and the value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MovieError {
    /// A value out of range.
    #[error("movie segment {segment}: {what}")]
    Bad {
        /// Segment number, from 1.
        segment: usize,
        /// What is wrong, with the value.
        what: String,
    },
    /// `fps` is not a positive finite number up to 1000.
    #[error("movie.fps = {0}: expected 0 < fps <= 1000")]
    Fps(f64),
    /// The script makes no image.
    #[error("the movie has no segment")]
    Empty,
}

/// Most images a script may make (a 24 fps movie of over an hour).
pub const MAX_SHOTS: usize = 100_000;

/// `t` in 0..1 eased in and out.
fn smoothstep(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

impl MovieScript {
    /// The images of the script, starting on `start_frame` with the start camera;
    /// `frames` is the trajectory's length and `opacity(rep)` a representation's own opacity
    /// (`None` when no representation has that name).
    pub fn shots(
        &self,
        start_frame: usize,
        frames: usize,
        opacity: impl Fn(&str) -> Option<f32>,
    ) -> Result<Vec<Shot>, MovieError> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= 1000.0) {
            return Err(MovieError::Fps(self.fps));
        }
        if self.segments.is_empty() {
            return Err(MovieError::Empty);
        }
        let mut shots: Vec<Shot> = Vec::new();
        let mut frame = start_frame.min(frames.saturating_sub(1));
        let mut camera = ShotCamera {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            zoom: 1.0,
        };
        let mut faded: Vec<(String, f32)> = Vec::new();
        for (n, segment) in self.segments.iter().enumerate() {
            let bad = |what: String| MovieError::Bad {
                segment: n + 1,
                what,
            };
            let images = |seconds: f64| -> Result<usize, MovieError> {
                if !(seconds.is_finite() && seconds > 0.0) {
                    return Err(bad(format!("seconds = {seconds}: expected > 0")));
                }
                let n = (seconds * self.fps).round().max(1.0);
                if n > MAX_SHOTS as f64 {
                    return Err(bad(format!("{seconds} s makes over {MAX_SHOTS} images")));
                }
                Ok(n as usize)
            };
            // Each timed segment moves from `camera`/`faded` (its start) to its target.
            let start = camera;
            let mut push = |frame: usize, camera: ShotCamera, faded: &[(String, f32)]| {
                shots.push(Shot {
                    frame,
                    camera,
                    opacity: faded.to_vec(),
                });
            };
            match segment {
                Segment::Play { from, to, step } => {
                    for (name, f) in [("from", *from), ("to", *to)] {
                        if f >= frames {
                            return Err(bad(format!(
                                "{name} = {f}: the trajectory has {frames} frames"
                            )));
                        }
                    }
                    if *step == 0 {
                        return Err(bad("step = 0: expected at least 1".into()));
                    }
                    let count = from.abs_diff(*to) / step + 1;
                    for k in 0..count {
                        frame = if to >= from {
                            from + k * step
                        } else {
                            from - k * step
                        };
                        push(frame, camera, &faded);
                    }
                }
                Segment::Hold { seconds } => {
                    for _ in 0..images(*seconds)? {
                        push(frame, camera, &faded);
                    }
                }
                Segment::Turn {
                    degrees,
                    axis,
                    seconds,
                } => {
                    if !degrees.is_finite() {
                        return Err(bad(format!("degrees = {degrees}: expected a number")));
                    }
                    let n = images(*seconds)?;
                    for k in 1..=n {
                        let angle = if k == n {
                            *degrees
                        } else {
                            degrees * k as f32 / n as f32
                        };
                        camera = match axis {
                            TurnAxis::Vertical => ShotCamera {
                                yaw_deg: start.yaw_deg + angle,
                                ..start
                            },
                            TurnAxis::Horizontal => ShotCamera {
                                pitch_deg: start.pitch_deg + angle,
                                ..start
                            },
                        };
                        push(frame, camera, &faded);
                    }
                }
                Segment::Zoom { factor, seconds } => {
                    if !(factor.is_finite() && *factor > 0.0) {
                        return Err(bad(format!("factor = {factor}: expected > 0")));
                    }
                    let n = images(*seconds)?;
                    for k in 1..=n {
                        let t = smoothstep(k as f32 / n as f32);
                        camera.zoom = start.zoom * factor.powf(t);
                        push(frame, camera, &faded);
                    }
                }
                Segment::Fly { view, seconds } => {
                    let target = self.views.iter().find(|v| &v.name == view).ok_or_else(|| {
                        let names: Vec<&str> = self.views.iter().map(|v| v.name.as_str()).collect();
                        bad(format!(
                            "no view named '{view}' (views: {})",
                            if names.is_empty() {
                                "none".to_string()
                            } else {
                                names.join(", ")
                            }
                        ))
                    })?;
                    if !(target.zoom.is_finite() && target.zoom > 0.0) {
                        return Err(bad(format!(
                            "view '{view}': zoom = {}: expected > 0",
                            target.zoom
                        )));
                    }
                    // The shorter way round to the view's yaw.
                    let turn = (target.yaw_deg - start.yaw_deg + 180.0).rem_euclid(360.0) - 180.0;
                    let n = images(*seconds)?;
                    for k in 1..=n {
                        let t = smoothstep(k as f32 / n as f32);
                        camera = ShotCamera {
                            yaw_deg: start.yaw_deg + turn * t,
                            pitch_deg: start.pitch_deg + (target.pitch_deg - start.pitch_deg) * t,
                            zoom: start.zoom * (target.zoom / start.zoom).powf(t),
                        };
                        push(frame, camera, &faded);
                    }
                }
                Segment::Fade { rep, to, seconds } => {
                    if !(0.0..=1.0).contains(to) {
                        return Err(bad(format!("to = {to}: expected an opacity 0..1")));
                    }
                    let own = opacity(rep)
                        .ok_or_else(|| bad(format!("no representation named '{rep}'")))?;
                    let from = faded
                        .iter()
                        .find(|(name, _)| name == rep)
                        .map_or(own, |(_, o)| *o);
                    let n = images(*seconds)?;
                    for k in 1..=n {
                        let o = if k == n {
                            *to
                        } else {
                            from + (to - from) * k as f32 / n as f32
                        };
                        match faded.iter_mut().find(|(name, _)| name == rep) {
                            Some(entry) => entry.1 = o,
                            None => faded.push((rep.clone(), o)),
                        }
                        push(frame, camera, &faded);
                    }
                }
            }
            if shots.len() > MAX_SHOTS {
                return Err(bad(format!("the movie passes {MAX_SHOTS} images")));
            }
        }
        Ok(shots)
    }
}
