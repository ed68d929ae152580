//! What can be wrong in a state file, typed: a representation, a look value, the replication
//! counts, its TOML syntax or version, or reading and writing it. Each displays as one line
//! naming the file (or the representation, or the `look.` key).

use crate::export::ExportError;
use crate::render::settings::SettingError;
use crate::selection::SelectionError;
use crate::surface::SurfaceError;
use crate::surface::periodic::ReplicateError;

/// A representation that cannot be shown, naming it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RepresentationError {
    /// Its selection does not parse.
    #[error("representation '{name}': selection '{selection}': {source}")]
    Selection {
        /// The representation's name.
        name: String,
        /// The selection text as given.
        selection: String,
        /// Where the selection is wrong.
        source: SelectionError,
    },
    /// Its surface parameters (spacing, radius scale, isovalue) are out of range.
    #[error("representation '{name}': {source}")]
    Parameters {
        /// The representation's name.
        name: String,
        /// Which parameter is wrong.
        source: SurfaceError,
    },
    /// Its opacity is outside 0..1.
    #[error("representation '{name}': opacity {opacity} is outside 0..1")]
    Opacity {
        /// The representation's name.
        name: String,
        /// The opacity as given.
        opacity: f32,
    },
    /// Its cavity probe radius is outside 0.1 to 10 Å.
    #[error(
        "representation '{name}': cavity probe {probe} Å is outside 0.1 to 10 Å (1.4 for water)"
    )]
    CavityProbe {
        /// The representation's name.
        name: String,
        /// The probe radius as given (Å).
        probe: f32,
    },
}

/// A `[look]` value that cannot be used, naming its key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LookError {
    /// A named value (background, stereo mode) that is not known.
    #[error(transparent)]
    Name(#[from] SettingError),
    /// A fraction (ambient occlusion, depth cue) outside 0..1.
    #[error("look.{key} = {value} is outside 0..1")]
    Fraction {
        /// The key in `[look]`.
        key: &'static str,
        /// The value as given.
        value: f32,
    },
    /// A number the renderer's own check refuses (eye separation, focal distance, outline,
    /// shadows).
    #[error("look.{key}: {source}")]
    Setting {
        /// The key in `[look]`.
        key: &'static str,
        /// What the renderer's check says.
        source: SettingError,
    },
    /// An outline colour with a channel outside 0..1.
    #[error("look.outline_colour = {0:?} is outside 0..1")]
    OutlineColour([f32; 3]),
}

/// Why a state file cannot be read, used or written.
#[derive(Debug, thiserror::Error)]
pub enum StateFileError {
    /// The file cannot be read.
    #[error("cannot read state file {path}: {source}")]
    Read {
        /// The file as given.
        path: String,
        /// The system's reason.
        source: std::io::Error,
    },
    /// The TOML does not parse or has an unknown key, at a known place.
    #[error("{origin}:{line}:{column}: {message}")]
    SyntaxAt {
        /// The file (or text) the state came from.
        origin: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What TOML says, on one line.
        message: String,
    },
    /// The TOML does not parse, at no known place.
    #[error("{origin}: {message}")]
    Syntax {
        /// The file (or text) the state came from.
        origin: String,
        /// What TOML says, on one line.
        message: String,
    },
    /// A version this build does not read.
    #[error(
        "{origin}: state file version {found} is not supported (this mdsurf reads version {})",
        super::state_file::STATE_VERSION
    )]
    Version {
        /// The file the state came from.
        origin: String,
        /// The version the file declares.
        found: u32,
    },
    /// A representation that cannot be shown.
    #[error("{origin}: {source}")]
    Representation {
        /// The file the state came from.
        origin: String,
        /// Which representation, and why.
        source: RepresentationError,
    },
    /// A `[look]` value that cannot be used.
    #[error("{origin}: {source}")]
    Look {
        /// The file the state came from.
        origin: String,
        /// Which key, and why.
        source: LookError,
    },
    /// `[trajectory] replicate` counts out of range.
    #[error("{origin}: [trajectory] {source}")]
    Replicate {
        /// The file the state came from.
        origin: String,
        /// The counts as given.
        source: ReplicateError,
    },
    /// The file cannot be written (any old file is left as it was).
    #[error(transparent)]
    Write(#[from] ExportError),
}
