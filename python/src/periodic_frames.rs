//! Periodic surfaces for `mdsurf.measure` and `GaussianSurface(periodic=True)`: with per-frame
//! boxes, each frame's surface is computed by the CPU periodic engine in that frame's box (as
//! `mdsurf surface --periodic`), instead of by the engine the backend picks.

use glam::Vec3;
use mdsurf::gpu::Backend;
use mdsurf::surface::periodic::{PeriodicEngine, Replicate};
use mdsurf::surface::{AtomSet, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::surface_err;

/// The boxes of `frames` frames: an (F, 3, 3) array, rows a, b, c in Å.
pub fn boxes(array: &PyReadonlyArrayDyn<'_, f32>, frames: usize) -> PyResult<Vec<[Vec3; 3]>> {
    if array.shape() != [frames, 3, 3] {
        return Err(PyValueError::new_err(format!(
            "boxes must be an array of shape ({frames}, 3, 3), one box of edge vectors per \
             frame, got shape {:?}",
            array.shape()
        )));
    }
    let a = array.as_array();
    Ok((0..frames)
        .map(|f| [0, 1, 2].map(|r| Vec3::new(a[[f, r, 0]], a[[f, r, 1]], a[[f, r, 2]])))
        .collect())
}

/// The backend to open for a call with or without boxes: with them nothing is opened but the
/// CPU (the periodic engine has no GPU path and interpolates its vertices), so a GPU or refined
/// vertices asked for are refused in one line.
pub fn backend_for(periodic: bool, backend: Backend, vertices: VertexMode) -> PyResult<Backend> {
    if !periodic {
        return Ok(backend);
    }
    if backend == Backend::Gpu {
        return Err(PyValueError::new_err(
            "periodic surfaces (boxes given) are computed on the CPU: backend 'cpu' or 'auto'",
        ));
    }
    if vertices == VertexMode::Refined {
        return Err(PyValueError::new_err(
            "periodic surfaces (boxes given) interpolate their vertices: vertices='interpolated'",
        ));
    }
    Ok(Backend::Cpu)
}

/// Computes frames with `engine`, or, when boxes are given, periodic in each frame's box.
pub struct FrameSurfaces<'a> {
    periodic: Option<(PeriodicEngine, &'a [[Vec3; 3]])>,
}

impl<'a> FrameSurfaces<'a> {
    /// Frames in `boxes` when given.
    pub fn new(boxes: Option<&'a [[Vec3; 3]]>) -> FrameSurfaces<'a> {
        FrameSurfaces {
            periodic: boxes.map(|b| (PeriodicEngine::new(), b)),
        }
    }

    /// The surface of frame `f` (`atoms`); errors name the frame.
    pub fn compute(
        &mut self,
        engine: &mut dyn SurfaceEngine,
        f: usize,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> PyResult<SurfaceOutput> {
        match &mut self.periodic {
            Some((periodic, boxes)) => periodic
                .compute_in_cell(boxes.get(f), atoms, params, Replicate::default())
                .map_err(|e| PyValueError::new_err(format!("frame {f}: {e}"))),
            None => engine
                .compute(atoms, params)
                .map_err(|e| surface_err(&format!("frame {f}: "), e)),
        }
    }
}
