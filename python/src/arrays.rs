//! numpy arrays in and out: shape checks with one-line messages (`ValueError`), copies into the
//! engine's types, and the mesh arrays handed back. Coordinates and radii are in Å. The Python
//! wrapper (`mdsurf/__init__.py`) has already converted every input to float32.

use glam::Vec3;
use numpy::ndarray::{Array2, ArrayViewD};
use numpy::{PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Fails unless `array` has `shape`, where `None` stands for any length; `what` and `expected`
/// name the argument and its shape for the message, e.g. `positions must be an (N, 3) array`.
fn check_shape(
    array: &PyReadonlyArrayDyn<'_, f32>,
    shape: &[Option<usize>],
    what: &str,
    expected: &str,
) -> PyResult<()> {
    let got = array.shape();
    let fits = got.len() == shape.len()
        && got
            .iter()
            .zip(shape)
            .all(|(g, s)| s.is_none_or(|s| *g == s));
    if fits {
        Ok(())
    } else {
        let dims: Vec<String> = got.iter().map(usize::to_string).collect();
        Err(PyValueError::new_err(format!(
            "{what} must be an array of shape {expected}, got shape ({})",
            dims.join(", ")
        )))
    }
}

/// Positions (N, 3) in Å.
pub fn positions(array: &PyReadonlyArrayDyn<'_, f32>) -> PyResult<Vec<Vec3>> {
    check_shape(array, &[None, Some(3)], "positions", "(N, 3)")?;
    Ok(rows(&array.as_array()).map(Vec3::from).collect())
}

/// Radii (N,) in Å, for `atoms` atoms.
pub fn radii(array: &PyReadonlyArrayDyn<'_, f32>, atoms: usize) -> PyResult<Vec<f32>> {
    check_shape(
        array,
        &[Some(atoms)],
        "radii",
        &format!("({atoms},), one per atom"),
    )?;
    Ok(array.as_array().iter().copied().collect())
}

/// Linear RGB colours (N, 3) in 0..1.
pub fn colours(array: &PyReadonlyArrayDyn<'_, f32>, atoms: usize) -> PyResult<Vec<[f32; 3]>> {
    check_shape(
        array,
        &[Some(atoms), Some(3)],
        "colors",
        &format!("({atoms}, 3), one RGB row per atom"),
    )?;
    Ok(rows(&array.as_array()).collect())
}

/// Checks a trajectory (F, N, 3) in Å; returns F and N.
pub fn trajectory(array: &PyReadonlyArrayDyn<'_, f32>) -> PyResult<(usize, usize)> {
    check_shape(array, &[None, None, Some(3)], "trajectory", "(F, N, 3)")?;
    let shape = array.shape();
    Ok((shape[0], shape[1]))
}

/// The rows of an (M, 3) view as triples (any memory layout).
fn rows<'a>(view: &'a ArrayViewD<'_, f32>) -> impl Iterator<Item = [f32; 3]> + 'a {
    view.outer_iter().map(|row| {
        let mut it = row.iter().copied();
        let mut next = || it.next().unwrap_or(f32::NAN);
        [next(), next(), next()]
    })
}

/// Writes frame `f` of a checked (F, N, 3) view into `out` (resized to N).
pub fn frame_into(view: &ArrayViewD<'_, f32>, f: usize, out: &mut Vec<Vec3>) {
    out.clear();
    let frame = view.index_axis(numpy::ndarray::Axis(0), f);
    out.extend(rows(&frame).map(Vec3::from));
}

/// An (M, 3) float32 array of `items`.
pub fn array_f32<'py>(py: Python<'py>, items: &[[f32; 3]]) -> Bound<'py, PyArray2<f32>> {
    let flat: Vec<f32> = items.iter().flatten().copied().collect();
    to_array(py, flat)
}

/// An (M, 3) array from M * 3 values.
pub fn to_array<T: numpy::Element>(py: Python<'_>, flat: Vec<T>) -> Bound<'_, PyArray2<T>> {
    let rows = flat.len() / 3;
    match Array2::from_shape_vec((rows, 3), flat) {
        Ok(a) => PyArray2::from_owned_array(py, a),
        // Unreachable: `flat` holds whole rows of three.
        Err(_) => PyArray2::zeros(py, [0, 3], false),
    }
}
