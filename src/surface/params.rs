//! The user's knobs for a surface: grid spacing H, radius scale R, isovalue I and quality (the
//! Gaussian cutoff). Shared by the CPU and GPU engines and the UI.
use super::SurfaceError;

/// How far each Gaussian reaches, in units of its width alpha.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Quality {
    /// Cutoff 2.0 alpha.
    Low,
    /// Cutoff 2.5 alpha (the default).
    #[default]
    Medium,
    /// Cutoff 3.0 alpha.
    High,
    /// Cutoff 4.0 alpha.
    Max,
}

impl Quality {
    /// All qualities, lowest first.
    pub const ALL: [Quality; 4] = [Quality::Low, Quality::Medium, Quality::High, Quality::Max];

    /// Cutoff distance in units of alpha (dimensionless).
    pub fn cutoff(self) -> f32 {
        match self {
            Quality::Low => 2.0,
            Quality::Medium => 2.5,
            Quality::High => 3.0,
            Quality::Max => 4.0,
        }
    }

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Low => "low",
            Quality::Medium => "medium",
            Quality::High => "high",
            Quality::Max => "max",
        }
    }
}

/// `Display` (the name) and `FromStr` (any case; an unknown name is an error naming it and
/// what was expected) for an enum of named choices with `ALL` and `name(self)`.
macro_rules! display_and_parse_by_name {
    ($type:ty, $what:literal, $expected:literal) => {
        impl std::fmt::Display for $type {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $type {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                <$type>::ALL
                    .into_iter()
                    .find(|v| v.name().eq_ignore_ascii_case(s))
                    .ok_or_else(|| {
                        format!(
                            concat!("unknown ", $what, " '{}' (expected ", $expected, ")"),
                            s
                        )
                    })
            }
        }
    };
}
pub(crate) use display_and_parse_by_name;

display_and_parse_by_name!(Quality, "quality", "low, medium, high or max");

/// Grid spacings H that make sense, in Å: finer than 0.01 Å is a grid no machine holds for a
/// molecule, coarser than 100 Å shows nothing of it.
pub const SPACING_RANGE: (f32, f32) = (0.01, 100.0);
/// Radius scales R that make sense (Gaussian widths from 1 % to 100 times the atom radius).
pub const RADIUS_SCALE_RANGE: (f32, f32) = (0.01, 100.0);
/// Isovalues I that make sense (1 is the peak of one isolated atom; the sum of thousands of
/// overlapping atoms stays far below 1000).
pub const ISOVALUE_RANGE: (f32, f32) = (1e-6, 1000.0);

/// Parameters of one surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceParams {
    /// Grid spacing H in Å.
    pub spacing: f32,
    /// Radius scale R (dimensionless): Gaussian width alpha = r * R.
    pub radius_scale: f32,
    /// Isovalue I of the density (dimensionless; 1.0 is the peak of one isolated atom).
    pub isovalue: f32,
    /// Cutoff of each Gaussian.
    pub quality: Quality,
}

impl Default for SurfaceParams {
    fn default() -> Self {
        SurfaceParams {
            spacing: 1.0,
            radius_scale: 1.0,
            isovalue: 0.5,
            quality: Quality::Medium,
        }
    }
}

impl SurfaceParams {
    /// Checks that H, R and I are finite and positive.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        for (name, value, (min, max)) in [
            ("grid spacing H", self.spacing, SPACING_RANGE),
            ("radius scale R", self.radius_scale, RADIUS_SCALE_RANGE),
            ("isovalue I", self.isovalue, ISOVALUE_RANGE),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(SurfaceError::InvalidParameter {
                    name,
                    value: value.to_string(),
                });
            }
            if !(min..=max).contains(&value) {
                return Err(SurfaceError::OutOfRange {
                    name,
                    // Debug keeps 1e-45 short (Display writes every zero).
                    value: format!("{value:?}"),
                    min,
                    max,
                });
            }
        }
        Ok(())
    }

    /// Cutoff factor q (units of alpha).
    pub fn cutoff(&self) -> f32 {
        self.quality.cutoff()
    }
}
