//! Why a command-line value was refused. clap prints the message after "error: invalid value
//! ... for '--flag'", so each variant is one line naming the value as given.

use mdsurf::export::video::VideoOptionError;
use mdsurf::render::settings::SettingError;

/// A command-line value that does not parse or is out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArgError {
    /// Not a number, for the flag's quantity `what`.
    #[error("bad {what} '{text}': expected a number")]
    Number {
        /// What the number is ("outline width", ...).
        what: &'static str,
        /// The value as given.
        text: String,
    },
    /// A strength or opacity that is not a number from 0 to 1.
    #[error("'{0}': expected a number from 0 to 1")]
    Unit(String),
    /// A look setting out of range.
    #[error(transparent)]
    Setting(#[from] SettingError),
    /// A video option out of range.
    #[error(transparent)]
    Video(#[from] VideoOptionError),
    /// An image size that is not WIDTHxHEIGHT.
    #[error("bad size '{0}': expected WIDTHxHEIGHT, e.g. 1920x1080")]
    Size(String),
    /// An image side of 0 or more than 16384 pixels.
    #[error("bad size '{0}': each side must be 1 to 16384 pixels")]
    SizeRange(String),
    /// A view that is not YAW,PITCH.
    #[error("bad view '{0}': expected YAW,PITCH in degrees")]
    View(String),
    /// A view angle that is not finite.
    #[error("bad view '{0}': yaw and pitch must be finite numbers")]
    ViewNotFinite(String),
    /// A movie frame rate that is not a number.
    #[error("bad frame rate '{0}': expected frames per second")]
    FrameRate(String),
    /// A `surface --fps` value out of 0 < FPS <= 1000.
    #[error("bad frame rate '{0}': expected 0 < FPS <= 1000")]
    SurfaceFps(String),
    /// A viewer-benchmark timeline speed that is not a number.
    #[error("bad frame rate '{0}': expected a number, e.g. 60")]
    PlayFps(String),
    /// A viewer-benchmark timeline speed outside 0.5 to 240 frames per second.
    #[error("frame rate '{0}' must be between 0.5 and 240")]
    PlayFpsRange(String),
    /// A turntable step that is not a number.
    #[error("bad turntable step '{0}': expected degrees per image")]
    Turntable(String),
    /// A turntable step out of range.
    #[error("bad turntable step '{0}': expected 0.01 to 360 degrees per image (or 0, or negative)")]
    TurntableRange(String),
    /// A volume (Å³) that is negative or not a number.
    #[error("'{0}': expected a volume in Å³, 0 or more")]
    Volume(String),
    /// An area (Å²) that is negative or not a number.
    #[error("'{0}': expected an area of 0 Å² or more")]
    Area(String),
    /// A probe radius (Å) out of range or not a number.
    #[error("'{0}': expected a probe radius of 0.1 to 10 Å (1.4 for water)")]
    Probe(String),
    /// An atom count that does not parse.
    #[error("bad atom count '{0}' (e.g. 1000000, 1e6, 950k, 2.37M)")]
    Count(String),
    /// An atom count out of 1 to 1e10.
    #[error("atom count '{0}' must be between 1 and 1e10")]
    CountRange(String),
    /// A `--chunk` value that is not I/N or slurm.
    #[error("bad chunk '{0}': expected I/N (0-based I < N, e.g. 0/4) or slurm")]
    Chunk(String),
    /// A chunk whose index is not below its count.
    #[error("bad chunk {index}/{count}: I must be 0 to N-1 (0-based) and N at least 1")]
    ChunkRange {
        /// The 0-based index given.
        index: usize,
        /// The number of chunks given.
        count: usize,
    },
    /// A frame range that is not START:STOP:STEP.
    #[error("bad frame range '{0}': expected START:STOP:STEP, e.g. 0:50:5, 10 or all")]
    FrameRange(String),
    /// A frame range with step 0.
    #[error("bad frame range '{0}': the step must be at least 1")]
    FrameStep(String),
}
