//! How a picture looks, independent of what is in it: background, surface opacity and colour,
//! atom style, depth cue and stereo. The app edits one of these; `mdsurf render` builds one from
//! its flags; the renderer turns it into uniforms.

use std::fmt;
use std::str::FromStr;

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

/// Stereo output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Stereo {
    /// One view.
    #[default]
    Off,
    /// Left eye in the left half of the image, right eye in the right half (each half keeps its
    /// own aspect ratio, for parallel free viewing and 3D displays).
    SideBySide,
    /// Red (left eye) / cyan (right eye) anaglyph.
    Anaglyph,
}

impl Stereo {
    /// All modes, in menu order.
    pub const ALL: [Stereo; 3] = [Stereo::Off, Stereo::SideBySide, Stereo::Anaglyph];

    /// Name for menus and the command line (`off`, `sbs`, `anaglyph`).
    pub fn name(self) -> &'static str {
        match self {
            Stereo::Off => "off",
            Stereo::SideBySide => "sbs",
            Stereo::Anaglyph => "anaglyph",
        }
    }
}

impl fmt::Display for Stereo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stereo {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stereo::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("unknown stereo mode '{s}' (expected off, sbs or anaglyph)"))
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
    /// Distance between the eyes as a fraction of the viewing distance (0.02 to 0.1 is comfortable).
    pub eye_separation: f32,
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
            eye_separation: 0.05,
        }
    }
}

impl RenderSettings {
    /// True when the surface needs the transparency passes.
    pub fn surface_is_transparent(&self) -> bool {
        self.show_surface && self.surface_opacity < 0.999
    }
}

impl FromStr for AtomStyle {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        AtomStyle::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                format!(
                    "unknown atom style '{s}' (expected none, spheres, sticks or ball-and-stick)"
                )
            })
    }
}

impl FromStr for Background {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "dark" | "black" => Ok(Background::Dark),
            "light" | "white" => Ok(Background::Light),
            _ => Err(format!("unknown background '{s}' (expected dark or light)")),
        }
    }
}
