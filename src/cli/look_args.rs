//! The look flags of `mdsurf render` (`--look`, `--outline`, `--outline-colour`, `--shadows`,
//! `--transparent`) and how they change [`RenderSettings`].

use mdsurf::render::RenderSettings;
use mdsurf::render::settings::{
    check_outline_width, check_samples, check_shadows, parse_linear_rgb,
};

use super::arg_error::ArgError;
use super::render_args::parse_f32;

/// A preset look.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LookPreset {
    /// The window's look: ambient occlusion and depth cue, no outlines or shadows.
    #[default]
    Default,
    /// For figures: adds 2 px black outlines and shadows of strength 0.5 from the key light.
    Figure,
    /// The figure look drawn with 32 progressive samples per picture (smooth occlusion and
    /// shadows, anti-aliased edges; 32 times the drawing time).
    High,
}

/// Outline, shadow and background-alpha flags.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LookArgs {
    /// Preset look: default (as the window), figure (outlines and shadows added) or high (the
    /// figure look with 32 progressive samples); the other look flags change the preset.
    #[arg(
        id = "look_preset",
        long = "look",
        value_enum,
        value_name = "PRESET",
        default_value = "default"
    )]
    pub preset: LookPreset,
    /// Silhouette outline width in pixels (0: off).
    #[arg(long = "outline", value_name = "PX", value_parser = parse_outline)]
    pub outline: Option<f32>,
    /// Outline colour: black (default), white, grey, #rrggbb or linear r,g,b (0..1 each).
    #[arg(long = "outline-colour", visible_alias = "outline-color", value_name = "COLOUR",
          value_parser = parse_linear_rgb)]
    pub outline_colour: Option<[f32; 3]>,
    /// Shadow strength 0..1 from the key light (0: off).
    #[arg(long = "shadows", value_name = "S", value_parser = parse_shadows)]
    pub shadows: Option<f32>,
    /// Transparent background: background pixels of the PNG get alpha 0.
    #[arg(long = "transparent")]
    pub transparent: bool,
    /// Progressive samples per picture, 1 to 256 (each turns the occlusion and shadow patterns
    /// and moves the camera by a sub-pixel offset; the draws are averaged).
    #[arg(long = "samples", value_name = "N", value_parser = parse_samples)]
    pub samples: Option<u32>,
}

fn parse_samples(s: &str) -> Result<u32, ArgError> {
    let n: u32 = s.trim().parse().map_err(|_| ArgError::Number {
        what: "sample count",
        text: s.to_string(),
    })?;
    Ok(check_samples(n)?)
}

fn parse_outline(s: &str) -> Result<f32, ArgError> {
    Ok(check_outline_width(parse_f32(s, "outline width")?)?)
}

fn parse_shadows(s: &str) -> Result<f32, ArgError> {
    Ok(check_shadows(parse_f32(s, "shadow strength")?)?)
}

impl LookArgs {
    /// Applies the preset, then the single flags given, to `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) {
        match self.preset {
            LookPreset::Default => {}
            LookPreset::Figure => settings.figure(),
            LookPreset::High => settings.high(),
        }
        if let Some(px) = self.outline {
            settings.outline_width = px;
        }
        if let Some(c) = self.outline_colour {
            settings.outline_colour = c;
        }
        if let Some(s) = self.shadows {
            settings.shadows = s;
        }
        if self.transparent {
            settings.transparent_background = true;
        }
        if let Some(n) = self.samples {
            settings.samples = n;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        look: LookArgs,
    }

    fn settings(args: &[&str]) -> Result<RenderSettings, clap::Error> {
        let cli = Cli::try_parse_from(std::iter::once("x").chain(args.iter().copied()))?;
        let mut s = RenderSettings::default();
        cli.look.apply(&mut s);
        Ok(s)
    }

    #[test]
    fn presets_and_flags() {
        assert_eq!(settings(&[]).unwrap(), RenderSettings::default());
        let fig = settings(&["--look", "figure"]).unwrap();
        assert!(fig.outline_width > 0.0 && fig.shadows > 0.0);
        let s = settings(&["--look", "figure", "--outline", "0", "--shadows", "0.2"]).unwrap();
        assert_eq!((s.outline_width, s.shadows), (0.0, 0.2));
        let s = settings(&["--outline-colour", "white", "--transparent"]).unwrap();
        assert_eq!(s.outline_colour, [1.0; 3]);
        assert!(s.transparent_background);
        assert!(settings(&["--shadows", "2"]).is_err());
        assert!(settings(&["--outline", "-1"]).is_err());
        assert!(settings(&["--outline-colour", "#12345"]).is_err());
    }
}
