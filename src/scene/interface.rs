//! The buried area between two selections, frame by frame: what `mdsurf surface --interface`,
//! the window's Interface section and Python share. Each side is a [`Layer`] (a selection
//! bound to the topology, with the radii and surface parameters of a representation), and a
//! frame is measured on the Gaussian surface ([`measure::interface`], CPU engine) or, with a
//! probe radius, on the probe's solvent-excluded surface ([`measure::ses_probe_interface`]).

use glam::Vec3;

use crate::measure::{
    self, ContactResidue, InterfaceResult, MeasureError, ProbeOptions, ResidueNames,
};
use crate::model::{Frame, RadiusOverrides, Topology};
use crate::surface::{CpuEngine, SurfaceParams};

use super::layer::{Layer, LayerError, LayerFrame};
use super::representation::{RepStyle, Representation, RepresentationError};

/// Why an interface could not be set up or measured.
#[derive(Debug, thiserror::Error)]
pub enum InterfaceError {
    /// A side's selection or parameters are invalid.
    #[error(transparent)]
    Representation(#[from] RepresentationError),
    /// A side's selection does not fit the frame.
    #[error(transparent)]
    Side(#[from] LayerError),
    /// A side's selection picks no atom.
    #[error("selection '{selection}' matches no atom")]
    NoAtoms {
        /// The selection text.
        selection: String,
    },
    /// The two selections pick some of the same atoms.
    #[error(
        "selections '{a}' and '{b}' share {shared} atom(s), the first {first}: the buried area is between two separate groups"
    )]
    Overlap {
        /// The first selection.
        a: String,
        /// The second selection.
        b: String,
        /// How many atoms both pick.
        shared: usize,
        /// The first of them, as `A:PRO1 N`.
        first: String,
    },
    /// The surfaces could not be measured.
    #[error(transparent)]
    Measure(#[from] MeasureError),
}

/// One frame's interface.
#[derive(Debug, Clone)]
pub struct InterfaceFrame {
    /// Areas alone, together and buried (Å²), per atom too.
    pub result: InterfaceResult,
    /// Residues losing more than the threshold asked for, those of A first.
    pub contacts: Vec<ContactResidue>,
}

/// Two selections to measure the interface of.
pub struct Interface {
    sides: [Layer; 2],
    engine: CpuEngine,
    params: SurfaceParams,
    probe: Option<f32>,
}

impl Interface {
    /// Binds `selection_a` and `selection_b` to `topology` as surface layers starting from
    /// `base` (its parameters, radius set and vertex mode), with `overrides`. With `probe`
    /// (Å) frames are measured on that probe's SES with Bondi's radii instead.
    pub fn new(
        topology: &Topology,
        [selection_a, selection_b]: [&str; 2],
        base: &Representation,
        overrides: &RadiusOverrides,
        probe: Option<f32>,
    ) -> Result<Interface, InterfaceError> {
        let side = |name: &str, selection: &str| -> Result<Layer, InterfaceError> {
            let mut rep = Representation::new(name, selection, RepStyle::Surface);
            rep.set_params(&base.params());
            rep.radii = base.radii;
            rep.vertices = base.vertices;
            rep.validate()?;
            Ok(Layer::new(rep, topology, overrides)?)
        };
        Ok(Interface {
            sides: [side("side A", selection_a)?, side("side B", selection_b)?],
            engine: CpuEngine::new().with_vertices(base.vertices),
            params: base.params(),
            probe,
        })
    }

    /// The two selections' texts.
    pub fn selections(&self) -> [&str; 2] {
        self.sides.each_ref().map(|s| s.rep().selection.as_str())
    }

    /// Fails when a side picks no atom of `frame` (the error names its selection), or when
    /// both pick some of the same atoms.
    pub fn check_sides(&self, topology: &Topology, frame: &Frame) -> Result<(), InterfaceError> {
        let [a, b] = self.sides.each_ref().map(|side| side.atoms(frame));
        for (side, atoms) in self.sides.iter().zip([&a, &b]) {
            if atoms.is_empty() {
                return Err(no_atoms(side));
            }
        }
        self.check_apart(topology, &a, &b)
    }

    /// Fails when the topology atoms `a` and `b` of the two sides share any.
    fn check_apart(&self, topology: &Topology, a: &[u32], b: &[u32]) -> Result<(), InterfaceError> {
        let len = a
            .iter()
            .chain(b)
            .map(|&i| i as usize + 1)
            .max()
            .unwrap_or(0);
        let mut in_a = vec![false; len];
        for &i in a {
            in_a[i as usize] = true;
        }
        let shared: Vec<u32> = b.iter().copied().filter(|&i| in_a[i as usize]).collect();
        let Some(&first) = shared.iter().min() else {
            return Ok(());
        };
        let names = ResidueNames::of_atom(topology, first as usize);
        let [a, b] = self.selections().map(str::to_string);
        Err(InterfaceError::Overlap {
            a,
            b,
            shared: shared.len(),
            first: format!("{} {}", names.label(), names.atom_name.trim()),
        })
    }

    /// The interface in `frame`, with the residues that lose more than `threshold` Å²
    /// ([`measure::CONTACT_THRESHOLD`] by default).
    pub fn measure(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        threshold: f64,
    ) -> Result<InterfaceFrame, InterfaceError> {
        let [a, b] = &mut self.sides;
        let (fa, fb) = (a.frame(topology, frame)?, b.frame(topology, frame)?);
        let (ia, ib) = (atoms_of(&fa, a)?, atoms_of(&fb, b)?);
        self.check_apart(topology, &ia, &ib)?;
        let result = match self.probe {
            Some(probe) => measure::ses_probe_interface(
                topology,
                (Some(&ia), &fa.atom_set()),
                (Some(&ib), &fb.atom_set()),
                &ProbeOptions {
                    probe,
                    ..ProbeOptions::default()
                },
            )?,
            None => measure::interface_with(
                &mut self.engine,
                &fa.atom_set(),
                &fb.atom_set(),
                complex_radii(&fa, &fb).as_deref(),
                &self.params,
            )?,
        };
        let contacts =
            measure::contact_residues(topology, Some(&ia), Some(&ib), &result, threshold)?;
        Ok(InterfaceFrame { result, contacts })
    }
}

/// The complex's radii (Å, A's atoms then B's) when they follow exposure: each atom's
/// neighbours counted over both sides, as a surface of the two together counts them (each
/// side's own frame counts them over that side alone). `None` when radii are fixed.
fn complex_radii(a: &LayerFrame, b: &LayerFrame) -> Option<Vec<f32>> {
    let ((model, heavy_a), (_, heavy_b)) = (a.particles.exposure()?, b.particles.exposure()?);
    let radii: Vec<f32> = [a, b]
        .iter()
        .flat_map(|s| s.particles.radii())
        .copied()
        .collect();
    let positions: Vec<Vec3> = [a, b].iter().flat_map(|s| &s.positions).copied().collect();
    let heavy: Vec<bool> = heavy_a.iter().chain(heavy_b).copied().collect();
    Some(model.apply(&radii, &positions, &heavy))
}

/// The error of a side whose selection picks no atom.
fn no_atoms(side: &Layer) -> InterfaceError {
    InterfaceError::NoAtoms {
        selection: side.rep().selection.clone(),
    }
}

/// The topology indices of the atoms a side's frame holds (its selection's, evaluated once by
/// [`Layer::frame`]); fails when there are none.
fn atoms_of(frame: &LayerFrame, side: &Layer) -> Result<Vec<u32>, InterfaceError> {
    let particles = &frame.particles;
    if particles.is_empty() {
        return Err(no_atoms(side));
    }
    Ok(match particles.subset() {
        Some(atoms) => atoms.to_vec(),
        None => (0..particles.len() as u32).collect(),
    })
}
