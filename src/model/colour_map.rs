//! Colour maps for numbers (per-atom data, B-factors): `viridis` (perceptually uniform, for
//! values of one sign) and `bwr` (blue-white-red, diverging, for signed data such as charges),
//! from the `colorous` crate (matplotlib's viridis and ColorBrewer's RdBu, reversed, as tables
//! it interpolates), returned as linear RGB in 0..1 like every per-atom colour. Also the default
//! range of each map and the neutral grey of atoms without a value.

use std::fmt;
use std::str::FromStr;

use super::colour::srgb_to_linear;

/// A named colour map from a number in a range to a colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum ColourMap {
    /// Dark blue through green to yellow (low to high).
    #[default]
    Viridis,
    /// Blue (low) through white (middle) to red (high).
    BlueWhiteRed,
}

/// Linear RGB of atoms that have no value (sRGB 128, 128, 128).
pub const NO_VALUE_GREY: [f32; 3] = [0.215_860_53; 3];

impl ColourMap {
    /// Every map, in menu order.
    pub const ALL: [ColourMap; 2] = [ColourMap::Viridis, ColourMap::BlueWhiteRed];

    /// Short name (`viridis`, `bwr`).
    pub fn name(self) -> &'static str {
        match self {
            ColourMap::Viridis => "viridis",
            ColourMap::BlueWhiteRed => "bwr",
        }
    }

    /// The sRGB colour (bytes) at `t` in 0..1 (clamped; NaN gives the low end).
    pub fn srgb8(self, t: f32) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } as f64;
        let c = match self {
            ColourMap::Viridis => colorous::VIRIDIS.eval_continuous(t),
            // RdBu runs red to blue: reversed, low values are blue.
            ColourMap::BlueWhiteRed => colorous::RED_BLUE.eval_continuous(1.0 - t),
        };
        [c.r, c.g, c.b]
    }

    /// The linear RGB colour at `t` in 0..1.
    pub fn linear(self, t: f32) -> [f32; 3] {
        self.srgb8(t).map(|v| srgb_to_linear(f32::from(v) / 255.0))
    }

    /// The linear RGB colour of `value` over `range` = [low, high]; grey for a non-finite value.
    pub fn colour(self, value: f32, range: [f32; 2]) -> [f32; 3] {
        if !value.is_finite() {
            return NO_VALUE_GREY;
        }
        let span = range[1] - range[0];
        let t = if span > 0.0 {
            (value - range[0]) / span
        } else {
            0.5
        };
        self.linear(t)
    }

    /// The range used when none is given, from the finite values' minimum and maximum:
    /// viridis spans them, bwr is centred on zero (±the largest magnitude) so that white is 0.
    pub fn default_range(self, min: f32, max: f32) -> [f32; 2] {
        if !(min.is_finite() && max.is_finite()) {
            return [0.0, 1.0];
        }
        match self {
            ColourMap::Viridis => [min, max],
            ColourMap::BlueWhiteRed => {
                let m = min.abs().max(max.abs());
                if m > 0.0 { [-m, m] } else { [-1.0, 1.0] }
            }
        }
    }
}

impl fmt::Display for ColourMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ColourMap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "viridis" => Ok(ColourMap::Viridis),
            "bwr" | "blue-white-red" | "diverging" => Ok(ColourMap::BlueWhiteRed),
            _ => Err(format!(
                "bad colour map '{s}': use viridis or bwr (blue-white-red)"
            )),
        }
    }
}

/// A colour range that cannot be used (the text as given).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// Not two numbers separated by a colon.
    #[error("bad colour range '{0}': expected LOW:HIGH, e.g. -1:1 or 0:80")]
    Syntax(String),
    /// Two numbers, but not finite or not increasing.
    #[error("bad colour range '{0}': LOW and HIGH must be finite with LOW < HIGH")]
    Order(String),
}

/// Parses a range `LOW:HIGH` (numbers, LOW < HIGH).
pub fn parse_range(s: &str) -> Result<[f32; 2], RangeError> {
    let bad = || RangeError::Syntax(s.to_string());
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let lo: f32 = a.trim().parse().map_err(|_| bad())?;
    let hi: f32 = b.trim().parse().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(RangeError::Order(s.to_string()));
    }
    Ok([lo, hi])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_have_the_expected_ends_and_middle() {
        // viridis: dark purple-blue to yellow.
        let [r, g, b] = ColourMap::Viridis.srgb8(0.0);
        assert!(r < 80 && g < 10 && b > 70, "{r} {g} {b}");
        let [r, g, b] = ColourMap::Viridis.srgb8(1.0);
        assert!(r > 240 && g > 220 && b < 50, "{r} {g} {b}");
        // bwr: blue, near-white, red.
        let [r, _, b] = ColourMap::BlueWhiteRed.srgb8(0.0);
        assert!(b > 90 && r < 20, "{r} {b}");
        let mid = ColourMap::BlueWhiteRed.srgb8(0.5);
        assert!(mid.iter().all(|&c| c > 225), "{mid:?}");
        let [r, _, b] = ColourMap::BlueWhiteRed.srgb8(1.0);
        assert!(r > 90 && b < 40, "{r} {b}");
        assert_eq!(
            ColourMap::Viridis.colour(f32::NAN, [0.0, 1.0]),
            NO_VALUE_GREY
        );
        assert_eq!(
            ColourMap::BlueWhiteRed.default_range(-0.3, 0.8),
            [-0.8, 0.8]
        );
        assert_eq!(ColourMap::Viridis.default_range(2.0, 5.0), [2.0, 5.0]);
        assert_eq!("BWR".parse(), Ok(ColourMap::BlueWhiteRed));
        assert_eq!(parse_range("-1:2"), Ok([-1.0, 2.0]));
        assert!(parse_range("2:1").is_err() && parse_range("x").is_err());
    }
}
