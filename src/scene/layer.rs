//! A representation bound to a topology: its selection evaluated (static parts once, geometric
//! parts per frame), and the particles (atoms or residue beads of the selected atoms, with radii
//! and colours) that the surface engines and the atom renderer consume. Particles are rebuilt
//! only when the selected atoms change (a `within` selection as atoms move) or the
//! representation's colours or style change.

use std::sync::Arc;

use glam::Vec3;

use crate::model::bonds::guess_bonds;
use crate::model::{Frame, ModelError, Particles, RadiusOverrides, Topology};
use crate::surface::AtomSet;

use super::representation::Representation;
use crate::selection::BoundSelection;

/// Why a layer could not be built or updated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LayerError {
    /// The selection does not parse (the message names the column).
    #[error("representation '{name}': selection '{selection}': {message}")]
    Selection {
        /// Representation name.
        name: String,
        /// The selection text.
        selection: String,
        /// The parser's one-line message.
        message: String,
    },
    /// The frame does not fit the topology.
    #[error("representation '{name}': {source}")]
    Model {
        /// Representation name.
        name: String,
        /// What went wrong.
        source: ModelError,
    },
}

/// The particles of one representation in one frame.
#[derive(Debug, Clone)]
pub struct LayerFrame {
    /// Particles (radii, colours, and which atoms they come from).
    pub particles: Arc<Particles>,
    /// Particle positions in Å.
    pub positions: Vec<Vec3>,
    /// Bonds between particles (file bonds between selected atoms, else guessed; empty for
    /// beads and for surface styles, which draw none).
    pub bonds: Arc<Vec<[u32; 2]>>,
    /// True when the particles were rebuilt for this frame (new atoms, colours or radii).
    pub rebuilt: bool,
    /// This frame's radii in Å when they follow exposure ([`Particles::frame_radii`]), else
    /// `None` (the particles' own).
    pub frame_radii: Option<Vec<f32>>,
}

impl LayerFrame {
    /// Particle radii in Å in this frame.
    pub fn radii(&self) -> &[f32] {
        self.frame_radii
            .as_deref()
            .unwrap_or_else(|| self.particles.radii())
    }

    /// The surface engine's input.
    pub fn atom_set(&self) -> AtomSet<'_> {
        AtomSet {
            radii: self.radii(),
            ..self.particles.atom_set(&self.positions)
        }
    }
}

/// A [`Representation`] bound to a topology.
#[derive(Debug, Clone)]
pub struct Layer {
    rep: Representation,
    selection: BoundSelection,
    radius_overrides: RadiusOverrides,
    /// The particles of the last frame and the atoms they were built from.
    built: Option<Built>,
}

/// Particles built for a set of atoms: (the selected atoms, their particles, their bonds).
type Built = (Vec<u32>, Arc<Particles>, Arc<Vec<[u32; 2]>>);

impl Layer {
    /// Parses `rep`'s selection and binds it to `topology`.
    pub fn new(
        rep: Representation,
        topology: &Topology,
        radius_overrides: &RadiusOverrides,
    ) -> Result<Layer, LayerError> {
        let selection = rep
            .parse_selection()
            .map_err(|e| LayerError::Selection {
                name: rep.name.clone(),
                selection: rep.selection.clone(),
                message: e.to_string(),
            })?
            .bind(topology);
        Ok(Layer {
            rep,
            selection,
            radius_overrides: radius_overrides.clone(),
            built: None,
        })
    }

    /// The representation.
    pub fn rep(&self) -> &Representation {
        &self.rep
    }

    /// Replaces the representation by `rep`, which must have the same selection (the binding is
    /// kept); the particles are rebuilt on the next frame when its style, colours or radii
    /// changed.
    pub fn set_rep(&mut self, rep: Representation) {
        debug_assert_eq!(rep.selection, self.rep.selection);
        if rep.style != self.rep.style
            || rep.colour != self.rep.colour
            || rep.radii != self.rep.radii
        {
            self.built = None;
        }
        self.rep = rep;
    }

    /// The particles of the last frame, once one was built (their own radii, before any
    /// exposure, and which are heavy atoms).
    pub fn particles(&self) -> Option<&Particles> {
        self.built
            .as_ref()
            .map(|(_, particles, _)| particles.as_ref())
    }

    /// True when the selection depends on positions (re-evaluated every frame).
    pub fn is_dynamic(&self) -> bool {
        self.selection.is_dynamic()
    }

    /// The selected atoms in `frame` (sorted 0-based indices).
    pub fn atoms(&self, frame: &Frame) -> Vec<u32> {
        self.selection.indices(frame)
    }

    /// The particles of this representation in `frame`.
    pub fn frame(&mut self, topology: &Topology, frame: &Frame) -> Result<LayerFrame, LayerError> {
        self.frame_with(topology, frame, true)
    }

    /// [`Layer::frame`]; with `host_exposure` false, radii that follow exposure are left to the
    /// engine ([`LayerFrame::frame_radii`] stays `None` and the radii are the particles' own:
    /// the GPU engine counts the exposure itself, [`crate::gpu::exposure`]).
    pub fn frame_with(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        host_exposure: bool,
    ) -> Result<LayerFrame, LayerError> {
        let model_err = |source| LayerError::Model {
            name: self.rep.name.clone(),
            source,
        };
        if frame.positions.len() != topology.len() {
            return Err(model_err(ModelError::AtomCountMismatch {
                frame: frame.index,
                frame_atoms: frame.positions.len(),
                topology_atoms: topology.len(),
            }));
        }
        let atoms = self.selection.indices(frame);
        // Per-frame data colours rebuild the particles (their colours) every frame.
        let reuse = self.built.as_ref().is_some_and(|(a, _, _)| *a == atoms)
            && !self.rep.colour.is_per_frame();
        let rebuilt = !reuse;
        if rebuilt {
            let all = atoms.len() == topology.len();
            let subset = (!all).then_some(&atoms[..]);
            let options = self.rep.particle_options(&self.radius_overrides);
            let particles =
                Particles::new_subset(topology, frame, &options, subset).map_err(model_err)?;
            let bonds = if self.rep.style.atom_style().is_some_and(|s| s.has_bonds()) {
                let file_bonds = plausible_bonds(&topology.bonds, frame);
                let mut b = particles.bonds_within(&file_bonds);
                if file_bonds.is_empty() && !particles.is_beads() {
                    let positions = particles.positions(frame).map_err(model_err)?;
                    b = guess_bonds(&positions, particles.radii());
                }
                b
            } else {
                Vec::new()
            };
            self.built = Some((atoms, Arc::new(particles), Arc::new(bonds)));
        }
        let Some((_, particles, bonds)) = &self.built else {
            unreachable!("built above")
        };
        let positions = particles.positions(frame).map_err(model_err)?;
        let frame_radii = if host_exposure {
            particles.frame_radii(&positions)
        } else {
            None
        };
        Ok(LayerFrame {
            particles: particles.clone(),
            positions,
            bonds: bonds.clone(),
            rebuilt,
            frame_radii,
        })
    }
}

/// Longest bond kept from a file, in Å: covalent bonds are under 2.5 Å (S-S 2.05, P-O 1.6);
/// anything this long is a CONECT record or topology entry joined to the wrong atom.
pub const MAX_FILE_BOND: f32 = 3.0;

/// The file's bonds that are drawable in `frame`: both ends exist and lie at most
/// [`MAX_FILE_BOND`] apart (a bond split by the periodic box is not drawn across it).
pub fn plausible_bonds(bonds: &[[u32; 2]], frame: &Frame) -> Vec<[u32; 2]> {
    let p = &frame.positions;
    bonds
        .iter()
        .copied()
        .filter(|&[a, b]| match (p.get(a as usize), p.get(b as usize)) {
            (Some(pa), Some(pb)) => a != b && pa.distance(*pb) <= MAX_FILE_BOND,
            _ => false,
        })
        .collect()
}
