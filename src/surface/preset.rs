//! Named surface presets: R, I and quality chosen for a purpose, leaving H to the user
//! (issue 13 section 2). The only one so far, [`Preset::Ses`], makes the Gaussian surface's area
//! match the solvent-excluded surface (probe 1.4 Å) of proteins within 2 %; its values were
//! fitted by `scripts/ses_reference.py --fit` (smallest worst deviation) against MSMS on five
//! proteins and are checked on every row of `tests/data/ses_reference.csv`, a held-out one
//! included, by `tests/it/surface_ses.rs`.

use super::{Quality, SurfaceParams};

/// A named choice of R, I and quality.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    /// R = 0.77, I = 0.27, quality high: area within 2 % of the SES area (probe 1.4 Å, Bondi
    /// radii, MSMS) on proteins, with refined vertices at H = 1 Å (fitted on five proteins:
    /// worst deviation 1.5 %; I ± 0.01 moves the area by about 1 %). An earlier fit on two
    /// proteins (R = 0.72, I = 0.16) missed 2 % on two of three others: dimers and single
    /// chains pull apart there.
    Ses,
}

impl Preset {
    /// Every preset.
    pub const ALL: [Preset; 1] = [Preset::Ses];

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Ses => "ses",
        }
    }

    /// One-line description for help texts and tooltips.
    pub fn description(self) -> &'static str {
        match self {
            Preset::Ses => "area within 2 % of the solvent-excluded surface (probe 1.4 Å)",
        }
    }

    /// Radius scale R (dimensionless), isovalue I (dimensionless) and quality of the preset.
    pub fn values(self) -> (f32, f32, Quality) {
        match self {
            Preset::Ses => (SES_RADIUS_SCALE, SES_ISOVALUE, Quality::High),
        }
    }

    /// `params` with R, I and quality set by the preset (H kept).
    pub fn apply(self, params: SurfaceParams) -> SurfaceParams {
        let (radius_scale, isovalue, quality) = self.values();
        SurfaceParams {
            radius_scale,
            isovalue,
            quality,
            ..params
        }
    }
}

/// R of [`Preset::Ses`] (fitted; see the module docs).
const SES_RADIUS_SCALE: f32 = 0.77;
/// I of [`Preset::Ses`] (fitted; see the module docs).
const SES_ISOVALUE: f32 = 0.27;

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("unknown preset '{s}' (expected ses)"))
    }
}
