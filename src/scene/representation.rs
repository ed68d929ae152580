//! A representation: what part of the system is drawn (a selection), how (surface, bead surface,
//! spheres, sticks, ball-and-stick), in which colours, how opaque, and, for surfaces, with which
//! H, R, I and quality. The viewer, `mdsurf render`, `mdsurf surface` and the state file all use
//! this one type; [`super::layer`] binds it to a topology and turns frames into particles.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::model::{ColorScheme, ParticleOptions, RadiusOverrides};
use crate::render::AtomStyle;
use crate::surface::{Quality, RadiusSet, SurfaceParams, VertexMode};

pub use super::state_error::RepresentationError;
use crate::selection::{Selection, SelectionError};

/// How a representation draws its atoms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RepStyle {
    /// A Gaussian density surface of the selected atoms.
    #[default]
    Surface,
    /// A Gaussian density surface of one bead per residue (centred at the residue's selected
    /// atoms).
    Beads,
    /// Atoms as spheres of their radius.
    Spheres,
    /// Bonds as sticks.
    Sticks,
    /// Small spheres joined by sticks.
    BallAndStick,
}

impl RepStyle {
    /// Every style, in the order the panel lists them.
    pub const ALL: [RepStyle; 5] = [
        RepStyle::Surface,
        RepStyle::Beads,
        RepStyle::Spheres,
        RepStyle::Sticks,
        RepStyle::BallAndStick,
    ];

    /// The name used on the command line and in state files.
    pub fn name(self) -> &'static str {
        match self {
            RepStyle::Surface => "surface",
            RepStyle::Beads => "beads",
            RepStyle::Spheres => "spheres",
            RepStyle::Sticks => "sticks",
            RepStyle::BallAndStick => "ball-and-stick",
        }
    }

    /// True for the styles that compute a density surface.
    pub fn is_surface(self) -> bool {
        matches!(self, RepStyle::Surface | RepStyle::Beads)
    }

    /// The renderer's atom style for the atom styles; `None` for surfaces.
    pub fn atom_style(self) -> Option<AtomStyle> {
        match self {
            RepStyle::Surface | RepStyle::Beads => None,
            RepStyle::Spheres => Some(AtomStyle::Spheres),
            RepStyle::Sticks => Some(AtomStyle::Sticks),
            RepStyle::BallAndStick => Some(AtomStyle::BallAndStick),
        }
    }
}

impl fmt::Display for RepStyle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RepStyle {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim().to_ascii_lowercase().replace('_', "-");
        RepStyle::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .or(match s.as_str() {
                "bead-surface" | "bead" => Some(RepStyle::Beads),
                "cpk" | "vdw" => Some(RepStyle::Spheres),
                "licorice" => Some(RepStyle::Sticks),
                "ball-stick" | "ballandstick" => Some(RepStyle::BallAndStick),
                _ => None,
            })
            .ok_or_else(|| {
                format!(
                    "unknown style '{s}' (expected surface, beads, spheres, sticks or ball-and-stick)"
                )
            })
    }
}

/// One representation. In state files every field is written; a missing field takes its
/// default (see [`Representation::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Representation {
    /// Name shown in the panel and written in the `rep` column of `surface --stats`.
    pub name: String,
    /// The selection, in the language of [`Selection`].
    pub selection: String,
    /// How the atoms are drawn.
    #[serde(with = "as_text")]
    pub style: RepStyle,
    /// Colour scheme (`element`, `chain`, `residue-type`, `residue-index`, `b-factor`,
    /// `single:#rrggbb`).
    #[serde(with = "as_text")]
    pub colour: ColorScheme,
    /// Opacity, 0 (invisible) to 1 (opaque).
    pub opacity: f32,
    /// Grid spacing H in Å (surfaces).
    pub spacing: f32,
    /// Radius scale R (surfaces; Gaussian width = radius × R).
    pub radius_scale: f32,
    /// Isovalue I (surfaces; 1 = peak of one isolated atom).
    pub isovalue: f32,
    /// Gaussian cutoff: low, medium, high or max (surfaces).
    #[serde(with = "as_text")]
    pub quality: Quality,
    /// Vertex placement (surfaces): `interpolated` or `refined` (on the exact Gaussian sum,
    /// analytic normals). State files written before it existed load as interpolated.
    #[serde(with = "as_text")]
    pub vertices: VertexMode,
    /// The radii the atoms start from: `mdsurf` (the element table) or `ses` (the SES preset's);
    /// the user's radius overrides apply on top. State files written before it existed load as
    /// `mdsurf`.
    #[serde(with = "as_text")]
    pub radii: RadiusSet,
    /// Surfaces: find the enclosed cavities of the surface every frame and draw them in their
    /// own colour (see [`super::cavity_layer`]). Off by default (nothing is computed); state
    /// files written before it existed load as off.
    pub cavities: bool,
    /// Surfaces, with `cavities` on: the cavities are those a probe of this radius (Å; 1.4 for
    /// water) fits in but cannot reach, with Bondi's radii (`measure::probe_cavities`), instead
    /// of the Gaussian surface's enclosed voids. `None` (the default; absent from state files
    /// written before it existed): the surface's voids.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cavity_probe: Option<f32>,
    /// Drawn (and, for surfaces, computed) when true.
    pub visible: bool,
}

impl Default for Representation {
    fn default() -> Self {
        let p = SurfaceParams::default();
        Representation {
            name: "all".into(),
            selection: "all".into(),
            style: RepStyle::Surface,
            colour: ColorScheme::Element,
            opacity: 1.0,
            spacing: p.spacing,
            radius_scale: p.radius_scale,
            isovalue: p.isovalue,
            quality: p.quality,
            vertices: VertexMode::default(),
            radii: RadiusSet::default(),
            cavities: false,
            cavity_probe: None,
            visible: true,
        }
    }
}

impl Representation {
    /// A visible representation of `selection` drawn as `style`, with default parameters.
    pub fn new(name: &str, selection: &str, style: RepStyle) -> Self {
        Representation {
            name: name.into(),
            selection: selection.into(),
            style,
            ..Representation::default()
        }
    }

    /// The surface parameters H, R, I and quality.
    pub fn params(&self) -> SurfaceParams {
        SurfaceParams {
            spacing: self.spacing,
            radius_scale: self.radius_scale,
            isovalue: self.isovalue,
            quality: self.quality,
        }
    }

    /// Sets H, R, I and quality from `params`.
    pub fn set_params(&mut self, params: &SurfaceParams) {
        self.spacing = params.spacing;
        self.radius_scale = params.radius_scale;
        self.isovalue = params.isovalue;
        self.quality = params.quality;
    }

    /// How the selected atoms become particles (beads for the bead surface).
    pub fn particle_options(&self, radius_overrides: &RadiusOverrides) -> ParticleOptions {
        self.radii.particle_options(ParticleOptions {
            beads: self.style == RepStyle::Beads,
            radius_overrides: radius_overrides.clone(),
            colours: self.colour,
            exposure: None,
        })
    }

    /// Parses the selection.
    pub fn parse_selection(&self) -> Result<Selection, SelectionError> {
        Selection::parse(&self.selection)
    }

    /// Checks everything a state file or a panel can get wrong, naming the representation:
    /// the selection parses, the surface parameters are valid, the opacity is within 0..1.
    pub fn validate(&self) -> Result<(), RepresentationError> {
        let name = || self.name.clone();
        self.parse_selection()
            .map_err(|source| RepresentationError::Selection {
                name: name(),
                selection: self.selection.clone(),
                source,
            })?;
        if self.style.is_surface() {
            self.params()
                .validate()
                .map_err(|source| RepresentationError::Parameters {
                    name: name(),
                    source,
                })?;
        }
        if !(0.0..=1.0).contains(&self.opacity) {
            return Err(RepresentationError::Opacity {
                name: name(),
                opacity: self.opacity,
            });
        }
        if let Some(probe) = self
            .cavity_probe
            .filter(|p| !(p.is_finite() && (0.1..=10.0).contains(p)))
        {
            return Err(RepresentationError::CavityProbe {
                name: name(),
                probe,
            });
        }
        Ok(())
    }
}

/// Serde through `Display` / `FromStr`, so enums read and write as their command-line names.
mod as_text {
    use std::fmt::Display;
    use std::str::FromStr;

    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<T: Display, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(value)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: FromStr,
        T::Err: Display,
        D: Deserializer<'de>,
    {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn styles_round_trip_by_name() {
        for s in RepStyle::ALL {
            assert_eq!(s.name().parse::<RepStyle>(), Ok(s));
        }
        assert_eq!("licorice".parse::<RepStyle>(), Ok(RepStyle::Sticks));
        assert!("ribbon".parse::<RepStyle>().is_err());
        assert!(RepStyle::Beads.is_surface() && !RepStyle::Sticks.is_surface());
    }

    #[test]
    fn validation_names_the_problem() {
        let mut r = Representation::new("prot", "protein and", RepStyle::Surface);
        let e = r.validate().unwrap_err().to_string();
        assert!(
            e.contains("representation 'prot'") && e.contains("column"),
            "{e}"
        );
        r.selection = "protein".into();
        assert!(r.validate().is_ok());
        r.spacing = -1.0;
        assert!(r.validate().is_err());
        r.spacing = 1.0;
        r.opacity = 2.0;
        assert!(r.validate().unwrap_err().to_string().contains("opacity"));
    }
}
