//! Per-atom colour schemes (element, chain, residue type, residue index, B-factor or any number,
//! single colour, the user's data through a colour map, each residue's solvent exposure on the
//! surface). Colours are linear RGB in 0..1, as the
//! colour volume and renderer expect.

use std::fmt;
use std::str::FromStr;

use std::path::Path;
use std::sync::Arc;

use super::colour_data::{self, DataId, DataTable};
use super::colour_map::{ColourMap, NO_VALUE_GREY, parse_range};
use super::residues::{ResidueClass, residue_class};
use super::{Labels, ModelError, Topology};

/// How atoms are coloured. `FromStr` accepts `element`, `chain`, `residue-type`,
/// `residue-index` (alias `rainbow`), `b-factor`, `single:#rrggbb` (or just `#rrggbb`), and
/// `data:FILE[;map=viridis|bwr][;range=LOW:HIGH]` (which reads FILE: see [`colour_data`]) and
/// `exposure[;map=viridis|bwr]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum ColorScheme {
    /// CPK-like colours by element; particles without an element get a colour per name.
    #[default]
    Element,
    /// One colour per chain or segment, in order of appearance.
    Chain,
    /// Hydrophobic white, polar green, acid red, base blue, anything else tan.
    ResidueType,
    /// A blue-to-red rainbow along the residue index.
    ResidueIndex,
    /// Blue (low) through white to red (high) over the B-factor range.
    BFactor,
    /// The same linear RGB colour for every atom.
    Single([f32; 3]),
    /// The user's numbers per atom (or per frame and atom) through a colour map.
    Data(DataColours),
    /// Each residue's exposure on its representation's surface in this frame (its area over the
    /// largest area a residue of its name has alone, `crate::measure::ExposureTable`) through a
    /// colour map over 0 (buried) to 1 (as exposed as alone). The exposure needs the surface:
    /// the scene engine computes it after each surface and colours the surface again
    /// (`crate::scene::exposure`); until then, and for atom styles, atoms are
    /// [`super::colour_map::NO_VALUE_GREY`].
    Exposure(ColourMap),
}

/// Colouring by a loaded [`colour_data::DataTable`]: which table, the map, and the value range
/// (`None`: the map's default over the table's values, see [`ColourMap::default_range`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataColours {
    /// The table in the registry.
    pub id: DataId,
    /// The colour map.
    pub map: ColourMap,
    /// Values mapped to the map's ends (same unit as the data).
    pub range: Option<[f32; 2]>,
}

impl DataColours {
    /// Loads `path` (errors name the file and line) and colours by it with `map`.
    pub fn load(path: &Path, map: ColourMap) -> Result<DataColours, ModelError> {
        let table = colour_data::load(path).map_err(|e| ModelError::Parse(e.0))?;
        Ok(DataColours {
            id: colour_data::register(table),
            map,
            range: None,
        })
    }

    /// The table (`None` only for an id of no table).
    pub fn table(&self) -> Option<Arc<DataTable>> {
        colour_data::get(self.id)
    }

    /// The range in use: the given one, else the map's default over the values.
    pub fn effective_range(&self) -> [f32; 2] {
        match (self.range, self.table()) {
            (Some(r), _) => r,
            (None, Some(t)) => self.map.default_range(t.min_max[0], t.min_max[1]),
            (None, None) => [0.0, 1.0],
        }
    }

    /// Colours of `atoms` atoms in trajectory frame `frame`: grey where there is no value.
    pub fn colours(&self, atoms: usize, frame: usize) -> Vec<[f32; 3]> {
        let table = self.table();
        let values = table.as_ref().and_then(|t| t.values(frame)).unwrap_or(&[]);
        let range = self.effective_range();
        (0..atoms)
            .map(|i| {
                self.map
                    .colour(values.get(i).copied().unwrap_or(f32::NAN), range)
            })
            .collect()
    }
}

impl FromStr for ColorScheme {
    type Err = ModelError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        Ok(match lower.as_str() {
            "element" => ColorScheme::Element,
            "chain" | "segment" => ColorScheme::Chain,
            "residue-type" | "restype" | "residue_type" => ColorScheme::ResidueType,
            "residue-index" | "residue_index" | "rainbow" => ColorScheme::ResidueIndex,
            "b-factor" | "bfactor" | "b_factor" => ColorScheme::BFactor,
            _ if lower.starts_with("data:") => return parse_data(s.trim()),
            _ if lower == "exposure" || lower.starts_with("exposure;") => {
                return parse_exposure(s.trim());
            }
            _ => {
                let hex = lower.strip_prefix("single:").unwrap_or(&lower);
                ColorScheme::Single(parse_hex(hex).ok_or_else(|| {
                    ModelError::Parse(format!(
                        "bad colour scheme '{s}': use element, chain, residue-type, residue-index, b-factor, exposure, single:#rrggbb or data:FILE.csv"
                    ))
                })?)
            }
        })
    }
}

impl fmt::Display for ColorScheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ColorScheme::Element => write!(f, "element"),
            ColorScheme::Chain => write!(f, "chain"),
            ColorScheme::ResidueType => write!(f, "residue-type"),
            ColorScheme::ResidueIndex => write!(f, "residue-index"),
            ColorScheme::BFactor => write!(f, "b-factor"),
            ColorScheme::Single(c) => {
                let [r, g, b] = c.map(|v| (linear_to_srgb(v) * 255.0).round() as u8);
                write!(f, "single:#{r:02x}{g:02x}{b:02x}")
            }
            ColorScheme::Data(d) => {
                let path = d.table().map(|t| t.path.display().to_string());
                write!(f, "data:{}", path.unwrap_or_default())?;
                if d.map != ColourMap::default() {
                    write!(f, ";map={}", d.map)?;
                }
                if let Some([lo, hi]) = d.range {
                    write!(f, ";range={lo}:{hi}")?;
                }
                Ok(())
            }
            ColorScheme::Exposure(map) if *map == ColourMap::default() => write!(f, "exposure"),
            ColorScheme::Exposure(map) => write!(f, "exposure;map={map}"),
        }
    }
}

impl ColorScheme {
    /// True when colours change from frame to frame (per-frame data).
    pub fn is_per_frame(&self) -> bool {
        match self {
            ColorScheme::Data(d) => d.table().is_some_and(|t| t.per_frame),
            _ => false,
        }
    }

    /// True when the colours come from the surface (exposure): the scene engine computes them
    /// after each surface.
    pub fn needs_surface(&self) -> bool {
        matches!(self, ColorScheme::Exposure(_))
    }

    /// The colour map and value range a colour bar shows for this scheme: data colours over
    /// their range, exposure over 0 to 1; `None` for the other schemes.
    pub fn colour_bar(&self) -> Option<(ColourMap, [f32; 2])> {
        match self {
            ColorScheme::Data(d) => Some((d.map, d.effective_range())),
            ColorScheme::Exposure(map) => Some((*map, [0.0, 1.0])),
            _ => None,
        }
    }

    /// The data colouring, if this is one.
    pub fn data(&self) -> Option<&DataColours> {
        match self {
            ColorScheme::Data(d) => Some(d),
            _ => None,
        }
    }

    /// The linear RGB colour of every atom of `topology` in trajectory frame `frame` (only
    /// per-frame data depends on it).
    pub fn atom_colours_at(&self, topology: &Topology, frame: usize) -> Vec<[f32; 3]> {
        match self {
            ColorScheme::Data(d) => d.colours(topology.len(), frame),
            _ => self.atom_colours(topology),
        }
    }

    /// The linear RGB colour of every atom of `topology` (frame 0 for per-frame data).
    pub fn atom_colours(&self, topology: &Topology) -> Vec<[f32; 3]> {
        let n = topology.len();
        match self {
            ColorScheme::Element => element_colours(topology),
            ColorScheme::Chain => chain_colours(&topology.chains),
            ColorScheme::ResidueType => {
                // Once per distinct residue name; atoms past the names have the empty one.
                let (names, ids) = topology.residue_names.distinct();
                let colour_of: Vec<[f32; 3]> = names
                    .iter()
                    .map(|r| residue_type_colour(residue_class(r)))
                    .collect();
                (0..n)
                    .map(|i| match ids.get(i) {
                        Some(&id) => colour_of[id as usize],
                        None => residue_type_colour(residue_class("")),
                    })
                    .collect()
            }
            ColorScheme::ResidueIndex => {
                let last = topology.residue_count().saturating_sub(1).max(1) as f32;
                let t = |i: usize| {
                    topology
                        .residue_index
                        .get(i)
                        .map_or(0.0, |&r| r as f32 / last)
                };
                (0..n).map(|i| rainbow(t(i))).collect()
            }
            ColorScheme::BFactor => colours_from_values(&topology.b_factors),
            ColorScheme::Single(c) => vec![*c; n],
            ColorScheme::Data(d) => d.colours(n, 0),
            ColorScheme::Exposure(_) => vec![NO_VALUE_GREY; n],
        }
    }
}

/// Maps per-atom numbers to blue (minimum) - white - red (maximum); all white if they are all
/// equal; non-finite values are grey.
pub fn colours_from_values(values: &[f32]) -> Vec<[f32; 3]> {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let span = hi - lo;
    values
        .iter()
        .map(|&v| {
            if !v.is_finite() {
                return [0.2; 3];
            }
            let t = if span > 0.0 { (v - lo) / span } else { 0.5 };
            if t < 0.5 {
                let s = t * 2.0;
                [s, s, 1.0]
            } else {
                let s = (1.0 - t) * 2.0;
                [1.0, s, s]
            }
        })
        .collect()
}

/// Parses `data:FILE[;map=NAME][;range=LOW:HIGH]`, reading FILE.
fn parse_data(s: &str) -> Result<ColorScheme, ModelError> {
    let rest = &s["data:".len()..];
    let mut parts = rest.split(';');
    let path = parts.next().unwrap_or("").trim();
    if path.is_empty() {
        return Err(ModelError::Parse(format!(
            "bad colour scheme '{s}': expected data:FILE.csv"
        )));
    }
    let (mut map, mut range) = (ColourMap::default(), None);
    for part in parts {
        match part.split_once('=') {
            Some(("map", v)) => map = v.parse().map_err(ModelError::Parse)?,
            Some(("range", v)) => {
                range = Some(parse_range(v).map_err(|e| ModelError::Parse(e.to_string()))?)
            }
            _ => {
                return Err(ModelError::Parse(format!(
                    "bad colour scheme '{s}': after the file name, expected ;map=viridis|bwr or ;range=LOW:HIGH"
                )));
            }
        }
    }
    let mut data = DataColours::load(Path::new(path), map)?;
    data.range = range;
    Ok(ColorScheme::Data(data))
}

/// Parses `exposure[;map=NAME]`.
fn parse_exposure(s: &str) -> Result<ColorScheme, ModelError> {
    let mut map = ColourMap::default();
    for part in s.split(';').skip(1) {
        match part.split_once('=') {
            Some(("map", v)) => map = v.parse().map_err(ModelError::Parse)?,
            _ => {
                return Err(ModelError::Parse(format!(
                    "bad colour scheme '{s}': after exposure, expected ;map=viridis|bwr"
                )));
            }
        }
    }
    Ok(ColorScheme::Exposure(map))
}

/// Converts one sRGB channel (0..1) to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Converts one linear channel (0..1) to sRGB.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Parses `#rrggbb` (or `rrggbb`) as sRGB into linear RGB.
fn parse_hex(hex: &str) -> Option<[f32; 3]> {
    let h = hex.strip_prefix('#').unwrap_or(hex);
    if h.len() != 6 || !h.is_ascii() {
        return None;
    }
    let channel = |k: usize| u8::from_str_radix(&h[k..k + 2], 16).ok();
    Some([channel(0)?, channel(2)?, channel(4)?].map(|v| srgb_to_linear(f32::from(v) / 255.0)))
}

/// An sRGB byte triple as linear RGB.
fn rgb(r: u8, g: u8, b: u8) -> [f32; 3] {
    [r, g, b].map(|v| srgb_to_linear(f32::from(v) / 255.0))
}

/// Distinct colours for chains and unnamed particle types.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

fn palette(k: usize) -> [f32; 3] {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    rgb(r, g, b)
}

/// CPK-like element colour; particles without element get a palette colour from their name.
/// [`element_colour`] of every atom, worked out once per distinct element (and, for atoms
/// without one, per distinct name).
fn element_colours(topology: &Topology) -> Vec<[f32; 3]> {
    let (elements, element_ids) = topology.elements.distinct();
    let (names, name_ids) = topology.names.distinct();
    let by_element: Vec<Option<[f32; 3]>> = elements
        .iter()
        .map(|e| (!e.is_empty()).then(|| element_colour(e, "")))
        .collect();
    let mut by_name: Vec<Option<[f32; 3]>> = vec![None; names.len()];
    (0..topology.len())
        .map(|i| {
            by_element[element_ids[i] as usize].unwrap_or_else(|| {
                let name = name_ids[i] as usize;
                *by_name[name].get_or_insert_with(|| element_colour("", &names[name]))
            })
        })
        .collect()
}

fn element_colour(element: &str, name: &str) -> [f32; 3] {
    match element {
        "C" => rgb(144, 144, 144),
        "N" => rgb(48, 80, 248),
        "O" => rgb(255, 13, 13),
        "H" => rgb(240, 240, 240),
        "S" => rgb(255, 200, 50),
        "P" => rgb(255, 128, 0),
        "" => {
            let hash = name.bytes().fold(7usize, |h, b| {
                h.wrapping_mul(31).wrapping_add(usize::from(b))
            });
            palette(hash)
        }
        _ => rgb(220, 120, 220),
    }
}

/// One palette colour per distinct chain id, in order of first appearance.
fn chain_colours(chains: &Labels) -> Vec<[f32; 3]> {
    let mut seen: Vec<&str> = Vec::new();
    chains
        .iter()
        .map(|c| {
            let k = seen.iter().position(|s| *s == c).unwrap_or_else(|| {
                seen.push(c);
                seen.len() - 1
            });
            palette(k)
        })
        .collect()
}

fn residue_type_colour(class: ResidueClass) -> [f32; 3] {
    match class {
        ResidueClass::Hydrophobic => rgb(235, 235, 235),
        ResidueClass::Polar => rgb(60, 180, 75),
        ResidueClass::Acid => rgb(220, 40, 40),
        ResidueClass::Base => rgb(40, 80, 220),
        ResidueClass::Other => rgb(210, 180, 140),
    }
}

/// Hue from blue (t = 0) to red (t = 1), full saturation, as linear RGB.
fn rainbow(t: f32) -> [f32; 3] {
    let h = (1.0 - t.clamp(0.0, 1.0)) * 4.0; // 4 = blue, 0 = red, through cyan, green, yellow
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let srgb = match h as u32 {
        0 => [1.0, x, 0.0],
        1 => [x, 1.0, 0.0],
        2 => [0.0, 1.0, x],
        _ => [0.0, x, 1.0],
    };
    srgb.map(srgb_to_linear)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_round_trip() {
        for s in [
            "element",
            "chain",
            "residue-type",
            "residue-index",
            "b-factor",
            "single:#ff8800",
            "exposure",
            "exposure;map=bwr",
        ] {
            let scheme: ColorScheme = s.parse().expect(s);
            assert_eq!(scheme.to_string(), s);
        }
        let c: ColorScheme = "#ff8800".parse().expect("hex");
        assert_eq!(c, "single:#FF8800".parse().expect("hex"));
        assert!("single:#ff88".parse::<ColorScheme>().is_err());
        let bad = "exposure;range=0:2".parse::<ColorScheme>().unwrap_err();
        assert!(bad.to_string().contains("exposure;range=0:2"), "{bad}");
        assert!(
            "plaid"
                .parse::<ColorScheme>()
                .unwrap_err()
                .to_string()
                .contains("plaid")
        );
    }

    #[test]
    fn rainbow_ends_and_values() {
        assert_eq!(rainbow(0.0), [0.0, 0.0, 1.0]);
        assert_eq!(rainbow(1.0), [1.0, 0.0, 0.0]);
        let c = colours_from_values(&[0.0, 5.0, 10.0, f32::NAN]);
        assert_eq!(c[0], [0.0, 0.0, 1.0]);
        assert_eq!(c[1], [1.0, 1.0, 1.0]);
        assert_eq!(c[2], [1.0, 0.0, 0.0]);
        assert_eq!(c[3], [0.2; 3]);
    }
}
