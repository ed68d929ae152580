//! `mdsurf._mdsurf`, the native half of the Python package `mdsurf`: the Gaussian density
//! surface engine (CPU reference or wgpu compute) on numpy arrays, without the file readers, the
//! command line or the viewer. The Python half (`python/mdsurf/`) converts inputs to float32,
//! documents the API, and holds the MDAnalysis analysis.
//!
//! Defaults and messages follow `mdsurf surface`: H = 1 Å, R = 1, I = 0.5, quality `medium`,
//! backend `auto`, interpolated vertices; a bad argument raises `ValueError` with the engine's
//! own one-line message, a grid too large for memory `MemoryError`, a GPU failure
//! `RuntimeError`. Lengths are in Å, areas in Å², volumes in Å³.

mod arrays;
mod engines;
mod measurements;
mod periodic_frames;
mod scene;
mod topology;

use mdsurf::measure::ExposureTable;
use mdsurf::model::pbc::PbcCell;
use mdsurf::surface::{
    AtomSet, CpuEngine, Quality, SurfaceError, SurfaceOutput, SurfaceParams, VertexMode,
};
use numpy::{PyArray1, PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use engines::parse_backend;
use mdsurf::gpu::Backend;
use periodic_frames::FrameSurfaces;

/// The exception for an engine error: bad input is a `ValueError`, a grid that does not fit a
/// `MemoryError`, anything else (the GPU) a `RuntimeError`.
fn surface_err(prefix: &str, err: SurfaceError) -> PyErr {
    let msg = format!("{prefix}{err}");
    match err {
        SurfaceError::InvalidParameter { .. }
        | SurfaceError::OutOfRange { .. }
        | SurfaceError::EmptySystem
        | SurfaceError::NonFiniteCoordinate { .. }
        | SurfaceError::InvalidRadius { .. }
        | SurfaceError::LengthMismatch { .. }
        | SurfaceError::NonFiniteColour { .. } => PyValueError::new_err(msg),
        SurfaceError::GridTooLarge { .. } => PyMemoryError::new_err(msg),
        _ => PyRuntimeError::new_err(msg),
    }
}

/// Parses the shared keyword arguments into checked parameters, backend and vertex mode.
fn settings(
    spacing: f32,
    radius_scale: f32,
    isovalue: f32,
    quality: &str,
    backend: &str,
    vertices: &str,
) -> PyResult<(SurfaceParams, Backend, VertexMode)> {
    let quality: Quality = quality.parse().map_err(PyValueError::new_err)?;
    let backend = parse_backend(backend).map_err(PyValueError::new_err)?;
    let vertices: VertexMode = vertices.parse().map_err(PyValueError::new_err)?;
    let params = SurfaceParams {
        spacing,
        radius_scale,
        isovalue,
        quality,
    };
    params.validate().map_err(|e| surface_err("", e))?;
    Ok((params, backend, vertices))
}

/// The grid a surface was sampled on: `origin` (x, y, z) in Å, `spacing` H in Å, `dims`
/// samples along x, y and z.
#[pyclass(frozen, module = "mdsurf", name = "Grid")]
struct Grid {
    /// Position of sample (0, 0, 0) in Å.
    #[pyo3(get)]
    origin: (f32, f32, f32),
    /// Distance between neighbouring samples in Å.
    #[pyo3(get)]
    spacing: f32,
    /// Number of samples along x, y and z.
    #[pyo3(get)]
    dims: (u32, u32, u32),
}

#[pymethods]
impl Grid {
    fn __repr__(&self) -> String {
        let (x, y, z) = self.origin;
        let (nx, ny, nz) = self.dims;
        format!(
            "Grid(origin=({x}, {y}, {z}), spacing={}, dims=({nx}, {ny}, {nz}))",
            self.spacing
        )
    }
}

/// One surface: `vertices` (V, 3) and unit outward `normals` (V, 3) float32 in Å, per-vertex
/// linear RGB `colors` (V, 3) or None when no atom colours were given, `triangles` (T, 3)
/// uint32 vertex indices wound counter-clockwise seen from outside, `area` in Å², enclosed
/// `volume` in Å³, the `grid` it was sampled on and the `engine` that computed it.
#[pyclass(frozen, module = "mdsurf", name = "Surface")]
struct Surface {
    #[pyo3(get)]
    vertices: Py<PyArray2<f32>>,
    #[pyo3(get)]
    normals: Py<PyArray2<f32>>,
    #[pyo3(get)]
    colors: Option<Py<PyArray2<f32>>>,
    #[pyo3(get)]
    triangles: Py<PyArray2<u32>>,
    #[pyo3(get)]
    area: f64,
    #[pyo3(get)]
    volume: f64,
    #[pyo3(get)]
    grid: Py<Grid>,
    #[pyo3(get)]
    engine: String,
}

#[pymethods]
impl Surface {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Surface({} vertices, {} triangles, area={:.1} Å², volume={:.1} Å³, engine='{}')",
            self.vertices.bind(py).shape()[0],
            self.triangles.bind(py).shape()[0],
            self.area,
            self.volume,
            self.engine
        )
    }
}

impl Surface {
    fn new(py: Python<'_>, out: SurfaceOutput, coloured: bool, engine: String) -> PyResult<Self> {
        let mesh = out.mesh;
        let vertices: Vec<[f32; 3]> = mesh.positions.iter().map(|v| v.to_array()).collect();
        let normals: Vec<[f32; 3]> = mesh.normals.iter().map(|v| v.to_array()).collect();
        let g = out.grid;
        Ok(Surface {
            vertices: arrays::array_f32(py, &vertices).unbind(),
            normals: arrays::array_f32(py, &normals).unbind(),
            colors: coloured.then(|| arrays::array_f32(py, &mesh.colours).unbind()),
            triangles: arrays::to_array(py, mesh.indices).unbind(),
            area: out.area,
            volume: out.volume,
            grid: Py::new(
                py,
                Grid {
                    origin: (g.origin.x, g.origin.y, g.origin.z),
                    spacing: g.spacing,
                    dims: (g.dims[0], g.dims[1], g.dims[2]),
                },
            )?,
            engine,
        })
    }
}

/// See `mdsurf.surface` (python/mdsurf/__init__.py) for the documentation.
#[pyfunction]
#[pyo3(signature = (positions, radii, colors, spacing, radius_scale, isovalue, quality, backend, vertices))]
#[allow(clippy::too_many_arguments)]
fn surface(
    py: Python<'_>,
    positions: PyReadonlyArrayDyn<'_, f32>,
    radii: PyReadonlyArrayDyn<'_, f32>,
    colors: Option<PyReadonlyArrayDyn<'_, f32>>,
    spacing: f32,
    radius_scale: f32,
    isovalue: f32,
    quality: &str,
    backend: &str,
    vertices: &str,
) -> PyResult<Surface> {
    let (params, backend, vertices) =
        settings(spacing, radius_scale, isovalue, quality, backend, vertices)?;
    let positions = arrays::positions(&positions)?;
    let radii = arrays::radii(&radii, positions.len())?;
    let colours = colors
        .map(|c| arrays::colours(&c, positions.len()))
        .transpose()?;
    let result = py.detach(|| {
        engines::with_engine(backend, vertices, |engine| {
            let atoms = AtomSet {
                positions: &positions,
                radii: &radii,
                colours: colours.as_deref(),
            };
            let name = engine.name().to_string();
            engine.compute(&atoms, &params).map(|out| (out, name))
        })
    });
    let (out, name) = result
        .map_err(PyRuntimeError::new_err)?
        .map_err(|e| surface_err("", e))?;
    Surface::new(py, out, colours.is_some(), name)
}

/// Per-frame values (areas in Å², volumes in Å³) as a float64 array.
type Measures<'py> = Bound<'py, PyArray1<f64>>;

/// See `mdsurf.measure` (python/mdsurf/__init__.py) for the documentation.
#[pyfunction]
#[pyo3(signature = (trajectory, radii, spacing, radius_scale, isovalue, quality, backend, vertices, boxes = None))]
#[allow(clippy::too_many_arguments)]
fn measure<'py>(
    py: Python<'py>,
    trajectory: PyReadonlyArrayDyn<'py, f32>,
    radii: PyReadonlyArrayDyn<'py, f32>,
    spacing: f32,
    radius_scale: f32,
    isovalue: f32,
    quality: &str,
    backend: &str,
    vertices: &str,
    boxes: Option<PyReadonlyArrayDyn<'py, f32>>,
) -> PyResult<(Measures<'py>, Measures<'py>)> {
    let (params, backend, vertices) =
        settings(spacing, radius_scale, isovalue, quality, backend, vertices)?;
    let backend = periodic_frames::backend_for(boxes.is_some(), backend, vertices)?;
    let (frames, atoms) = arrays::trajectory(&trajectory)?;
    let radii = arrays::radii(&radii, atoms)?;
    let boxes = boxes
        .map(|b| periodic_frames::boxes(&b, frames))
        .transpose()?;
    if frames == 0 {
        // Nothing to compute: no engine is chosen, so no GPU is opened.
        return Ok((PyArray1::zeros(py, 0, false), PyArray1::zeros(py, 0, false)));
    }
    let view = trajectory.as_array();
    let result = py.detach(|| {
        engines::with_engine(backend, vertices, |engine| {
            let mut area = Vec::with_capacity(frames);
            let mut volume = Vec::with_capacity(frames);
            let mut positions = Vec::with_capacity(atoms);
            let mut surfaces = FrameSurfaces::new(boxes.as_deref());
            for f in 0..frames {
                arrays::frame_into(&view, f, &mut positions);
                let atoms = AtomSet {
                    positions: &positions,
                    radii: &radii,
                    colours: None,
                };
                let out = surfaces.compute(engine, f, &atoms, &params)?;
                area.push(out.area);
                volume.push(out.volume);
            }
            Ok::<_, PyErr>((area, volume))
        })
    });
    let (area, volume) = result.map_err(PyRuntimeError::new_err)??;
    Ok((PyArray1::from_vec(py, area), PyArray1::from_vec(py, volume)))
}

/// Per-frame values and per-atom areas: area (F,) in Å², volume (F,) in Å³, each atom's share
/// of the area (F, N) in Å².
type AtomMeasures<'py> = (Measures<'py>, Measures<'py>, Bound<'py, PyArray2<f64>>);

/// Area, volume and each atom's share of the area per frame (the rule of `mdsurf surface
/// --per-atom`, docs/measure.md: a triangle's area goes a third to each vertex, a vertex's
/// share to the atoms by their Gaussians there, scaled to the surface's area); the frames of
/// `mdsurf.analysis.GaussianSurface(per_residue=True)`.
#[pyfunction]
#[pyo3(signature = (trajectory, radii, spacing, radius_scale, isovalue, quality, backend, vertices, boxes = None))]
#[allow(clippy::too_many_arguments)]
fn atom_areas<'py>(
    py: Python<'py>,
    trajectory: PyReadonlyArrayDyn<'py, f32>,
    radii: PyReadonlyArrayDyn<'py, f32>,
    spacing: f32,
    radius_scale: f32,
    isovalue: f32,
    quality: &str,
    backend: &str,
    vertices: &str,
    boxes: Option<PyReadonlyArrayDyn<'py, f32>>,
) -> PyResult<AtomMeasures<'py>> {
    let (params, backend, vertices) =
        settings(spacing, radius_scale, isovalue, quality, backend, vertices)?;
    let backend = periodic_frames::backend_for(boxes.is_some(), backend, vertices)?;
    let (frames, atoms) = arrays::trajectory(&trajectory)?;
    let radii = arrays::radii(&radii, atoms)?;
    let boxes = boxes
        .map(|b| periodic_frames::boxes(&b, frames))
        .transpose()?;
    let view = trajectory.as_array();
    let result = py.detach(|| {
        engines::with_engine(backend, vertices, |engine| {
            let (mut area, mut volume) = (Vec::with_capacity(frames), Vec::with_capacity(frames));
            let mut shares = Vec::with_capacity(frames * atoms);
            let mut positions = Vec::with_capacity(atoms);
            // The parameters the engine computes with (refined vertices run at quality max).
            let effective = engine.vertices().effective(&params);
            engine.set_keep_mesh(true);
            let mut surfaces = FrameSurfaces::new(boxes.as_deref());
            for f in 0..frames {
                arrays::frame_into(&view, f, &mut positions);
                let set = AtomSet {
                    positions: &positions,
                    radii: &radii,
                    colours: None,
                };
                let out = surfaces.compute(engine, f, &set, &params)?;
                let per_atom = mdsurf::measure::atom_areas_of(&out, &set, &effective)
                    .map_err(|e| PyRuntimeError::new_err(format!("frame {f}: {e}")))?;
                area.push(out.area);
                volume.push(out.volume);
                shares.extend(per_atom);
            }
            Ok::<_, PyErr>((area, volume, shares))
        })
    });
    let (area, volume, shares) = result.map_err(PyRuntimeError::new_err)??;
    let shares = numpy::ndarray::Array2::from_shape_vec((frames, atoms), shares)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok((
        PyArray1::from_vec(py, area),
        PyArray1::from_vec(py, volume),
        PyArray2::from_owned_array(py, shares),
    ))
}

/// The exposure table of `mdsurf.analysis.GaussianSurface(per_residue=True)`: for each residue
/// name, the largest area (Å²) of its first residues each computed alone on the CPU (the rule of
/// `mdsurf surface --per-residue`, `ExposureTable`), from `positions` (N, 3) in Å, `radii` (N,)
/// in Å, `residue_of_atom` (N,) (indices into `residue_names`, residues in topology order) and
/// the surface settings; with `box_` (3, 3), the frame's box (rows a, b, c in Å), each residue
/// is made whole in it first. Returns (names, areas).
#[pyfunction]
#[pyo3(signature = (positions, radii, residue_of_atom, residue_names, spacing, radius_scale, isovalue, quality, vertices, box_ = None))]
#[allow(clippy::too_many_arguments)]
fn exposure_table(
    py: Python<'_>,
    positions: PyReadonlyArrayDyn<'_, f32>,
    radii: PyReadonlyArrayDyn<'_, f32>,
    residue_of_atom: Vec<u32>,
    residue_names: Vec<String>,
    spacing: f32,
    radius_scale: f32,
    isovalue: f32,
    quality: &str,
    vertices: &str,
    box_: Option<PyReadonlyArrayDyn<'_, f32>>,
) -> PyResult<(Vec<String>, Vec<f64>)> {
    let cell = scene::cell_of(box_)?.and_then(|rows| PbcCell::new(&rows));
    let (params, _, vertices) =
        settings(spacing, radius_scale, isovalue, quality, "cpu", vertices)?;
    let positions = arrays::positions(&positions)?;
    let radii = arrays::radii(&radii, positions.len())?;
    if residue_of_atom.len() != positions.len() {
        return Err(PyValueError::new_err(format!(
            "residue_of_atom has {} entries for {} atoms",
            residue_of_atom.len(),
            positions.len()
        )));
    }
    let mut members = vec![Vec::new(); residue_names.len()];
    for (atom, &residue) in residue_of_atom.iter().enumerate() {
        let slot = members.get_mut(residue as usize).ok_or_else(|| {
            PyValueError::new_err(format!(
                "residue index {residue} of atom {atom} is past the {} residue names",
                residue_names.len()
            ))
        })?;
        slot.push(atom);
    }
    let set = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let effective = vertices.effective(&params);
    let table = py.detach(|| {
        ExposureTable::from_residue_members(
            &mut CpuEngine::new(),
            residue_names.into_iter().zip(members),
            &set,
            cell.as_ref(),
            &effective,
        )
    });
    let table = table.map_err(|e| PyValueError::new_err(format!("exposure table: {e}")))?;
    Ok(table.entries().map(|(n, a)| (n.to_string(), a)).unzip())
}

/// See `mdsurf.engine_info`.
#[pyfunction]
fn engine_info(py: Python<'_>, backend: &str) -> PyResult<String> {
    let backend = parse_backend(backend).map_err(PyValueError::new_err)?;
    py.detach(|| engines::describe(backend))
        .map(|(_, text)| text)
        .map_err(PyRuntimeError::new_err)
}

/// True once this process has opened (or tried to open) the GPU; a test hook for the promise
/// that importing `mdsurf` opens no device.
#[pyfunction]
fn _gpu_opened() -> bool {
    engines::gpu_opened()
}

#[pymodule]
fn _mdsurf(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Surface>()?;
    m.add_class::<Grid>()?;
    m.add_function(wrap_pyfunction!(surface, m)?)?;
    m.add_function(wrap_pyfunction!(measure, m)?)?;
    m.add_function(wrap_pyfunction!(atom_areas, m)?)?;
    m.add_function(wrap_pyfunction!(exposure_table, m)?)?;
    m.add_function(wrap_pyfunction!(engine_info, m)?)?;
    m.add_function(wrap_pyfunction!(_gpu_opened, m)?)?;
    m.add_class::<scene::SceneCore>()?;
    topology::register(m)?;
    measurements::register(m)?;
    Ok(())
}
