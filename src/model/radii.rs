//! User overrides of particle radii (`--radius C=1.7 --radius 2=1.2 --radius OW=1.4`), applied on
//! top of the radii the topology got from the file or the element table.

use std::str::FromStr;

use super::{ModelError, Topology};

/// Largest radius in Å an override may set (anything larger is a typo, not a particle).
const MAX_RADIUS: f32 = 50.0;

/// One override: every particle whose name (or type) or element equals `key` gets `radius`.
#[derive(Debug, Clone, PartialEq)]
pub struct RadiusOverride {
    /// Atom name, particle type (`2` for a LAMMPS type) or element symbol (`C`, `Fe`); case
    /// sensitive.
    pub key: String,
    /// Radius in Å.
    pub radius: f32,
}

impl FromStr for RadiusOverride {
    type Err = ModelError;

    /// Parses `KEY=RADIUS`, with RADIUS a positive number of Å up to 50.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |why: &str| ModelError::Parse(format!("bad radius override '{s}': {why}"));
        let (key, value) = s
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=RADIUS, e.g. C=1.7"))?;
        let key = key.trim();
        if key.is_empty() {
            return Err(bad("the element, name or type before '=' is empty"));
        }
        let radius: f32 = value
            .trim()
            .parse()
            .map_err(|_| bad("the radius is not a number"))?;
        if !(radius > 0.0 && radius <= MAX_RADIUS) {
            return Err(bad(
                "the radius must be a number of Å above 0 and at most 50",
            ));
        }
        Ok(RadiusOverride {
            key: key.to_string(),
            radius,
        })
    }
}

/// A list of overrides. A name/type match wins over an element match; among equals the last
/// one given wins.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RadiusOverrides(pub Vec<RadiusOverride>);

impl RadiusOverrides {
    /// Parses each string as a [`RadiusOverride`].
    pub fn parse_all<S: AsRef<str>>(items: &[S]) -> Result<Self, ModelError> {
        items
            .iter()
            .map(|s| s.as_ref().parse())
            .collect::<Result<Vec<_>, _>>()
            .map(Self)
    }

    /// True when there are no overrides.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The overridden radius in Å of a particle with this name and element, if any.
    pub fn radius_for(&self, name: &str, element: &str) -> Option<f32> {
        let by_name = self.0.iter().rev().find(|o| o.key == name);
        let by_element = || {
            self.0
                .iter()
                .rev()
                .find(|o| !element.is_empty() && o.key == element)
        };
        by_name.or_else(by_element).map(|o| o.radius)
    }

    /// The topology's radii (Å) with the overrides applied.
    pub fn apply(&self, topology: &Topology) -> Vec<f32> {
        let n = topology.len();
        if self.0.is_empty() && topology.radii.len() >= n {
            return topology.radii[..n].to_vec(); // nothing to override
        }
        (0..n)
            .map(|i| {
                let element = topology.elements.get(i).unwrap_or("");
                self.radius_for(&topology.names[i], element).unwrap_or(
                    topology
                        .radii
                        .get(i)
                        .copied()
                        .unwrap_or(super::elements::DEFAULT_RADIUS),
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        let o: RadiusOverride = "C=1.7".parse().expect("valid");
        assert_eq!(
            o,
            RadiusOverride {
                key: "C".into(),
                radius: 1.7
            }
        );
        for bad in [
            "C", "=1.0", "C=abc", "C=-1", "C=0", "C=NaN", "C=inf", "C=1000",
        ] {
            let e = bad.parse::<RadiusOverride>().expect_err(bad);
            assert!(e.to_string().contains(bad), "{e}");
        }
    }

    #[test]
    fn name_beats_element_and_last_wins() {
        let o = RadiusOverrides::parse_all(&["C=1.7", "CA=2.0", "C=1.8"]).expect("valid");
        assert_eq!(o.radius_for("CA", "C"), Some(2.0));
        assert_eq!(o.radius_for("CB", "C"), Some(1.8));
        assert_eq!(o.radius_for("N", "N"), None);
    }
}
