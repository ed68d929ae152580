//! What the user can ask the viewer for: the [`Command`]s that the panels, the keyboard, the
//! console and scripts produce, and that [`super::state::AppCore::apply`] (state) and
//! `Viewer::apply` (window: dialogs, files, screenshots) carry out in one place.

use std::path::PathBuf;

use super::timeline::TimelineCmd;
use crate::model::ColorScheme;
use crate::render::{Projection, RenderSettings};
use crate::scene::representation::Representation;
use crate::surface::{Preset, SurfaceParams};

/// Something the user asked for.
#[derive(Debug, Clone)]
pub enum Command {
    /// Open files (topology, optional trajectory) in the background.
    Open(PathBuf, Option<PathBuf>),
    /// Show the file dialog (in the background).
    OpenDialog,
    /// New surface parameters of the selected representation (already checked against the
    /// grid limit).
    SetParams(SurfaceParams),
    /// A preset's vertex placement and radii for the selected surface representation (its R, I
    /// and quality come as [`Command::SetParams`]).
    ApplyPreset(Preset),
    /// Bead surface (one bead per residue) on or off for the selected representation.
    SetBeads(bool),
    /// Colour scheme of the selected representation.
    SetColours(ColorScheme),
    /// Select representation `i` for editing.
    SelectRep(usize),
    /// Add a representation (a surface of everything) and select it.
    AddRep,
    /// Duplicate representation `i` and select the copy.
    DuplicateRep(usize),
    /// Delete representation `i`.
    DeleteRep(usize),
    /// Replace representation `i` (its selection already parsed by the panel).
    UpdateRep(usize, Box<Representation>),
    /// Replace every representation (File → Open view).
    SetReps(Vec<Representation>),
    /// Save the view (representations, camera, look, timeline) as a state file (dialog when
    /// `None`).
    SaveView(Option<PathBuf>),
    /// Open a state file and apply it (dialog when `None`).
    OpenView(Option<PathBuf>),
    /// Look of the picture.
    SetRender(RenderSettings),
    /// Playback.
    Timeline(TimelineCmd),
    /// Camera back to the default direction, fitted to the scene.
    ResetCamera,
    /// Fit the scene, keeping the direction.
    FitCamera,
    /// Fit this sphere (centre, radius in Å), keeping the direction (console `fit "SEL"`).
    FitSphere(glam::Vec3, f32),
    /// Perspective or orthographic.
    SetProjection(Projection),
    /// Rotate the camera about its target (radians right, up).
    Orbit(f32, f32),
    /// Move the camera in the view plane (fractions of the view height, right, up).
    Pan(f32, f32),
    /// Multiply the camera distance.
    Zoom(f32),
    /// Turntable speed in degrees per second (`None`: off).
    SetTurntable(Option<f32>),
    /// Save a screenshot: scale of the window size, or an explicit size, to a path (dialog when
    /// `None`).
    Screenshot {
        /// Multiple of the viewport size (1 to 4) when `size` is `None`.
        scale: u32,
        /// Explicit width and height in pixels.
        size: Option<[u32; 2]>,
        /// Output file; `None` asks with a dialog.
        path: Option<PathBuf>,
    },
    /// Start a movie export.
    StartMovie(super::export::MoviePlan),
    /// Stop the movie export.
    CancelMovie,
    /// Write the area/volume history as CSV (dialog when `None`).
    ExportCsv(Option<PathBuf>),
    /// Close the error message.
    DismissError,
    /// Show (`true`) or hide the keyboard shortcut list (window layer; see `app::keys`).
    ShowShortcuts(bool),
    /// Show or hide the console under the viewport (window layer; see `app::console_ui`).
    ToggleConsole,
    /// Pause, resume or detach from the running simulation (`--imd`).
    Live(crate::io::LiveAction),
    /// Forget the kept panel layout and look, and give the window its first size (window
    /// layer; see `app::settings_store`).
    ResetLayout,
}

/// A switch typed as `on` or `off` (console settings such as `rep N cavities`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OnOff(pub bool);

impl std::str::FromStr for OnOff {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "on" => Ok(OnOff(true)),
            "off" => Ok(OnOff(false)),
            other => Err(format!("expected on or off, got '{other}'")),
        }
    }
}
