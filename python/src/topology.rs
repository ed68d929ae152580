//! Radii as `mdsurf surface` assigns them (DESIGN section 2), for callers that read the files
//! themselves (MDAnalysis): elements from the file where it states a valid one, else guessed
//! from atom and residue names (`CD` in a protein is carbon); coarse-grained systems get the
//! bead radius; untyped particle types a radius fitted to their spacing. Radii are in Å.
//! And the topology of a scene (`SceneCore`), built from the per-atom columns Python reads
//! from a universe or arrays ([`Columns`], [`build_topology`]).

use glam::Vec3;
use mdsurf::model::Topology;
use mdsurf::model::elements;
use mdsurf::model::sizing::fit_untyped_radii;
use numpy::{PyArray1, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Radius in Å of an element symbol (any case): H 1.0, C 1.5, N 1.4, O 1.3, F 1.2, S 1.9,
/// P 1.8, anything else 1.5.
#[pyfunction]
fn element_radius(symbol: &str) -> f32 {
    elements::element_radius(elements::canonical_symbol(symbol).unwrap_or(""))
}

/// The element mdsurf guesses for atom `name` in residue `resname` (`""` when none).
#[pyfunction]
#[pyo3(signature = (name, resname = ""))]
fn guess_element(name: &str, resname: &str) -> &'static str {
    elements::guess_element(name, resname).unwrap_or("")
}

/// Fails unless `list` (when given) has one entry per atom.
fn per_atom(list: Option<Vec<String>>, what: &str, atoms: usize) -> PyResult<Vec<String>> {
    match list {
        None => Ok(vec![String::new(); atoms]),
        Some(l) if l.len() == atoms => Ok(l),
        Some(l) => Err(PyValueError::new_err(format!(
            "{what} has {} entries for {atoms} atoms",
            l.len()
        ))),
    }
}

/// The radius in Å of every atom, as `mdsurf surface` gives it for a file with these atom
/// `names`, residue names `resnames` and `elements` (empty or invalid entries are guessed);
/// `positions` (N, 3) in Å, when given, size untyped particles as the CLI does from the first
/// frame.
#[pyfunction]
#[pyo3(signature = (names, resnames = None, elements = None, positions = None))]
fn topology_radii<'py>(
    py: Python<'py>,
    names: Vec<String>,
    resnames: Option<Vec<String>>,
    elements: Option<Vec<String>>,
    positions: Option<PyReadonlyArrayDyn<'py, f32>>,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    let n = names.len();
    let elements = per_atom(elements, "elements", n)?
        .into_iter()
        .map(|e| elements::canonical_symbol(&e).unwrap_or(""))
        .collect();
    let mut topology = Topology {
        residue_names: per_atom(resnames, "resnames", n)?.into(),
        elements,
        names: names.into(),
        ..Topology::default()
    };
    topology.complete_elements_and_radii();
    if let Some(p) = positions {
        let points = crate::arrays::positions(&p)?;
        if points.len() != n {
            return Err(PyValueError::new_err(format!(
                "positions has {} rows for {n} atoms",
                points.len()
            )));
        }
        fit_untyped_radii(&mut topology, &points);
    }
    Ok(PyArray1::from_vec(py, topology.radii))
}

/// Adds this file's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(element_radius, m)?)?;
    m.add_function(wrap_pyfunction!(guess_element, m)?)?;
    m.add_function(wrap_pyfunction!(topology_radii, m)?)?;
    Ok(())
}

/// Fails unless `list` (when given) has one entry per atom.
fn per_atom_if_given<T>(
    list: Option<Vec<T>>,
    what: &str,
    atoms: usize,
) -> PyResult<Option<Vec<T>>> {
    match list {
        Some(l) if l.len() != atoms => Err(PyValueError::new_err(format!(
            "{what} has {} entries for {atoms} atoms",
            l.len()
        ))),
        other => Ok(other),
    }
}

/// The per-atom columns a topology is built from (any but `names` may be missing).
#[derive(FromPyObject, Default)]
#[pyo3(from_item_all)]
pub(crate) struct Columns {
    names: Vec<String>,
    #[pyo3(default)]
    resnames: Option<Vec<String>>,
    #[pyo3(default)]
    resids: Option<Vec<i64>>,
    /// Which residue each atom belongs to as the reader grouped them (MDAnalysis' resindex): a
    /// new residue starts where it changes, as where number, name, chain or segment change.
    #[pyo3(default)]
    residues: Option<Vec<i64>>,
    #[pyo3(default)]
    chains: Option<Vec<String>>,
    #[pyo3(default)]
    segments: Option<Vec<String>>,
    #[pyo3(default)]
    elements: Option<Vec<String>>,
    #[pyo3(default)]
    types: Option<Vec<String>>,
    #[pyo3(default)]
    masses: Option<Vec<f32>>,
    #[pyo3(default)]
    charges: Option<Vec<f32>>,
    #[pyo3(default)]
    serials: Option<Vec<i64>>,
    #[pyo3(default)]
    b_factors: Option<Vec<f32>>,
    #[pyo3(default)]
    occupancies: Option<Vec<f32>>,
    #[pyo3(default)]
    bonds: Option<Vec<(i64, i64)>>,
}

/// The topology of `columns` as the crate's readers leave it: elements canonical (invalid ones
/// guessed from atom and residue names), radii and missing masses from the element table,
/// residues numbered as runs, untyped particles sized from `first` (positions of frame 0).
pub(crate) fn build_topology(c: Columns, first: &[Vec3]) -> PyResult<Topology> {
    let n = c.names.len();
    if n == 0 {
        return Err(PyValueError::new_err("the topology has no atoms"));
    }
    if first.len() != n {
        return Err(PyValueError::new_err(format!(
            "frame 0 has {} atoms but the topology has {n}",
            first.len()
        )));
    }
    let resnames = per_atom_if_given(c.resnames, "resnames", n)?;
    let resids = per_atom_if_given(c.resids, "resids", n)?;
    let residues = per_atom_if_given(c.residues, "residues", n)?;
    let has_residues = resnames.is_some() || resids.is_some() || residues.is_some();
    let labels = |v: Option<Vec<String>>| v.unwrap_or_else(|| vec![String::new(); n]);
    let elements = per_atom_if_given(c.elements, "elements", n)?
        .map(|v| {
            v.iter()
                .map(|e| elements::canonical_symbol(e).unwrap_or(""))
                .collect::<Vec<_>>()
        })
        .unwrap_or_else(|| vec![""; n]);
    let mut top = Topology {
        names: c.names.into(),
        elements: elements.into(),
        residue_names: labels(resnames).into(),
        residue_ids: resids.unwrap_or_else(|| vec![0; n]),
        chains: labels(per_atom_if_given(c.chains, "chains", n)?).into(),
        segments: labels(per_atom_if_given(c.segments, "segments", n)?).into(),
        b_factors: per_atom_if_given(c.b_factors, "b_factors", n)?.unwrap_or_default(),
        occupancies: per_atom_if_given(c.occupancies, "occupancies", n)?.unwrap_or_default(),
        masses: per_atom_if_given(c.masses, "masses", n)?.unwrap_or_default(),
        charges: per_atom_if_given(c.charges, "charges", n)?.unwrap_or_default(),
        serials: per_atom_if_given(c.serials, "serials", n)?.unwrap_or_default(),
        ..Topology::default()
    };
    if let Some(types) = per_atom_if_given(c.types, "types", n)? {
        top.types = types.into();
    }
    if let Some(bonds) = c.bonds {
        top.bonds = bonds
            .into_iter()
            .map(|(a, b)| {
                let ok = |x: i64| (0..n as i64).contains(&x);
                if ok(a) && ok(b) {
                    Ok([a as u32, b as u32])
                } else {
                    Err(PyValueError::new_err(format!(
                        "bond ({a}, {b}) names an atom outside 0..{n}"
                    )))
                }
            })
            .collect::<PyResult<_>>()?;
    }
    // Residues as runs of atoms with the same (number, name, chain, segment) and reader
    // residue, numbered as the crate's readers number them; atoms of a file without residues
    // are residues of their own.
    let group = match (has_residues, residues) {
        (false, _) => vec![u32::MAX; n],
        (true, Some(residues)) => {
            // Only whether an atom's residue equals the previous atom's counts: run numbers.
            let mut run = 0u32;
            (0..n)
                .map(|i| {
                    if i > 0 && residues[i] != residues[i - 1] {
                        run = (run + 1) % u32::MAX;
                    }
                    run
                })
                .collect()
        }
        (true, None) => vec![0; n],
    };
    top.number_residue_runs(&group);
    top.complete_elements_and_radii();
    fit_untyped_radii(&mut top, first);
    Ok(top)
}
