//! Named surface presets: R, I, quality, vertex placement and radii chosen for a purpose,
//! leaving H to the user (issue 13 section 2). The only one so far, [`Preset::Ses`], brings the
//! Gaussian surface's area close to the solvent-excluded surface (probe 1.4 Å, external surface)
//! of proteins; its values were fitted by `scripts/ses_models.py --model exposure16 --spacing 1
//! 0.5` (smallest worst deviation over R, I, the H, N and O radii and the two exposure weights
//! at quality max, at H = 1 and 0.5 Å at once; carbon stays at 1.5 Å) against MSMS on the
//! eighteen `fit` rows of `tests/data/ses_reference.csv`, and are checked on every row, the four
//! `check` ones (proteins never in the fit) included, by `tests/it/surface_ses.rs`.
//!
//! Why radii: with mdsurf's element radii no R and I held 2 % (3.0 % at best): a sum of
//! Gaussians swells around exposed chains and fills narrow grooves, so small open proteins came
//! out larger and the others smaller. A smaller nitrogen (0.707 Å instead of 1.4) and a larger
//! oxygen (1.413 instead of 1.3) do part of the correction; the rest is per atom.
//!
//! Why radii follow exposure within 16 Å (2026-11-24, [`crate::model::exposure`]): with radii
//! per element alone the preset missed 2 % by most on the most exposed structures (1mot +3.6 %,
//! the partly unfolded 2ofg +3.8 %). Shrinking atoms with fewer than 60 heavy atoms within 10 Å
//! brought every row to 2.13 %, five of them just over 2 %. Counting within 16 Å instead, the
//! shrink ending at 160 heavy atoms, holds every row to 1.84 % at H = 0.35 to 1 Å: a count over
//! 16 Å sees how open the protein is around an atom (a small domain, a loose loop) where 10 Å
//! sees little more than its own residue's neighbours. Counts within 6 to 16 Å, two terms, and
//! features for the atoms that line grooves were screened on the fit rows (README).
//!
//! History: R 0.832, I 0.378, H 0.964, N 0.882, O 1.374 with the 10 Å shrink (2.13 %); before
//! it R 0.832, I 0.382, H 0.986, N 0.922, O 1.402 with constant radii (1.93 % on sixteen rows,
//! 3.9 % on 2ofg); before that R 0.83, I 0.377, H 0.991, N 1.136, O 1.331, made when the sharp
//! triangles of this surface were measured 12 % short ([`super::curved`]).

use super::{Quality, SurfaceParams, VertexMode};
use crate::model::exposure::ExposureModel;
use crate::model::{ParticleOptions, RadiusOverride, RadiusOverrides};

/// A named choice of R, I and quality.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    /// R = 0.802, I = 0.293, quality max, refined vertices and [`RadiusSet::Ses`] radii
    /// (following exposure): area within 1.84 % of the SES area of the external surface (probe
    /// 1.4 Å, Bondi radii, MSMS) on the eighteen proteins of 408 to 9,466 atoms it was fitted
    /// on and on the four never fitted, at every H from 0.35 to 1 Å; 2.53 % at 1.5 Å and 3.9 %
    /// at 2 Å, where the grid no longer resolves its creases (see the README). Made for
    /// proteins: a small molecule alone, with few heavy atoms within 16 Å, shrinks to 40 % of
    /// its radii.
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
            Preset::Ses => {
                "area close to the solvent-excluded surface (probe 1.4 Å): within 1.84 % on 22 \
                 proteins at H = 0.35 to 1 Å"
            }
        }
    }

    /// Radius scale R (dimensionless), isovalue I (dimensionless) and quality of the preset.
    pub fn values(self) -> (f32, f32, Quality) {
        match self {
            Preset::Ses => (SES_RADIUS_SCALE, SES_ISOVALUE, Quality::Max),
        }
    }

    /// How the preset places vertices. [`Preset::Ses`] was fitted with refined vertices (the
    /// areas it was fitted on hardly move with H); with interpolated ones the areas are several
    /// % smaller and move with H (the interpolated area of 1hpv's SES surface at H = 1 Å is
    /// 2.7 % under its refined one). The command line's
    /// `--vertices` and the window's "vertices" box still override it.
    pub fn vertices(self) -> VertexMode {
        match self {
            Preset::Ses => VertexMode::Refined,
        }
    }

    /// Which radii the preset gives the atoms (before the user's own overrides).
    pub fn radius_set(self) -> RadiusSet {
        match self {
            Preset::Ses => RadiusSet::Ses,
        }
    }

    /// The grid spacings (Å) over which the preset was fitted and holds its promise, finest
    /// and coarsest. [`Preset::Ses`]: 0.35 to 1 Å (at 1.5 Å its worst row is 2.53 % off the
    /// SES, at 2 Å 3.9 %: the grid no longer resolves the creases of its sharp surface).
    pub fn spacing_range(self) -> (f32, f32) {
        match self {
            Preset::Ses => (SES_FINEST_SPACING, SES_COARSEST_SPACING),
        }
    }

    /// A one-line note when `spacing` (Å) lies outside [`Self::spacing_range`], for the
    /// command line and the window; `None` inside it.
    pub fn spacing_note(self, spacing: f32) -> Option<String> {
        let (finest, coarsest) = self.spacing_range();
        if spacing > coarsest {
            Some(format!(
                "the {} preset holds its area to the SES at H = {finest} to {coarsest} Å; at \
                 H = {spacing} Å the grid is too coarse for its creases (up to 3.9 % off at \
                 2 Å): use H = {coarsest} Å or finer (--spacing {coarsest})",
                self.name()
            ))
        } else {
            // Finer than the fitted range only costs time: the area converges as H shrinks.
            None
        }
    }

    /// `params` with R, I and quality set by the preset (H kept; the vertex mode, which is
    /// not part of [`SurfaceParams`], is [`Self::vertices`]).
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
const SES_RADIUS_SCALE: f32 = 0.802;
/// I of [`Preset::Ses`] (fitted; see the module docs).
const SES_ISOVALUE: f32 = 0.293;

/// Finest grid spacing (Å) [`Preset::Ses`] was checked at (`ses_reference.py --spacings`).
const SES_FINEST_SPACING: f32 = 0.35;
/// Coarsest grid spacing (Å) at which [`Preset::Ses`] holds 2 % on its fit rows.
const SES_COARSEST_SPACING: f32 = 1.0;

/// Radii (Å) by element of [`RadiusSet::Ses`] (fitted with R and I; see the module docs).
const SES_RADII: [(&str, f32); 3] = [("H", 1.020), ("N", 0.707), ("O", 1.413)];
/// How [`RadiusSet::Ses`] radii follow exposure ([`crate::model::exposure`]; fitted with R, I
/// and the radii): heavy atoms counted within 16 Å; an atom with 160 or more keeps its radius,
/// one with fewer shrinks by 59.8 % of the missing fraction (one with 80 by 29.9 %).
const SES_EXPOSURE: ExposureModel = ExposureModel {
    radius: 16.0,
    terms: &[(160.0, -0.598)],
};

/// The radii a representation's atoms start from: mdsurf's element table (DESIGN section 2) or
/// a preset's, with the user's `--radius` overrides on top of either.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RadiusSet {
    /// The file's radii, else the element table (DESIGN section 2).
    #[default]
    Mdsurf,
    /// [`Preset::Ses`]'s: H 1.020, N 0.707, O 1.413 Å, the rest as [`RadiusSet::Mdsurf`],
    /// following exposure frame by frame ([`RadiusSet::exposure`]).
    Ses,
}

impl RadiusSet {
    /// Every set, the default first.
    pub const ALL: [RadiusSet; 2] = [RadiusSet::Mdsurf, RadiusSet::Ses];

    /// Lower-case name as used in state files.
    pub fn name(self) -> &'static str {
        match self {
            RadiusSet::Mdsurf => "mdsurf",
            RadiusSet::Ses => "ses",
        }
    }

    /// The radii (element, Å) this set changes from the element table.
    pub fn radii(self) -> &'static [(&'static str, f32)] {
        match self {
            RadiusSet::Mdsurf => &[],
            RadiusSet::Ses => &SES_RADII,
        }
    }

    /// How this set's radii follow exposure, frame by frame ([`crate::model::exposure`]), or
    /// `None` when its radii are constant.
    pub fn exposure(self) -> Option<ExposureModel> {
        match self {
            RadiusSet::Mdsurf => None,
            RadiusSet::Ses => Some(SES_EXPOSURE),
        }
    }

    /// `options` with this set's radii under its own user overrides and this set's exposure
    /// exposure model: how a representation's radius set reaches its particles.
    pub fn particle_options(self, options: ParticleOptions) -> ParticleOptions {
        ParticleOptions {
            radius_overrides: self.with_overrides(&options.radius_overrides),
            exposure: self.exposure(),
            ..options
        }
    }

    /// `user` overrides on top of this set's radii (a user's override of the same element or
    /// name wins, being later in the list).
    pub fn with_overrides(self, user: &RadiusOverrides) -> RadiusOverrides {
        let own = self.radii().iter().map(|&(key, radius)| RadiusOverride {
            key: key.to_string(),
            radius,
        });
        RadiusOverrides(own.chain(user.0.iter().cloned()).collect())
    }
}

super::params::display_and_parse_by_name!(RadiusSet, "radius set", "mdsurf or ses");

super::params::display_and_parse_by_name!(Preset, "preset", "ses");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_bad_ones_say_what_is_expected() {
        for r in RadiusSet::ALL {
            assert_eq!(r.name().parse::<RadiusSet>(), Ok(r));
        }
        let e = "bondi".parse::<RadiusSet>().expect_err("unknown");
        assert!(e.contains("bondi") && e.contains("mdsurf or ses"), "{e}");
        assert_eq!(RadiusSet::default(), RadiusSet::Mdsurf);
        assert_eq!(Preset::Ses.radius_set(), RadiusSet::Ses);
    }

    #[test]
    fn user_overrides_beat_the_set_and_the_rest_keeps_the_table() {
        let user = RadiusOverrides::parse_all(&["N=1.5", "CA=2.0"]).expect("valid");
        let all = RadiusSet::Ses.with_overrides(&user);
        assert_eq!(all.radius_for("NZ", "N"), Some(1.5));
        assert_eq!(all.radius_for("N", "N"), Some(1.5));
        assert_eq!(all.radius_for("OG", "O"), Some(1.413));
        assert_eq!(all.radius_for("HA", "H"), Some(1.020));
        assert_eq!(all.radius_for("CA", "C"), Some(2.0));
        assert_eq!(all.radius_for("CB", "C"), None);
        let none = RadiusSet::Mdsurf.with_overrides(&user);
        assert_eq!(none, user);
    }

    #[test]
    fn the_ses_preset_notes_a_spacing_coarser_than_it_holds_at() {
        let (finest, coarsest) = Preset::Ses.spacing_range();
        assert!(finest < coarsest);
        assert_eq!(Preset::Ses.spacing_note(coarsest), None);
        assert_eq!(Preset::Ses.spacing_note(0.25), None);
        let note = Preset::Ses.spacing_note(2.0).expect("2 Å is too coarse");
        assert!(note.contains("ses") && note.contains("H = 2 Å"), "{note}");
        assert!(note.contains("--spacing 1"), "{note}");
        assert!(!note.contains("  "), "{note}");
    }
}
