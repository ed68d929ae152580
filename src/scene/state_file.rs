//! The state file: representations, camera, look and trajectory settings in one human-readable
//! TOML file with a version field. The viewer writes it (File → Save view) and reads it (File →
//! Open view, `mdsurf TOP TRAJ --state FILE`); `mdsurf render --state` and `mdsurf surface
//! --state` read it, so a picture made in the window can be re-made headless or on a cluster.
//!
//! ```toml
//! version = 1
//!
//! [[representation]]
//! name = "protein"
//! selection = "protein"
//! style = "surface"
//! colour = "residue-type"
//! opacity = 1.0
//! spacing = 1.0
//! radius_scale = 1.0
//! isovalue = 0.5
//! quality = "medium"
//! cavities = false  # surfaces: find and draw the enclosed cavities every frame
//! cavity_probe = 1.4  # optional, with cavities: the voids a 1.4 Å probe fits in (SES)
//! visible = true
//!
//! [camera]          # optional: without it the camera fits the scene
//! yaw_deg = 30.0
//! pitch_deg = 10.0
//!
//! [look]
//! background = "light"
//! ```

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::representation::Representation;
pub use super::state_error::{LookError, RepresentationError, StateFileError};
use crate::render::settings::SettingError;
use crate::render::{Background, Camera, Projection, RenderSettings};

/// The state-file format version this build writes and reads.
pub const STATE_VERSION: u32 = 1;

/// Everything a state file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateFile {
    /// Format version ([`STATE_VERSION`]).
    pub version: u32,
    /// The representations, drawn in this order.
    #[serde(default, rename = "representation")]
    pub representations: Vec<Representation>,
    /// The camera; `None` fits the camera to the scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraState>,
    /// Background, shading and stereo.
    #[serde(default)]
    pub look: LookState,
    /// Which frame is shown and how the timeline plays.
    #[serde(default)]
    pub trajectory: TrajectoryState,
    /// A camera script for movies ([`super::movie`]); `render --state` plays it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub movie: Option<super::movie::MovieScript>,
}

/// The orbit camera, in degrees and Å.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraState {
    /// Point the camera orbits (Å).
    pub target: [f32; 3],
    /// Eye-to-target distance (Å).
    pub distance: f32,
    /// Rotation about the vertical axis (degrees).
    pub yaw_deg: f32,
    /// Elevation (degrees).
    pub pitch_deg: f32,
    /// Vertical field of view (degrees).
    pub fov_deg: f32,
    /// True for an orthographic projection.
    pub orthographic: bool,
    /// Radius of the scene around the target (Å; clip planes and depth cue).
    pub scene_radius: f32,
    /// When true, only the direction (yaw, pitch, projection) is used and the camera is fitted
    /// to the scene (a state written by hand usually wants this).
    pub fit: bool,
    /// The world direction shown upwards on screen (a unit vector; `[0, 1, 0]` by default, a
    /// membrane's normal in its side view).
    pub vertical: [f32; 3],
}

impl Default for CameraState {
    fn default() -> Self {
        CameraState::from_camera(&Camera::default(), true)
    }
}

impl CameraState {
    /// The state of `camera`; `fit` asks readers to refit the distance and target.
    pub fn from_camera(camera: &Camera, fit: bool) -> Self {
        CameraState {
            target: camera.target.to_array(),
            distance: camera.distance,
            yaw_deg: camera.yaw.to_degrees(),
            pitch_deg: camera.pitch.to_degrees(),
            fov_deg: camera.fov_y.to_degrees(),
            orthographic: camera.projection == Projection::Orthographic,
            scene_radius: camera.scene_radius,
            fit,
            vertical: camera.vertical.to_array(),
        }
    }

    /// Applies this state to `camera` (all of it, or only the direction when [`Self::fit`]).
    pub fn apply(&self, camera: &mut Camera) {
        camera.yaw = self.yaw_deg.to_radians();
        camera.pitch = self.pitch_deg.to_radians();
        let vertical = glam::Vec3::from(self.vertical);
        camera.vertical = if vertical.is_finite() {
            vertical.normalize_or(glam::Vec3::Y)
        } else {
            glam::Vec3::Y
        };
        camera.projection = if self.orthographic {
            Projection::Orthographic
        } else {
            Projection::Perspective
        };
        if self.fov_deg.is_finite() && self.fov_deg > 1.0 && self.fov_deg < 170.0 {
            camera.fov_y = self.fov_deg.to_radians();
        }
        if !self.fit {
            camera.target = self.target.into();
            camera.distance = self.distance;
            camera.scene_radius = self.scene_radius;
        }
    }
}

/// Look settings that are not per representation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LookState {
    /// `dark` or `light`.
    pub background: String,
    /// Ambient occlusion strength 0..1.
    pub ambient_occlusion: f32,
    /// Depth cue strength 0..1.
    pub depth_cue: f32,
    /// Stereo mode name (`off`, `sbs`, `anaglyph`, ...).
    pub stereo: String,
    /// Eye separation as a fraction of the focal distance.
    pub eye_separation: f32,
    /// Fixed stereo focal (zero-parallax) distance in Å from the camera; absent: the distance
    /// to the camera's target.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_distance: Option<f32>,
    /// Silhouette outline width in pixels (0: off); absent: as the command line says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outline_width: Option<f32>,
    /// Outline colour, linear RGB 0..1; absent: as the command line says (black).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outline_colour: Option<[f32; 3]>,
    /// Key-light shadow strength 0..1 (0: off); absent: as the command line says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadows: Option<f32>,
    /// Transparent PNG background; absent: as the command line says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transparent_background: Option<bool>,
    /// Progressive samples per picture (1 to 256); absent: as the command line says (1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
}

impl Default for LookState {
    fn default() -> Self {
        LookState::from_settings(&RenderSettings::default())
    }
}

impl LookState {
    /// The look part of `settings`.
    pub fn from_settings(settings: &RenderSettings) -> Self {
        LookState {
            background: match settings.background {
                Background::Dark => "dark".into(),
                Background::Light => "light".into(),
            },
            ambient_occlusion: settings.ambient_occlusion,
            depth_cue: settings.depth_cue,
            stereo: settings.stereo.to_string(),
            eye_separation: settings.eye_separation,
            focal_distance: settings.focal_distance,
            // Written only when on, so a saved default look leaves `--look figure` alone.
            outline_width: (settings.outline_width > 0.0).then_some(settings.outline_width),
            outline_colour: (settings.outline_width > 0.0 && settings.outline_colour != [0.0; 3])
                .then_some(settings.outline_colour),
            shadows: (settings.shadows > 0.0).then_some(settings.shadows),
            transparent_background: settings.transparent_background.then_some(true),
            samples: (settings.samples > 1).then_some(settings.samples),
        }
    }

    /// Applies this look to `settings`; fails naming the first bad value.
    pub fn apply(&self, settings: &mut RenderSettings) -> Result<(), LookError> {
        use crate::render::settings::{
            check_eye_separation, check_focal_distance, check_outline_width, check_samples,
            check_shadows,
        };
        let setting =
            |key: &'static str| move |source: SettingError| LookError::Setting { key, source };
        settings.background = self.background.parse()?;
        settings.stereo = self.stereo.parse()?;
        for (key, value) in [
            ("ambient_occlusion", self.ambient_occlusion),
            ("depth_cue", self.depth_cue),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(LookError::Fraction { key, value });
            }
        }
        check_eye_separation(self.eye_separation).map_err(setting("eye_separation"))?;
        if let Some(f) = self.focal_distance {
            check_focal_distance(f).map_err(setting("focal_distance"))?;
        }
        settings.focal_distance = self.focal_distance;
        settings.ambient_occlusion = self.ambient_occlusion;
        settings.depth_cue = self.depth_cue;
        settings.eye_separation = self.eye_separation;
        if let Some(px) = self.outline_width {
            settings.outline_width = check_outline_width(px).map_err(setting("outline_width"))?;
        }
        if let Some(c) = self.outline_colour {
            if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
                return Err(LookError::OutlineColour(c));
            }
            settings.outline_colour = c;
        }
        if let Some(v) = self.shadows {
            settings.shadows = check_shadows(v).map_err(setting("shadows"))?;
        }
        if let Some(t) = self.transparent_background {
            settings.transparent_background = t;
        }
        if let Some(n) = self.samples {
            settings.samples = check_samples(n).map_err(setting("samples"))?;
        }
        Ok(())
    }
}

/// Timeline settings and the per-frame transformations (see [`crate::transform`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrajectoryState {
    /// Frame shown (from 0).
    pub frame: usize,
    /// Frames advanced per step when playing.
    pub stride: usize,
    /// Playback speed in frames per second.
    pub fps: f32,
    /// Make molecules whole (absent: on when the file has a box and connectivity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub whole: Option<bool>,
    /// Selection centred in the box.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<String>,
    /// Selection fitted onto the reference frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<String>,
    /// The fit's reference frame (`first` or `topology`).
    #[serde(default)]
    pub fit_reference: crate::transform::FitReference,
    /// Half-width of the smoothing window in frames.
    #[serde(default)]
    pub smooth: usize,
    /// Periodic density (`--periodic`): Gaussians reach across the box faces.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub periodic: bool,
    /// Images of the box shown side by side along x, y, z with `periodic` (`--replicate`).
    #[serde(default, skip_serializing_if = "crate::transform::Replicate::is_one")]
    pub replicate: crate::transform::Replicate,
}

impl Default for TrajectoryState {
    fn default() -> Self {
        TrajectoryState {
            frame: 0,
            stride: 1,
            fps: 24.0,
            whole: None,
            center: None,
            fit: None,
            fit_reference: crate::transform::FitReference::First,
            smooth: 0,
            periodic: false,
            replicate: crate::transform::Replicate::default(),
        }
    }
}

impl TrajectoryState {
    /// The transformations this state records.
    pub fn transforms(&self) -> crate::transform::TransformOptions {
        crate::transform::TransformOptions {
            whole: self.whole,
            center: self.center.clone(),
            fit: self.fit.clone(),
            fit_reference: self.fit_reference,
            smooth: self.smooth,
            periodic: self.periodic,
            replicate: self.replicate,
        }
    }

    /// Records `options`.
    pub fn set_transforms(&mut self, options: &crate::transform::TransformOptions) {
        self.whole = options.whole;
        self.center = options.center.clone();
        self.fit = options.fit.clone();
        self.fit_reference = options.fit_reference;
        self.smooth = options.smooth;
        self.periodic = options.periodic;
        self.replicate = options.replicate;
    }
}

impl StateFile {
    /// A state holding `representations` and default everything else.
    pub fn new(representations: Vec<Representation>) -> Self {
        StateFile {
            version: STATE_VERSION,
            representations,
            camera: None,
            look: LookState::default(),
            trajectory: TrajectoryState::default(),
            movie: None,
        }
    }

    /// Parses state-file text; `origin` names the file in errors. Every representation is
    /// validated (selection, parameters), and the error is one line.
    pub fn parse(text: &str, origin: &str) -> Result<Self, StateFileError> {
        let origin = || origin.to_string();
        let state: StateFile = toml::from_str(text).map_err(|e| {
            let message = e.message().replace('\n', " ").trim().to_string();
            match e.span().map(|s| line_col(text, s.start)) {
                Some((line, column)) => StateFileError::SyntaxAt {
                    origin: origin(),
                    line,
                    column,
                    message,
                },
                None => StateFileError::Syntax {
                    origin: origin(),
                    message,
                },
            }
        })?;
        if state.version != STATE_VERSION {
            return Err(StateFileError::Version {
                origin: origin(),
                found: state.version,
            });
        }
        for r in &state.representations {
            r.validate()
                .map_err(|source| StateFileError::Representation {
                    origin: origin(),
                    source,
                })?;
        }
        let mut probe = RenderSettings::default();
        state
            .look
            .apply(&mut probe)
            .map_err(|source| StateFileError::Look {
                origin: origin(),
                source,
            })?;
        state
            .trajectory
            .replicate
            .validate()
            .map_err(|source| StateFileError::Replicate {
                origin: origin(),
                source,
            })?;
        Ok(state)
    }

    /// Reads and checks the state file at `path` (one-line errors naming the file).
    pub fn load(path: &Path) -> Result<Self, StateFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| StateFileError::Read {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The TOML text of this state.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot write state: {e}\n"))
    }

    /// Writes the state to `path` atomically (a failed write leaves any old file as it was).
    pub fn save(&self, path: &Path) -> Result<(), StateFileError> {
        let text = self.to_toml();
        crate::export::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
        Ok(())
    }
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::representation::RepStyle;

    #[test]
    fn round_trips_through_toml() {
        let mut state = StateFile::new(vec![
            Representation::new("protein", "protein", RepStyle::Surface),
            Representation {
                opacity: 0.4,
                spacing: 2.0,
                visible: false,
                ..Representation::new("lipids", "lipid", RepStyle::Beads)
            },
        ]);
        state.camera = Some(CameraState::from_camera(&Camera::default(), false));
        let text = state.to_toml();
        assert!(text.contains("version = 1"), "{text}");
        let back = StateFile::parse(&text, "s.toml").expect("parse");
        assert_eq!(back, state);
    }

    #[test]
    fn keeps_the_cavities_switch_and_old_files_load_without_it() {
        let state = StateFile::new(vec![
            Representation {
                cavities: true,
                ..Representation::new("protein", "protein", RepStyle::Surface)
            },
            Representation::new("rest", "all", RepStyle::Surface),
        ]);
        let text = state.to_toml();
        assert!(text.contains("cavities = true"), "{text}");
        let back = StateFile::parse(&text, "s.toml").expect("parse");
        assert_eq!(back, state);
        assert!(back.representations[0].cavities && !back.representations[1].cavities);
        assert!(!text.contains("cavity_probe"), "{text}");
        let old = "version = 1\n[[representation]]\nname = \"p\"\nselection = \"all\"\n";
        let old = StateFile::parse(old, "old.toml").expect("an old file loads");
        assert!(!old.representations[0].cavities);
        assert_eq!(old.representations[0].cavity_probe, None);
        let mut probed = state.clone();
        probed.representations[0].cavity_probe = Some(1.4);
        let text = probed.to_toml();
        assert!(text.contains("cavity_probe = 1.4"), "{text}");
        assert_eq!(StateFile::parse(&text, "s.toml").expect("parse"), probed);
        let bad = text.replace("cavity_probe = 1.4", "cavity_probe = 0.0");
        let e = StateFile::parse(&bad, "s.toml").unwrap_err().to_string();
        assert!(e.contains("cavity probe 0 Å is outside 0.1 to 10 Å"), "{e}");
    }

    #[test]
    fn errors_name_file_line_and_representation() {
        let e = StateFile::parse("version = 1\nbogus = 3\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml:2:"), "{e}");
        let e = StateFile::parse("version = 7\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("version 7"), "{e}");
        let text = "version = 1\n[[representation]]\nname = \"p\"\nselection = \"resname (\"\n";
        let e = StateFile::parse(text, "s.toml").unwrap_err().to_string();
        assert!(
            e.contains("representation 'p'") && e.contains("column"),
            "{e}"
        );
        let text = "version = 1\n[[representation]]\nstyle = \"ribbon\"\n";
        let e = StateFile::parse(text, "s.toml").unwrap_err().to_string();
        assert!(e.contains("ribbon"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}
