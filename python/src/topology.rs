//! Radii as `mdsurf surface` assigns them (DESIGN section 2), for callers that read the files
//! themselves (MDAnalysis): elements from the file where it states a valid one, else guessed
//! from atom and residue names (`CD` in a protein is carbon); coarse-grained systems get the
//! bead radius; untyped particle types a radius fitted to their spacing. Radii are in Å.

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
