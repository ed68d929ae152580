//! Why a look setting was refused: a value out of range or a name that is not known. Each
//! prints as one line naming the value as given.

/// A look setting that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingError {
    /// An eye separation (fraction of the focal distance) that is negative or not finite.
    #[error("bad eye separation {0}: expected a fraction of the focal distance >= 0, e.g. 0.033")]
    EyeSeparation(f32),
    /// A focal distance (Å) that is not positive or not finite.
    #[error("bad focal distance {0}: expected a positive distance in Å from the camera")]
    FocalDistance(f32),
    /// An outline width (pixels) outside 0 to [`super::settings::MAX_OUTLINE_PX`].
    #[error("bad outline width {0}: expected pixels from 0 (off) to {max}", max = super::settings::MAX_OUTLINE_PX)]
    OutlineWidth(f32),
    /// A shadow strength outside 0 to 1.
    #[error("bad shadow strength {0}: expected 0 (off) to 1")]
    Shadows(f32),
    /// A progressive sample count outside 1 to [`super::settings::MAX_SAMPLES`].
    #[error("bad sample count {0}: expected 1 (one plain draw) to {max}", max = super::settings::MAX_SAMPLES)]
    Samples(u32),
    /// A stereo mode name that is not known (the text as given).
    #[error("unknown stereo mode '{0}' (expected off, sbs, sbs-cross, anaglyph or anaglyph-grey)")]
    Stereo(String),
    /// An atom style name that is not known (the text as given).
    #[error("unknown atom style '{0}' (expected none, spheres, sticks or ball-and-stick)")]
    AtomStyle(String),
    /// A background name that is not known (the text as given).
    #[error("unknown background '{0}' (expected dark or light)")]
    Background(String),
    /// A colour that does not parse (the text as given).
    #[error("bad colour '{0}': expected black, white, grey, #rrggbb or r,g,b (0..1)")]
    Colour(String),
}
