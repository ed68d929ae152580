//! The measurements of `mdsurf surface --per-atom/--per-residue/--cavities/--interface` for a
//! [`SceneCore`] (crate `mdsurf::measure`, docs/measure.md): area per atom and per residue
//! (Å²) with exposure, cavities tracked over the frames asked for (volume Å³, area Å², centroid
//! Å, lining residues), and the buried area between two selections with its contact residues.
//! Each function computes a list of frames in one call, in the given order, as the command line
//! does over `--frames`: the exposure table comes from the first of them, cavity ids start at 1
//! with the first. The surfaces come from the scene's second engine, which keeps meshes (as
//! the command line's does when a measurement needs them). The Python half
//! (`mdsurf/measurements.py`) assembles the per-frame rows into numpy arrays.

use std::sync::Arc;

use mdsurf::measure::{
    self, CavityOptions, CavityTracker, ExposureTable, MeasureError, ProbeOptions, Side,
    lining_residues,
};
use mdsurf::model::pbc::PbcCell;
use mdsurf::model::{Frame, RadiusOverrides};
use mdsurf::scene::interface::{Interface, InterfaceError};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{LayerResult, RepRequest};
use mdsurf::surface::{AtomSet, CpuEngine};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::scene::{SceneCore, engine_mut, in_pool, scene_err};

/// A measurement error of frame `index` as a one-line `ValueError` naming what was measured.
fn measure_err(what: &str, index: usize, err: MeasureError) -> PyErr {
    PyValueError::new_err(format!("frame {index}: {what}: {err}"))
}

/// The visible surface representation named `name` (the first, when names repeat).
fn rep_named(core: &SceneCore, name: &str) -> PyResult<RepRequest> {
    core.reps
        .iter()
        .find(|r| r.rep.name == name)
        .cloned()
        .ok_or_else(|| {
            let names: Vec<&str> = core.reps.iter().map(|r| r.rep.name.as_str()).collect();
            PyValueError::new_err(format!(
                "no surface representation named '{name}' (have {})",
                names.join(", ")
            ))
        })
}

/// One representation's surface in one frame, with its mesh.
struct Measured {
    frame: Arc<Frame>,
    layer: Arc<LayerResult>,
    /// Topology atoms behind the layer's particles, in particle order.
    atoms: Vec<u32>,
}

impl Measured {
    /// The atom set the surface was computed from.
    fn atom_set(&self) -> AtomSet<'_> {
        let p = &self.layer.particles;
        AtomSet {
            positions: &p.positions,
            radii: &p.radii,
            colours: None,
        }
    }
}

/// Frame `index` of representation `req` through the mesh-keeping engine.
fn measured(
    core: &mut SceneCore,
    index: usize,
    reader: &Py<PyAny>,
    req: &RepRequest,
) -> PyResult<Measured> {
    let frame = Arc::new(core.read(index, reader)?);
    let computed = engine_mut(&mut core.meshes)
        .frame(&core.topology, index, &frame, std::slice::from_ref(req))
        .map_err(scene_err)?;
    let name = &req.rep.name;
    let Some(layer) = computed.layers.into_iter().next() else {
        return Err(PyValueError::new_err(format!(
            "representation '{name}' is hidden: nothing to measure"
        )));
    };
    if layer.beads {
        return Err(PyValueError::new_err(format!(
            "representation '{name}': per-atom, per-residue and cavity measurements need atoms, not beads"
        )));
    }
    let atoms = match engine_mut(&mut core.meshes).layer(req.id) {
        Some(bound) => bound.atoms(&frame),
        None => {
            return Err(PyValueError::new_err(format!(
                "representation '{name}' is not bound"
            )));
        }
    };
    if atoms.len() != layer.particles.positions.len() {
        return Err(PyValueError::new_err(format!(
            "representation '{name}': {} atoms selected but {} particles",
            atoms.len(),
            layer.particles.positions.len()
        )));
    }
    Ok(Measured {
        frame,
        layer,
        atoms,
    })
}

/// Per-atom areas (Å², summing to the surface's area) of `measured`.
fn atom_areas(m: &Measured) -> Result<Vec<f64>, MeasureError> {
    let params = m.layer.measured_params();
    measure::atom_areas_of(&m.layer.output, &m.atom_set(), &params)
}

/// For every topology residue (by residue index): its first atom, its label (`A:LEU12`), its
/// chain (else segment), number and name as the CSV tables write them.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn scene_residues(
    core: PyRef<'_, SceneCore>,
) -> (Vec<u32>, Vec<String>, Vec<String>, Vec<i64>, Vec<String>) {
    let top = &core.topology;
    let n = top.len().min(top.residue_index.len());
    let count = top.residue_index[..n]
        .iter()
        .max()
        .map_or(0, |&r| r as usize + 1);
    let mut first = vec![u32::MAX; count];
    for (atom, &r) in top.residue_index[..n].iter().enumerate() {
        if first[r as usize] == u32::MAX {
            first[r as usize] = atom as u32;
        }
    }
    let text = |l: &mdsurf::model::Labels, i: usize| l.get(i).unwrap_or("").trim().to_string();
    let (mut labels, mut chains, mut resids, mut resnames) = (vec![], vec![], vec![], vec![]);
    for &atom in &first {
        let i = atom as usize;
        let names = measure::ResidueNames::of_atom(top, i);
        let (resid, resname) = (
            top.residue_ids.get(i).copied().unwrap_or(0),
            text(&top.residue_names, i),
        );
        labels.push(names.label());
        chains.push(names.chain_or_segment().to_string());
        resids.push(resid);
        resnames.push(resname);
    }
    (first, labels, chains, resids, resnames)
}

/// Per atom: serial, name and residue index (topology order).
#[pyfunction]
pub fn scene_atoms(core: PyRef<'_, SceneCore>) -> (Vec<i64>, Vec<String>, Vec<u32>) {
    let top = &core.topology;
    let serials = (0..top.len())
        .map(|i| top.serials.get(i).copied().unwrap_or(i as i64 + 1))
        .collect();
    let names = (0..top.len())
        .map(|i| top.names.get(i).unwrap_or("").trim().to_string())
        .collect();
    (serials, names, top.residue_index.clone())
}

/// One frame of per-atom areas: (frame, time ps, surface area Å², topology atoms, area Å² of
/// each).
type AtomRow<'py> = (
    usize,
    Option<f64>,
    f64,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<f64>>,
);

/// Area per atom of representation `rep` in each of `frames`.
#[pyfunction]
pub fn scene_atom_areas<'py>(
    py: Python<'py>,
    mut core: PyRefMut<'_, SceneCore>,
    rep: &str,
    frames: Vec<usize>,
    reader: Py<PyAny>,
) -> PyResult<Vec<AtomRow<'py>>> {
    let core = &mut *core;
    let req = rep_named(core, rep)?;
    let rows = in_pool(py, || {
        let mut rows = Vec::with_capacity(frames.len());
        for &index in &frames {
            let m = measured(core, index, &reader, &req)?;
            let what = format!("representation '{rep}'");
            let areas = atom_areas(&m).map_err(|e| measure_err(&what, index, e))?;
            rows.push((
                index,
                m.frame.time_ps,
                m.layer.output.measured_area(),
                m.atoms,
                areas,
            ));
        }
        Ok(rows)
    })?;
    Ok(rows
        .into_iter()
        .map(|(f, t, total, atoms, areas)| {
            let atoms = PyArray1::from_vec(py, atoms);
            (f, t, total, atoms, PyArray1::from_vec(py, areas))
        })
        .collect())
}

/// One frame of per-residue areas: (frame, time ps, surface area Å², residue indices, area Å²
/// of each, exposure of each (NaN where the table lacks the name)).
type ResidueRow = (usize, Option<f64>, f64, Vec<u32>, Vec<f64>, Vec<f64>);

/// Area per residue and exposure of representation `rep` in each of `frames`; the exposure
/// table is built from the first of them, as `--per-residue` builds it from the first frame.
#[pyfunction]
pub fn scene_residue_areas(
    py: Python<'_>,
    mut core: PyRefMut<'_, SceneCore>,
    rep: &str,
    frames: Vec<usize>,
    reader: Py<PyAny>,
) -> PyResult<Vec<ResidueRow>> {
    let core = &mut *core;
    let req = rep_named(core, rep)?;
    in_pool(py, || {
        let mut rows = Vec::with_capacity(frames.len());
        let mut table: Option<ExposureTable> = None;
        let what = format!("representation '{rep}'");
        for &index in &frames {
            let m = measured(core, index, &reader, &req)?;
            let err = |e| measure_err(&what, index, e);
            let areas = atom_areas(&m).map_err(err)?;
            let residues =
                measure::residue_areas(&core.topology, Some(&m.atoms), &areas).map_err(err)?;
            if table.is_none() {
                let params = m.layer.measured_params();
                let built = ExposureTable::from_isolated_residues(
                    &mut CpuEngine::new(),
                    &core.topology,
                    Some(&m.atoms),
                    &m.atom_set(),
                    PbcCell::of(&m.frame).as_ref(),
                    &params,
                )
                .map_err(err)?;
                table = Some(built);
            }
            let exposure = residues
                .iter()
                .map(|r| {
                    table
                        .as_ref()
                        .and_then(|t| t.exposure(r.names(&core.topology).resname, r.area))
                        .unwrap_or(f64::NAN)
                })
                .collect();
            rows.push((
                index,
                m.frame.time_ps,
                m.layer.output.measured_area(),
                residues.iter().map(|r| r.residue).collect(),
                residues.iter().map(|r| r.area).collect(),
                exposure,
            ));
        }
        Ok(rows)
    })
}

/// One cavity: (id, first frame of the id, volume Å³, area Å², centroid Å, lining residue
/// labels, lining topology atoms).
type CavityRow = (u64, usize, f64, f64, [f64; 3], Vec<String>, Vec<u32>);

/// Cavities of representation `rep` in each of `frames`, tracked over them (ids from 1):
/// (frame, time ps, cavities) per frame. With `probe` (Å) the cavities are the probe's
/// (`--cavity-probe`, Bondi radii) instead of the Gaussian surface's enclosed voids.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn scene_cavities(
    py: Python<'_>,
    mut core: PyRefMut<'_, SceneCore>,
    rep: &str,
    frames: Vec<usize>,
    reader: Py<PyAny>,
    min_volume: f64,
    probe: Option<f32>,
) -> PyResult<Vec<(usize, Option<f64>, Vec<CavityRow>)>> {
    if !(min_volume.is_finite() && min_volume >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "min_volume_A3 must be a finite volume of 0 Å³ or more, got {min_volume}"
        )));
    }
    if let Some(p) = probe.filter(|p| !(p.is_finite() && (0.1..=10.0).contains(p))) {
        return Err(PyValueError::new_err(format!(
            "probe_A must be a probe radius of 0.1 to 10 Å (1.4 for water), got {p}"
        )));
    }
    let core = &mut *core;
    let req = rep_named(core, rep)?;
    let options = CavityOptions {
        min_volume,
        ..CavityOptions::default()
    };
    in_pool(py, || {
        let mut tracker = CavityTracker::new();
        let mut rows = Vec::with_capacity(frames.len());
        let what = format!("representation '{rep}'");
        for &index in &frames {
            let m = measured(core, index, &reader, &req)?;
            let err = |e| measure_err(&what, index, e);
            let params = m.layer.measured_params();
            let found = match probe {
                Some(_) if m.layer.output.periodic.is_some() => Err(MeasureError::PeriodicProbe),
                Some(probe) => {
                    let probe_options = ProbeOptions {
                        probe,
                        min_volume,
                        ..ProbeOptions::default()
                    };
                    let atoms = Some(&m.atoms[..]);
                    measure::ses_probe_cavities(
                        &core.topology,
                        atoms,
                        &m.atom_set(),
                        &probe_options,
                    )
                }
                None => measure::cavities_of(&m.layer.output, &m.atom_set(), &params, &options),
            }
            .map_err(err)?;
            let tracked = tracker.update(index, &found);
            let mut cavities = Vec::with_capacity(tracked.cavities.len());
            for t in &tracked.cavities {
                let c = &t.cavity;
                let labels = lining_residues(&core.topology, Some(&m.atoms), &c.lining_atoms)
                    .map_err(err)?;
                let atoms = c
                    .lining_atoms
                    .iter()
                    .filter_map(|&a| m.atoms.get(a as usize).copied())
                    .collect();
                let centroid = c.centroid.to_array();
                cavities.push((t.id, t.born, c.volume, c.area, centroid, labels, atoms));
            }
            rows.push((index, m.frame.time_ps, cavities));
        }
        Ok(rows)
    })
}

/// One contact residue: (side 0 for A or 1 for B, residue index, label, area alone Å², area in
/// the complex Å², area lost Å²).
type ContactRow = (u8, u32, String, f64, f64, f64);

/// One interface frame: (frame, time ps, area A, area B, area of A and B, buried, all Å²,
/// contact residues).
type InterfaceRow = (usize, Option<f64>, f64, f64, f64, f64, Vec<ContactRow>);

/// The buried area between selections `a` and `b` in each of `frames`, as `--interface A B`:
/// the three surfaces on the union's grid, CPU engine, the scene's parameters; contact residues
/// lose more than `threshold` Å². With `probe` (Å) the surfaces are that probe's
/// solvent-excluded surfaces with Bondi's radii (`--interface-probe`).
#[pyfunction]
#[pyo3(signature = (core, a, b, frames, reader, threshold, probe=None))]
#[allow(clippy::too_many_arguments)]
pub fn scene_interface(
    py: Python<'_>,
    mut core: PyRefMut<'_, SceneCore>,
    a: &str,
    b: &str,
    frames: Vec<usize>,
    reader: Py<PyAny>,
    threshold: f64,
    probe: Option<f32>,
) -> PyResult<Vec<InterfaceRow>> {
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "contact_threshold_A2 must be a finite area of 0 Å² or more, got {threshold}"
        )));
    }
    if let Some(p) = probe.filter(|p| !(p.is_finite() && (0.1..=10.0).contains(p))) {
        return Err(PyValueError::new_err(format!(
            "probe_A must be a probe radius of 0.1 to 10 Å (1.4 for water), got {p}"
        )));
    }
    let core = &mut *core;
    let mut base = Representation::new("interface", "all", RepStyle::Surface);
    base.set_params(&core.params);
    base.vertices = mdsurf::surface::SurfaceEngine::vertices(&CpuEngine::new());
    let mut sides = Interface::new(
        &core.topology,
        [a, b],
        &base,
        &RadiusOverrides::default(),
        probe,
    )
    .map_err(|e| PyValueError::new_err(format!("interface: {e}")))?;
    sides
        .set_periodic(engine_mut(&mut core.meshes).periodic().is_some())
        .map_err(|e| PyValueError::new_err(format!("interface: {e}")))?;
    in_pool(py, || {
        let mut rows = Vec::with_capacity(frames.len());
        for &index in &frames {
            let frame = core.read(index, &reader)?;
            sides
                .check_sides(&core.topology, &frame)
                .map_err(|e| PyValueError::new_err(format!("interface: {e} in frame {index}")))?;
            let err = |e| measure_err("interface", index, e);
            let measured =
                sides
                    .measure(&core.topology, &frame, threshold)
                    .map_err(|e| match e {
                        InterfaceError::Measure(e) => err(e),
                        other => {
                            PyValueError::new_err(format!("frame {index}: interface: {other}"))
                        }
                    })?;
            let result = measured.result;
            let contacts = measured
                .contacts
                .into_iter()
                .map(|c| {
                    let side = u8::from(c.side == Side::B);
                    let alone = c.residue.area;
                    let label = c.residue.names(&core.topology).label();
                    (
                        side,
                        c.residue.residue,
                        label,
                        alone,
                        c.area_complex,
                        c.buried,
                    )
                })
                .collect();
            rows.push((
                index,
                frame.time_ps,
                result.area_a,
                result.area_b,
                result.area_complex,
                result.buried,
                contacts,
            ));
        }
        Ok(rows)
    })
}

/// Adds the measurement functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(scene_residues, m)?)?;
    m.add_function(wrap_pyfunction!(scene_atoms, m)?)?;
    m.add_function(wrap_pyfunction!(scene_atom_areas, m)?)?;
    m.add_function(wrap_pyfunction!(scene_residue_areas, m)?)?;
    m.add_function(wrap_pyfunction!(scene_cavities, m)?)?;
    m.add_function(wrap_pyfunction!(scene_interface, m)?)?;
    Ok(())
}
