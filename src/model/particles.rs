//! The glue between a topology and a surface engine: which particles (atoms or residue beads)
//! enter the surface, with which radii (Å) and colours, and where they are in a given frame.
//! Both the command line and the viewer build their `AtomSet`s through this.

use glam::Vec3;

use super::beads::check_count;
use super::exposure::ExposureModel;
use super::{BeadModel, ColorScheme, Frame, ModelError, RadiusOverrides, Topology};
use crate::surface::AtomSet;

/// How particles are derived from atoms.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParticleOptions {
    /// One bead per residue instead of one particle per atom.
    pub beads: bool,
    /// User radius overrides (applied to atoms; beads size themselves from their atoms).
    pub radius_overrides: RadiusOverrides,
    /// Colour scheme per atom (beads take the mean colour of their atoms).
    pub colours: ColorScheme,
    /// Radii that follow exposure frame by frame ([`super::exposure`]; the SES preset's
    /// radii). Not for beads.
    pub exposure: Option<ExposureModel>,
}

/// Per-particle radii and colours, constant over the trajectory, plus the per-frame positions.
#[derive(Debug, Clone)]
pub struct Particles {
    atom_count: usize,
    /// The atoms the particles come from (sorted 0-based indices), when not all of them.
    subset: Option<Vec<u32>>,
    beads: Option<BeadModel>,
    radii: Vec<f32>,
    colours: Vec<[f32; 3]>,
    /// Which particles are heavy atoms and how their radii follow exposure, when they do
    /// ([`ParticleOptions::exposure`]).
    exposure: Option<(Vec<bool>, ExposureModel)>,
}

impl Particles {
    /// Builds particles from `topology`; `first` sizes the beads (see [`BeadModel`]) and must
    /// have the topology's atom count.
    pub fn new(
        topology: &Topology,
        first: &Frame,
        options: &ParticleOptions,
    ) -> Result<Self, ModelError> {
        Self::new_subset(topology, first, options, None)
    }

    /// Like [`Particles::new`] for the atoms `subset` only (sorted 0-based atom indices, as a
    /// selection gives them; `None`: every atom). Beads are then one per residue with a
    /// selected atom, made of its selected atoms.
    pub fn new_subset(
        topology: &Topology,
        first: &Frame,
        options: &ParticleOptions,
        subset: Option<&[u32]>,
    ) -> Result<Self, ModelError> {
        check_count(first, topology.len())?;
        let atom_colours = options.colours.atom_colours_at(topology, first.index);
        let (beads, radii, colours) = if options.beads {
            let model = BeadModel::new_subset(topology, first, subset)?;
            let colours = model.colours(&atom_colours);
            (Some(model.clone()), model.radii().to_vec(), colours)
        } else {
            let radii = options.radius_overrides.apply(topology);
            match subset {
                Some(s) => (None, gather(&radii, s), gather(&atom_colours, s)),
                None => (None, radii, atom_colours),
            }
        };
        let exposure = match (options.exposure, &beads) {
            (Some(model), None) => {
                let is_heavy = |i: usize| !topology.elements[i].eq_ignore_ascii_case("H");
                let heavy = match subset {
                    Some(s) => s.iter().map(|&i| is_heavy(i as usize)).collect(),
                    None => (0..topology.len()).map(is_heavy).collect(),
                };
                Some((heavy, model))
            }
            _ => None,
        };
        Ok(Particles {
            atom_count: topology.len(),
            subset: subset.map(<[u32]>::to_vec),
            beads,
            radii,
            colours,
            exposure,
        })
    }

    /// Number of particles (atoms, or beads).
    pub fn len(&self) -> usize {
        self.radii.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// True when particles are residue beads.
    pub fn is_beads(&self) -> bool {
        self.beads.is_some()
    }

    /// The bead model, when particles are beads.
    pub fn bead_model(&self) -> Option<&BeadModel> {
        self.beads.as_ref()
    }

    /// Radius of each particle in Å.
    pub fn radii(&self) -> &[f32] {
        &self.radii
    }

    /// Linear RGB colour of each particle.
    pub fn colours(&self) -> &[[f32; 3]] {
        &self.colours
    }

    /// The atoms the particles come from (sorted 0-based indices), or `None` for all atoms.
    pub fn subset(&self) -> Option<&[u32]> {
        self.subset.as_deref()
    }

    /// Recolours the particles with another scheme (radii and positions are unaffected).
    pub fn set_colours(&mut self, topology: &Topology, scheme: ColorScheme) {
        let atom_colours = scheme.atom_colours(topology);
        self.colours = match (&self.beads, &self.subset) {
            (Some(model), _) => model.colours(&atom_colours),
            (None, Some(s)) => gather(&atom_colours, s),
            (None, None) => atom_colours,
        };
    }

    /// `bonds` (pairs of atom indices) between two atoms that are both particles, renumbered to
    /// particle indices; nothing for beads.
    pub fn bonds_within(&self, bonds: &[[u32; 2]]) -> Vec<[u32; 2]> {
        if self.beads.is_some() {
            return Vec::new();
        }
        let Some(subset) = &self.subset else {
            return bonds.to_vec();
        };
        let local = |a: u32| subset.binary_search(&a).ok().map(|i| i as u32);
        bonds
            .iter()
            .filter_map(|&[a, b]| Some([local(a)?, local(b)?]))
            .collect()
    }

    /// Particle positions in Å for `frame`, written into `out` (cleared first).
    pub fn positions_into(&self, frame: &Frame, out: &mut Vec<Vec3>) -> Result<(), ModelError> {
        check_count(frame, self.atom_count)?;
        match &self.beads {
            Some(model) => model.centres_into(frame, out)?,
            None => {
                out.clear();
                match &self.subset {
                    Some(s) => out.extend(s.iter().map(|&i| frame.positions[i as usize])),
                    None => out.extend_from_slice(&frame.positions),
                }
            }
        }
        Ok(())
    }

    /// Particle positions in Å for `frame`.
    pub fn positions(&self, frame: &Frame) -> Result<Vec<Vec3>, ModelError> {
        let mut out = Vec::with_capacity(self.len());
        self.positions_into(frame, &mut out)?;
        Ok(out)
    }

    /// The radii (Å) at `positions` (from [`Particles::positions`]) when they follow exposure
    /// ([`super::exposure`]), `None` when they are [`Particles::radii`] in every frame.
    pub fn frame_radii(&self, positions: &[Vec3]) -> Option<Vec<f32>> {
        let (heavy, model) = self.exposure.as_ref()?;
        Some(model.apply(&self.radii, positions, heavy))
    }

    /// How the radii follow exposure, when they do: the model and which particles are heavy
    /// atoms (the GPU engine computes [`Particles::frame_radii`] itself from these,
    /// [`crate::gpu::exposure`]).
    pub fn exposure(&self) -> Option<(ExposureModel, &[bool])> {
        self.exposure
            .as_ref()
            .map(|(heavy, model)| (*model, heavy.as_slice()))
    }

    /// The engine input for `positions` (from [`Particles::positions`]), with colours and the
    /// constant radii ([`Particles::frame_radii`] gives those of a frame when they follow
    /// exposure; [`crate::scene::layer::LayerFrame::atom_set`] uses them).
    pub fn atom_set<'a>(&'a self, positions: &'a [Vec3]) -> AtomSet<'a> {
        AtomSet {
            positions,
            radii: &self.radii,
            colours: Some(&self.colours),
        }
    }
}

/// `values` at `indices` (each index must be in range).
fn gather<T: Copy>(values: &[T], indices: &[u32]) -> Vec<T> {
    indices.iter().map(|&i| values[i as usize]).collect()
}
