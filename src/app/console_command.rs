//! What one line of the viewer's console means, once parsed (`super::console::parse`): the
//! commands and their arguments, before they are resolved against the app's state.

use std::path::PathBuf;

use crate::model::ColorScheme;
use crate::scene::representation::RepStyle;
use crate::surface::{Quality, VertexMode};

/// Which representation: 1-based number or name.
#[derive(Debug, Clone, PartialEq)]
pub enum RepRef {
    /// 1-based position in the list.
    Number(usize),
    /// Name shown in the panel.
    Name(String),
}

/// A change to one representation.
#[derive(Debug, Clone, PartialEq)]
pub enum RepEdit {
    /// Colour scheme.
    Color(ColorScheme),
    /// Grid spacing in Å.
    Spacing(f32),
    /// Radius scale R.
    RadiusScale(f32),
    /// Isovalue I.
    Isovalue(f32),
    /// Gaussian cutoff.
    Quality(Quality),
    /// Opacity 0..1.
    Opacity(f32),
    /// Vertex placement.
    Vertices(VertexMode),
    /// Cavities found and drawn (surfaces): the surface's voids (`None`) or a probe's (Å).
    Cavities(bool, Option<f32>),
    /// Drawing style.
    Style(RepStyle),
    /// New selection.
    Select(String),
    /// Hide.
    Hide,
    /// Show.
    Show,
    /// Delete.
    Delete,
}

/// One console command.
#[derive(Debug, Clone, PartialEq)]
pub enum ConsoleCommand {
    /// `rep add "SEL" STYLE [as NAME]`.
    RepAdd {
        /// Selection text.
        selection: String,
        /// Style.
        style: RepStyle,
        /// Name (default `rep N`).
        name: Option<String>,
    },
    /// `rep N EDIT …`.
    Rep(RepRef, RepEdit),
    /// `frame N` (0-based, as `--frame`).
    Frame(usize),
    /// `play`.
    Play,
    /// `pause`.
    Pause,
    /// `fit` or `fit "SEL"`.
    Fit(Option<String>),
    /// `view save FILE`.
    ViewSave(PathBuf),
    /// `view open FILE`.
    ViewOpen(PathBuf),
    /// `screenshot FILE [WxH]`.
    Screenshot(PathBuf, Option<[u32; 2]>),
    /// `select "SEL"`: prints the number of atoms in the current frame.
    Select(String),
    /// `imd pause|resume|detach`: the running simulation (`--imd`).
    Imd(ImdVerb),
    /// `help [TOPIC]`.
    Help(Option<String>),
}

/// What `imd` asks of the running simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImdVerb {
    /// `imd pause`.
    Pause,
    /// `imd resume`.
    Resume,
    /// `imd detach`: the simulation goes on, no more frames come.
    Detach,
}
