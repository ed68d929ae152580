//! The buried area between two selections, frame by frame: what `mdsurf surface --interface`,
//! the window's Interface section and Python share. Each side is a [`Layer`] (a selection
//! bound to the topology, with the radii and surface parameters of a representation), and a
//! frame is measured on the Gaussian surface ([`measure::interface`], CPU engine) or, with a
//! probe radius, on the probe's solvent-excluded surface ([`measure::ses_probe_interface`]).
//! When the frame already has the surface of both sides together ([`ShownSurface`], such as
//! the `--select` surface of `mdsurf surface`), that surface is the complex and only the two
//! sides are computed ([`measure::interface_on`]). With periodic surfaces
//! ([`Interface::set_periodic`]) the three are computed periodic in the frame's cell.

use glam::Vec3;

use crate::measure::interface::Complex;
use crate::measure::{
    self, ContactResidue, InterfaceResult, MeasureError, ProbeOptions, ResidueNames,
};
use crate::model::{Frame, Particles, RadiusOverrides, Topology};
use crate::surface::periodic::{PeriodicCell, PeriodicEngine, PeriodicError};
use crate::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceParams};

use super::frame::LayerResult;
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
    /// The frame's cell cannot hold periodic surfaces.
    #[error(transparent)]
    Periodic(#[from] PeriodicError),
    /// A probe was asked for with periodic surfaces.
    #[error(
        "the probe's surface (a probe radius) is measured in open space, not in a periodic cell: leave out the probe or the periodic surfaces"
    )]
    PeriodicProbe,
}

/// One frame's interface.
#[derive(Debug, Clone)]
pub struct InterfaceFrame {
    /// Areas alone, together and buried (Å²), per atom too.
    pub result: InterfaceResult,
    /// Residues losing more than the threshold asked for, those of A first.
    pub contacts: Vec<ContactResidue>,
    /// True when the complex was a surface the frame already had ([`ShownSurface`]), not
    /// computed again.
    pub complex_shown: bool,
}

/// A surface the frame already has (a representation's), with the topology atoms of its
/// particles (sorted): [`Interface::measure_on`] takes it as the complex when it is the surface
/// of exactly both sides' atoms, with the same positions, radii, parameters and vertex mode.
#[derive(Clone, Copy)]
pub struct ShownSurface<'a> {
    /// The representation's result (its mesh kept).
    pub layer: &'a LayerResult,
    /// The topology atoms of its particles, ascending.
    pub atoms: &'a [u32],
    /// Its particles ([`Layer::particles`]), when known: radii that follow exposure are then
    /// the complex's when the particles' own radii, heavy atoms and model are the sides', and
    /// the complex's radii need not be counted to check them.
    pub particles: Option<&'a Particles>,
}

/// Two selections to measure the interface of.
pub struct Interface {
    sides: [Layer; 2],
    engine: CpuEngine,
    params: SurfaceParams,
    probe: Option<f32>,
    /// The engine of periodic surfaces, when the three surfaces are periodic in each frame's
    /// cell ([`Interface::set_periodic`]).
    periodic: Option<PeriodicEngine>,
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
            periodic: None,
        })
    }

    /// Measures the three surfaces periodic in each frame's cell (as `--periodic` computes
    /// surfaces; [`measure::periodic_interface`]), or not. Fails with a probe, whose surface
    /// is not periodic.
    pub fn set_periodic(&mut self, periodic: bool) -> Result<(), InterfaceError> {
        if periodic && self.probe.is_some() {
            return Err(InterfaceError::PeriodicProbe);
        }
        self.periodic = periodic.then(PeriodicEngine::new);
        Ok(())
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
        self.measure_on(topology, frame, Some(threshold), &[])
    }

    /// [`Interface::measure`], taking the complex from `shown` when one of them is the surface
    /// of both sides together ([`ShownSurface`]) instead of computing it again: the result is
    /// the same (to rounding when its atoms are in another order than A's then B's). With no
    /// `threshold` the contact residues are not looked for: the Gaussian surfaces' per-atom
    /// areas are not weighed (empty in the result) and `contacts` is empty.
    pub fn measure_on(
        &mut self,
        topology: &Topology,
        frame: &Frame,
        threshold: Option<f64>,
        shown: &[ShownSurface<'_>],
    ) -> Result<InterfaceFrame, InterfaceError> {
        let [a, b] = &mut self.sides;
        let (fa, fb) = (a.frame(topology, frame)?, b.frame(topology, frame)?);
        let (ia, ib) = (atoms_of(&fa, a)?, atoms_of(&fb, b)?);
        self.check_apart(topology, &ia, &ib)?;
        let mut complex_shown = false;
        let result = match self.probe {
            None if self.periodic.is_some() => {
                let cell = frame.cell.as_ref().ok_or(PeriodicError::NoBox)?;
                let cell = PeriodicCell::from_cell(cell).map_err(PeriodicError::from)?;
                let radii = complex_radii(&fa, &fb);
                let engine = self.periodic.get_or_insert_with(PeriodicEngine::new);
                measure::periodic_interface(
                    engine,
                    [&fa.atom_set(), &fb.atom_set()],
                    &cell,
                    radii.as_deref(),
                    &self.params,
                    threshold.is_some(),
                )?
            }
            Some(probe) => measure::ses_probe_interface(
                topology,
                (Some(&ia), &fa.atom_set()),
                (Some(&ib), &fb.atom_set()),
                &ProbeOptions {
                    probe,
                    ..ProbeOptions::default()
                },
            )?,
            None => {
                let (sa, sb) = (fa.atom_set(), fb.atom_set());
                let per_atom = threshold.is_some();
                let mut radii = None;
                let mut sides = Sides {
                    atoms: [&ia, &ib],
                    sets: [&sa, &sb],
                    radii: Radii::SameExposure([&fa, &fb]),
                };
                // First without counting the complex's radii (a shown surface whose particles
                // prove them), then with them counted.
                let mut found = shown
                    .iter()
                    .find_map(|s| self.complex_in(s, &sides, per_atom));
                if found.is_none() {
                    radii = complex_radii(&fa, &fb);
                    sides.radii = Radii::Bits(radii.as_deref());
                    found = shown
                        .iter()
                        .find_map(|s| self.complex_in(s, &sides, per_atom));
                }
                match found {
                    Some((a_at, b_at, layer)) => {
                        complex_shown = true;
                        let complex = Complex {
                            output: &layer.output,
                            atoms: AtomSet {
                                positions: &layer.particles.positions,
                                radii: &layer.particles.radii,
                                colours: None,
                            },
                            a_at: &a_at,
                            b_at: &b_at,
                        };
                        measure::interface_on(
                            &mut self.engine,
                            &sa,
                            &sb,
                            &complex,
                            &self.params,
                            per_atom,
                        )?
                    }
                    None => measure::interface_with(
                        &mut self.engine,
                        &sa,
                        &sb,
                        radii.as_deref(),
                        &self.params,
                        per_atom,
                    )?,
                }
            }
        };
        let contacts = match threshold {
            Some(t) => measure::contact_residues(topology, Some(&ia), Some(&ib), &result, t)?,
            None => Vec::new(),
        };
        Ok(InterfaceFrame {
            result,
            contacts,
            complex_shown,
        })
    }
}

/// One frame's two sides: their topology atoms, their engine inputs and how a shown surface's
/// radii are checked against the complex's.
struct Sides<'a> {
    atoms: [&'a [u32]; 2],
    sets: [&'a AtomSet<'a>; 2],
    radii: Radii<'a>,
}

/// How a shown surface's radii are checked against the complex's.
enum Radii<'a> {
    /// Bit for bit against the complex's radii (A's atoms then B's; `None`: each side's own).
    Bits(Option<&'a [f32]>),
    /// The sides' frames: radii that follow exposure are the complex's when the shown
    /// particles' own radii, heavy atoms and model are the sides' (the same atoms at the same
    /// positions count the same neighbours); fixed radii are compared bit for bit.
    SameExposure([&'a LayerFrame; 2]),
}

impl Interface {
    /// Where each atom of A and of B is in `shown`'s particles, when `shown` is the surface of
    /// exactly these atoms, at the same positions with the complex's radii, computed with this
    /// interface's parameters and vertex mode, closed (not periodic), computed on the host, with
    /// its mesh when the per-atom areas are weighed (`per_atom`).
    fn complex_in<'s>(
        &self,
        shown: &ShownSurface<'s>,
        sides: &Sides<'_>,
        per_atom: bool,
    ) -> Option<(Vec<u32>, Vec<u32>, &'s LayerResult)> {
        let layer = shown.layer;
        let particles = &layer.particles;
        let fits = self.probe.is_none()
            && layer.is_surface()
            && !layer.beads
            && layer.closed
            && layer.gpu_surface.is_none()
            && (!per_atom || layer.output.counts_without_mesh.is_none())
            && layer.rep.params() == self.params
            && layer.rep.vertices == self.engine.vertices()
            && particles.positions.len() == shown.atoms.len()
            && particles.radii.len() == shown.atoms.len()
            && shown.atoms.len() == sides.atoms[0].len() + sides.atoms[1].len();
        if !fits {
            return None;
        }
        // With radii that follow exposure, the shown particles' own radii and heavy atoms, and
        // each side's, to compare instead of the counted radii.
        let exposure = match &sides.radii {
            Radii::SameExposure(frames) => {
                let own = shown.particles?;
                let model = own.exposure().map(|(m, _)| m);
                if frames
                    .iter()
                    .any(|f| f.particles.exposure().map(|(m, _)| m) != model)
                {
                    return None;
                }
                match model {
                    Some(_) => Some((
                        own_radii_and_heavy(own)?,
                        [
                            own_radii_and_heavy(&frames[0].particles)?,
                            own_radii_and_heavy(&frames[1].particles)?,
                        ],
                    )),
                    None => None,
                }
            }
            Radii::Bits(_) => None,
        };
        let mut k = 0;
        let mut place = |side: usize| -> Option<Vec<u32>> {
            let (atoms, set) = (sides.atoms[side], sides.sets[side]);
            let mut at = Vec::with_capacity(atoms.len());
            for (i, &atom) in atoms.iter().enumerate() {
                let j = shown.atoms.binary_search(&atom).ok()?;
                let same_radius = match (&exposure, &sides.radii) {
                    (Some(((own_radii, own_heavy), theirs)), _) => {
                        let (their_radii, their_heavy) = theirs[side];
                        own_radii[j].to_bits() == their_radii[i].to_bits()
                            && own_heavy[j] == their_heavy[i]
                    }
                    (None, Radii::Bits(Some(r))) => particles.radii[j].to_bits() == r[k].to_bits(),
                    (None, _) => particles.radii[j].to_bits() == set.radii[i].to_bits(),
                };
                k += 1;
                if !(same_radius && particles.positions[j] == set.positions[i]) {
                    return None;
                }
                at.push(j as u32);
            }
            Some(at)
        };
        let a_at = place(0)?;
        let b_at = place(1)?;
        Some((a_at, b_at, layer))
    }
}

/// `particles`' own radii (Å, before exposure) and which are heavy atoms, when their radii
/// follow exposure.
fn own_radii_and_heavy(particles: &Particles) -> Option<(&[f32], &[bool])> {
    Some((particles.radii(), particles.exposure()?.1))
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
