//! How a picture looks, independent of what is in it: background, surface opacity and colour,
//! atom style, depth cue and stereo. The app edits one of these; `mdsurf render` builds one from
//! its flags; the renderer turns it into uniforms.

use std::fmt;
use std::str::FromStr;

pub use super::setting_error::SettingError;

/// Background colour of the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Background {
    /// Near-black.
    #[default]
    Dark,
    /// White.
    Light,
}

impl Background {
    /// Linear RGB colour of the background.
    pub fn linear_rgb(self) -> [f32; 3] {
        match self {
            Background::Dark => [0.008, 0.009, 0.012],
            Background::Light => [1.0, 1.0, 1.0],
        }
    }
}

/// How atoms are drawn (besides the surface).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AtomStyle {
    /// No atoms.
    #[default]
    Hidden,
    /// Spheres of the atom radius (times `atom_scale`).
    Spheres,
    /// Licorice: bonds as sticks, atoms as spheres of the stick radius.
    Sticks,
    /// Small spheres (a quarter of the radius) joined by sticks.
    BallAndStick,
}

impl AtomStyle {
    /// All styles, in menu order.
    pub const ALL: [AtomStyle; 4] = [
        AtomStyle::Hidden,
        AtomStyle::Spheres,
        AtomStyle::Sticks,
        AtomStyle::BallAndStick,
    ];

    /// Name for menus and the command line.
    pub fn name(self) -> &'static str {
        match self {
            AtomStyle::Hidden => "none",
            AtomStyle::Spheres => "spheres",
            AtomStyle::Sticks => "sticks",
            AtomStyle::BallAndStick => "ball-and-stick",
        }
    }

    /// True when bonds are drawn.
    pub fn has_bonds(self) -> bool {
        matches!(self, AtomStyle::Sticks | AtomStyle::BallAndStick)
    }
}

/// Stereo output. Both eyes look through off-axis frusta around the camera (see
/// [`crate::render::camera::Camera::eye_matrices`]): the focal plane has zero parallax.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Stereo {
    /// One view.
    #[default]
    Off,
    /// Side by side, wall-eyed (parallel) viewing: the left eye's image in the left half, the
    /// right eye's in the right half (each half keeps its own aspect ratio; also for 3D
    /// displays).
    SideBySide,
    /// Side by side, cross-eyed viewing: the right eye's image in the left half.
    SideBySideCross,
    /// Red (left eye) / cyan (right eye) anaglyph in colour: red from the left eye's red
    /// channel, green and blue from the right eye's.
    Anaglyph,
    /// Red/cyan anaglyph of the eyes' luminance, so surface colours do not rival between eyes.
    AnaglyphGrey,
}

impl Stereo {
    /// All modes, in menu order.
    pub const ALL: [Stereo; 5] = [
        Stereo::Off,
        Stereo::SideBySide,
        Stereo::SideBySideCross,
        Stereo::Anaglyph,
        Stereo::AnaglyphGrey,
    ];

    /// Name for menus and the command line (`off`, `sbs`, `sbs-cross`, `anaglyph`,
    /// `anaglyph-grey`).
    pub fn name(self) -> &'static str {
        match self {
            Stereo::Off => "off",
            Stereo::SideBySide => "sbs",
            Stereo::SideBySideCross => "sbs-cross",
            Stereo::Anaglyph => "anaglyph",
            Stereo::AnaglyphGrey => "anaglyph-grey",
        }
    }

    /// True for the two anaglyph modes (each eye is rendered into its own texture first).
    pub fn is_anaglyph(self) -> bool {
        matches!(self, Stereo::Anaglyph | Stereo::AnaglyphGrey)
    }

    /// True for the two side-by-side modes.
    pub fn is_side_by_side(self) -> bool {
        matches!(self, Stereo::SideBySide | Stereo::SideBySideCross)
    }
}

/// Default eye separation: 1/30 of the focal distance (a common stereo-photography rule).
pub const DEFAULT_EYE_SEPARATION: f32 = 1.0 / 30.0;

/// Checks an eye separation (fraction of the focal distance): finite and not negative.
pub fn check_eye_separation(f: f32) -> Result<f32, SettingError> {
    if f.is_finite() && f >= 0.0 {
        Ok(f)
    } else {
        Err(SettingError::EyeSeparation(f))
    }
}

/// Checks a focal distance (Å from the camera): finite and positive.
pub fn check_focal_distance(d: f32) -> Result<f32, SettingError> {
    if d.is_finite() && d > 0.0 {
        Ok(d)
    } else {
        Err(SettingError::FocalDistance(d))
    }
}

impl fmt::Display for Stereo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stereo {
    type Err = SettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stereo::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .or_else(|| {
                s.eq_ignore_ascii_case("anaglyph-gray")
                    .then_some(Stereo::AnaglyphGrey)
            })
            .ok_or_else(|| SettingError::Stereo(s.to_string()))
    }
}

/// Everything about the look of a picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Background colour.
    pub background: Background,
    /// Whether the surface is drawn.
    pub show_surface: bool,
    /// Surface opacity, 0 (invisible) to 1 (opaque).
    pub surface_opacity: f32,
    /// A single linear RGB surface colour, or `None` for the per-vertex colours.
    pub surface_colour: Option<[f32; 3]>,
    /// How atoms are drawn.
    pub atom_style: AtomStyle,
    /// Sphere radius as a fraction of the atom radius (for [`AtomStyle::Spheres`]).
    pub atom_scale: f32,
    /// Stick radius in Å.
    pub stick_radius: f32,
    /// Depth-cue strength, 0 (off) to 1 (the far side fades fully into the background).
    pub depth_cue: f32,
    /// Screen-space ambient occlusion strength, 0 (off) to 1: creases and pockets darken.
    pub ambient_occlusion: f32,
    /// Stereo mode.
    pub stereo: Stereo,
    /// Distance between the eyes as a fraction of the focal distance (default 1/30; 0.02 to 0.07
    /// is comfortable).
    pub eye_separation: f32,
    /// Distance from the camera to the stereo focal (zero-parallax) plane in Å, or `None` to
    /// follow the camera's target.
    pub focal_distance: Option<f32>,
    /// Silhouette outline width in pixels (0: off): lines where the depth jumps (relative to the
    /// depth), on the nearer side (just inside a silhouette), or where the surface turns
    /// sharply; smooth surfaces are not darkened inside and the background is left alone.
    pub outline_width: f32,
    /// Linear RGB colour of the outlines.
    pub outline_colour: [f32; 3],
    /// Strength of the soft shadows cast by the key light, 0 (off) to 1 (the key light fully
    /// blocked in shadow). Screen-space: only what is on screen casts shadows.
    pub shadows: f32,
    /// Background pixels get alpha 0 (PNG with a transparent background); what is drawn keeps
    /// alpha 1 (edges of outlines and see-through surfaces may be fractional).
    pub transparent_background: bool,
    /// Progressive samples per offscreen picture (screenshots, movies, `mdsurf render`): the
    /// scene is drawn this many times, each with the ambient-occlusion and shadow sample
    /// patterns turned and the camera moved by a sub-pixel offset, and the draws are averaged
    /// (smooth occlusion and shadows, anti-aliased edges). 1: one plain draw. The window's own
    /// draw is always one sample.
    pub samples: u32,
    /// Which progressive sample a draw is (0: the plain draw); set by
    /// [`crate::render::render_to_rgba`] for each of [`RenderSettings::samples`].
    pub sample: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            background: Background::Dark,
            show_surface: true,
            surface_opacity: 1.0,
            surface_colour: None,
            atom_style: AtomStyle::Hidden,
            atom_scale: 1.0,
            stick_radius: 0.25,
            depth_cue: 0.6,
            ambient_occlusion: 0.7,
            stereo: Stereo::Off,
            eye_separation: DEFAULT_EYE_SEPARATION,
            focal_distance: None,
            outline_width: 0.0,
            outline_colour: [0.0; 3],
            shadows: 0.0,
            transparent_background: false,
            samples: 1,
            sample: 0,
        }
    }
}

/// Outline width of the figure look, in pixels (see [`RenderSettings::figure`]).
pub const FIGURE_OUTLINE_PX: f32 = 2.0;
/// Shadow strength of the figure look.
pub const FIGURE_SHADOWS: f32 = 0.5;
/// Largest outline width in pixels.
pub const MAX_OUTLINE_PX: f32 = 16.0;
/// Progressive samples of the high look (see [`RenderSettings::samples`]).
pub const HIGH_SAMPLES: u32 = 32;
/// Most progressive samples per picture.
pub const MAX_SAMPLES: u32 = 256;

/// Checks a progressive sample count: 1 to [`MAX_SAMPLES`].
pub fn check_samples(n: u32) -> Result<u32, SettingError> {
    if (1..=MAX_SAMPLES).contains(&n) {
        Ok(n)
    } else {
        Err(SettingError::Samples(n))
    }
}

/// Checks an outline width in pixels: finite, 0 (off) to [`MAX_OUTLINE_PX`].
pub fn check_outline_width(px: f32) -> Result<f32, SettingError> {
    if px.is_finite() && (0.0..=MAX_OUTLINE_PX).contains(&px) {
        Ok(px)
    } else {
        Err(SettingError::OutlineWidth(px))
    }
}

/// Checks a shadow strength: finite, 0 (off) to 1.
pub fn check_shadows(s: f32) -> Result<f32, SettingError> {
    if s.is_finite() && (0.0..=1.0).contains(&s) {
        Ok(s)
    } else {
        Err(SettingError::Shadows(s))
    }
}

/// Parses a linear RGB colour: `black`, `white`, `grey`, `#rrggbb` (sRGB hex, turned linear)
/// or `r,g,b` (linear, each 0..1).
pub fn parse_linear_rgb(s: &str) -> Result<[f32; 3], SettingError> {
    let t = s.trim().to_ascii_lowercase();
    let srgb = |v: f32| {
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let bad = || SettingError::Colour(s.to_string());
    match t.as_str() {
        "black" => return Ok([0.0; 3]),
        "white" => return Ok([1.0; 3]),
        "grey" | "gray" => return Ok([srgb(0.5); 3]),
        _ => {}
    }
    if let Some(hex) = t.strip_prefix('#') {
        if hex.len() != 6 || !hex.is_ascii() {
            return Err(bad());
        }
        let mut c = [0.0; 3];
        for (i, v) in c.iter_mut().enumerate() {
            let byte = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| bad())?;
            *v = srgb(byte as f32 / 255.0);
        }
        return Ok(c);
    }
    let parts: Vec<f32> = t
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match parts[..] {
        [r, g, b] if [r, g, b].iter().all(|v| (0.0..=1.0).contains(v)) => Ok([r, g, b]),
        _ => Err(bad()),
    }
}

impl RenderSettings {
    /// True when the surface needs the transparency passes.
    pub fn surface_is_transparent(&self) -> bool {
        self.show_surface && self.surface_opacity < 0.999
    }

    /// Turns on the figure look: black outlines of [`FIGURE_OUTLINE_PX`] pixels and shadows of
    /// strength [`FIGURE_SHADOWS`]; ambient occlusion and depth cue stay as they are.
    pub fn figure(&mut self) {
        self.outline_width = FIGURE_OUTLINE_PX;
        self.outline_colour = [0.0; 3];
        self.shadows = FIGURE_SHADOWS;
    }

    /// Turns on the high look: the figure look drawn with [`HIGH_SAMPLES`] progressive
    /// samples per picture.
    pub fn high(&mut self) {
        self.figure();
        self.samples = HIGH_SAMPLES;
    }

    /// The sub-pixel offset (pixels, each -0.5 to 0.5) of progressive sample `sample`: 0 for
    /// the plain draw, then the Halton (2, 3) sequence, which covers the pixel evenly.
    pub fn sample_offset(sample: u32) -> [f32; 2] {
        let halton = |mut i: u32, base: u32| {
            let (mut f, mut r) = (1.0f32, 0.0f32);
            while i > 0 {
                f /= base as f32;
                r += f * (i % base) as f32;
                i /= base;
            }
            r
        };
        if sample == 0 {
            [0.0; 2]
        } else {
            [halton(sample, 2) - 0.5, halton(sample, 3) - 0.5]
        }
    }

    /// True when the look pass (outlines or shadows) runs.
    pub fn has_look_pass(&self) -> bool {
        self.outline_width > 0.0 || self.shadows > 0.0
    }
}

impl FromStr for AtomStyle {
    type Err = SettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        AtomStyle::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| SettingError::AtomStyle(s.to_string()))
    }
}

impl FromStr for Background {
    type Err = SettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "dark" | "black" => Ok(Background::Dark),
            "light" | "white" => Ok(Background::Light),
            _ => Err(SettingError::Background(s.to_string())),
        }
    }
}
