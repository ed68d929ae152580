//! `mdsurf._mdsurf.SceneCore`: the command line's frame path for Python callers. A topology
//! built from arrays (as the crate's readers build it: elements guessed where the file gives
//! none, radii and masses from the element table, residues as runs), the transformation chain
//! of `mdsurf surface` (whole molecules by default when the frames have a box, `--center`,
//! `--fit`, `--smooth`), and the representations of `--select`, `--state` or the defaults,
//! computed per frame by [`SceneEngine::frame`] on the CPU engine. The Python wrapper
//! (`mdsurf.Scene`, `mdsurf.analysis.GaussianSurface`) reads the frames and hands them in
//! through a callable.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use glam::Vec3;
use mdsurf::model::{Frame, RadiusOverrides, Topology};
use mdsurf::scene::defaults::default_representations;
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;
use mdsurf::scene::{RepRequest, SceneBackend, SceneEngine, SceneError};
use mdsurf::selection::{BoundSelection, Selection};
use mdsurf::surface::periodic::Replicate;
use mdsurf::surface::{CpuEngine, SurfaceEngine, SurfaceParams, VertexMode};
use mdsurf::transform::{
    FitReference, TransformChain, TransformError, TransformOptions, TransformedFrames,
};
use numpy::{PyArray1, PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::arrays;
use crate::topology::{Columns, build_topology};

/// The Python exception for a scene error: a selection that does not bind, particles that do
/// not fit the topology, or a surface input the engine refuses is a `ValueError`; a grid too
/// large a `MemoryError`; anything else a `RuntimeError`. The message is the error's one line.
pub fn scene_err(err: SceneError) -> PyErr {
    use mdsurf::surface::SurfaceError as S;
    let msg = err.to_string();
    match &err {
        SceneError::Bind(_) | SceneError::Particles { .. } => PyValueError::new_err(msg),
        SceneError::Surface { source, .. } => match source {
            S::GridTooLarge { .. } => PyMemoryError::new_err(msg),
            S::Gpu(_) => PyRuntimeError::new_err(msg),
            _ => PyValueError::new_err(msg),
        },
        SceneError::Periodic { .. } | SceneError::Exposure { .. } | SceneError::Cavities { .. } => {
            PyValueError::new_err(msg)
        }
    }
}

fn transform_err(err: TransformError) -> PyErr {
    PyValueError::new_err(err.to_string())
}

/// Runs `f` without the GIL on this process's thread pool (the CPU engine's, see `engines`), so
/// that a forked worker never waits on threads of its parent; `f` takes the GIL to read frames.
pub(crate) fn in_pool<R: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> PyResult<R> + Send,
) -> PyResult<R> {
    py.detach(|| crate::engines::on_pool(f))
        .map_err(PyRuntimeError::new_err)?
}

/// A frame could not be read (the Python reader raised) or transformed.
enum ReadError {
    Py(PyErr),
    Transform(TransformError),
}

impl From<TransformError> for ReadError {
    fn from(e: TransformError) -> Self {
        ReadError::Transform(e)
    }
}

impl From<ReadError> for PyErr {
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Py(e) => e,
            ReadError::Transform(e) => transform_err(e),
        }
    }
}

/// A (3, 3) box (rows a, b, c in Å), or `None` for no box (absent, or all zero).
pub(crate) fn cell_of(cell: Option<PyReadonlyArrayDyn<'_, f32>>) -> PyResult<Option<[Vec3; 3]>> {
    let Some(cell) = cell else {
        return Ok(None);
    };
    if cell.shape() != [3, 3] {
        return Err(PyValueError::new_err(format!(
            "a box must be a (3, 3) array of edge vectors, got shape {:?}",
            cell.shape()
        )));
    }
    let a = cell.as_array();
    let row = |i: usize| Vec3::new(a[[i, 0]], a[[i, 1]], a[[i, 2]]);
    let rows = [row(0), row(1), row(2)];
    if rows.iter().all(|r| *r == Vec3::ZERO) {
        return Ok(None);
    }
    Ok(Some(rows))
}

/// Frame `index` from the Python reader: `reader(index)` returns `(positions (N, 3) float32,
/// box (3, 3) float32 or None, time in ps or None)`.
fn read_frame(reader: &Py<PyAny>, index: usize, atoms: usize) -> PyResult<Frame> {
    Python::attach(|py| read_frame_with(reader.bind(py), index, atoms))
}

fn read_frame_with(reader: &Bound<'_, PyAny>, index: usize, atoms: usize) -> PyResult<Frame> {
    let got = reader.call1((index,))?;
    let (positions, cell, time): (
        PyReadonlyArrayDyn<'_, f32>,
        Option<PyReadonlyArrayDyn<'_, f32>>,
        Option<f64>,
    ) = got.extract()?;
    let positions = arrays::positions(&positions)?;
    if positions.len() != atoms {
        return Err(PyValueError::new_err(format!(
            "frame {index} has {} atoms but the topology has {atoms}",
            positions.len()
        )));
    }
    Ok(Frame {
        index,
        time_ps: time,
        positions,
        cell: cell_of(cell)?,
    })
}

/// The engine in `slot`, reached through `&mut` without locking (a panic while it was held
/// left it as it was; the engine checks its own state per frame).
pub(crate) fn engine_mut(slot: &mut Mutex<SceneEngine>) -> &mut SceneEngine {
    slot.get_mut().unwrap_or_else(PoisonError::into_inner)
}

/// One representation's numbers in one frame.
type RepRow = (
    String,
    String,
    f64,
    f64,
    usize,
    (u32, u32, u32),
    usize,
    usize,
);

/// See the module documentation; `mdsurf.Scene` documents the arguments.
#[pyclass(module = "mdsurf._mdsurf", name = "SceneCore")]
pub struct SceneCore {
    pub(crate) topology: Topology,
    /// The engine of `frame`. In a mutex only so that the class is `Sync`, as Python may drop a
    /// scene on any thread; `&mut self` reaches it without locking ([`engine_mut`]).
    engine: Mutex<SceneEngine>,
    /// A second engine that keeps meshes, for the measurements of `crate::measurements` (the main
    /// one only measures area and volume, as `mdsurf surface` without mesh outputs).
    pub(crate) meshes: Mutex<SceneEngine>,
    frames: TransformedFrames,
    pub(crate) reps: Vec<RepRequest>,
    /// The scene's surface parameters (those of `select` and `--interface`).
    pub(crate) params: SurfaceParams,
    /// Selections bound for [`SceneCore::transformed`], by text.
    selections: HashMap<String, BoundSelection>,
    summary: String,
}

#[pymethods]
impl SceneCore {
    #[new]
    #[pyo3(signature = (
        columns, first, first_box, n_frames, reader, select = None, state = None,
        spacing = 1.0, radius_scale = 1.0, isovalue = 0.5, quality = "medium", vertices = None,
        whole = None, center = None, fit = None, smooth = 0, periodic = false, replicate = None,
        file = "", surfaces = true
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        columns: Columns,
        first: PyReadonlyArrayDyn<'_, f32>,
        first_box: Option<PyReadonlyArrayDyn<'_, f32>>,
        n_frames: usize,
        reader: &Bound<'_, PyAny>,
        select: Option<String>,
        state: Option<String>,
        spacing: f32,
        radius_scale: f32,
        isovalue: f32,
        quality: &str,
        vertices: Option<&str>,
        whole: Option<bool>,
        center: Option<String>,
        fit: Option<String>,
        smooth: usize,
        periodic: bool,
        replicate: Option<[u32; 3]>,
        file: &str,
        surfaces: bool,
    ) -> PyResult<Self> {
        if select.is_some() && state.is_some() {
            return Err(PyValueError::new_err(
                "give select or state, not both (as --select and --state)",
            ));
        }
        let params = SurfaceParams {
            spacing,
            radius_scale,
            isovalue,
            quality: quality.parse().map_err(PyValueError::new_err)?,
        };
        params.validate().map_err(|e| crate::surface_err("", e))?;
        let vertices: Option<VertexMode> = vertices
            .map(|v| v.parse().map_err(PyValueError::new_err))
            .transpose()?;
        let state = state
            .map(|p| {
                StateFile::load(std::path::Path::new(&p))
                    .map_err(|e| PyValueError::new_err(e.to_string()))
            })
            .transpose()?;
        let first_positions = arrays::positions(&first)?;
        let raw_first = Frame {
            index: 0,
            time_ps: None,
            positions: first_positions,
            cell: cell_of(first_box)?,
        };
        let reader = reader.clone().unbind();
        let file = file.to_string();
        // Everything that may run on threads runs on this process's pool (see `engines`).
        in_pool(py, move || {
            let file = file.as_str();
            let topology = build_topology(columns, &raw_first.positions)?;
            // The options as `TransformArgs::options` makes them: a state file's when no
            // transformation is asked for.
            let asked = whole.is_some()
                || center.is_some()
                || fit.is_some()
                || smooth > 0
                || periodic
                || replicate.is_some();
            let options = match &state {
                Some(s) if !asked => s.trajectory.transforms(),
                _ => TransformOptions {
                    whole,
                    center,
                    fit,
                    fit_reference: FitReference::First,
                    smooth,
                    periodic: periodic || replicate.is_some(),
                    replicate: replicate.map(Replicate).unwrap_or_default(),
                },
            };
            let chain = TransformChain::new(&options, &topology, &raw_first, None, file)
                .map_err(transform_err)?;
            let summary = chain.summary();
            let periodic = chain.periodic();
            let mut frames = TransformedFrames::new(chain, n_frames.max(1));
            let atoms = topology.len();
            let first = frames
                .read(0, |i| {
                    if i == 0 {
                        Ok(raw_first.clone())
                    } else {
                        read_frame(&reader, i, atoms).map_err(ReadError::Py)
                    }
                })
                .map_err(PyErr::from)?;

            // The representations, as `SceneArgs::representations` picks them.
            let mut base = Representation::new("selection", "all", RepStyle::Surface);
            base.set_params(&params);
            let from_state = state.is_some();
            let mut reps = if !surfaces {
                Vec::new()
            } else if let Some(state) = state {
                state.representations
            } else if let Some(expr) = select {
                let rep = Representation {
                    selection: expr,
                    ..base
                };
                rep.validate()
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                vec![rep]
            } else {
                default_representations(&topology, &first, &base)
            };
            if !from_state || vertices.is_some() {
                for rep in &mut reps {
                    rep.vertices = vertices.unwrap_or_default();
                }
            }
            reps.retain(|r| r.style.is_surface() && r.visible);
            let requests: Vec<RepRequest> = reps
                .into_iter()
                .enumerate()
                .map(|(id, rep)| RepRequest { id: id as u64, rep })
                .collect();

            let scene_engine = |keep_mesh: bool| {
                let mut cpu = CpuEngine::new();
                cpu.set_keep_mesh(keep_mesh);
                let mut engine = SceneEngine::new(SceneBackend::Host(Box::new(cpu)));
                engine.set_periodic(periodic);
                engine.reset(&topology, &RadiusOverrides::default());
                engine.bind(&topology, &requests).map_err(scene_err)?;
                Ok::<_, PyErr>(engine)
            };
            let engine = scene_engine(false)?;
            let meshes = scene_engine(true)?;
            if surfaces && requests.is_empty() {
                return Err(PyValueError::new_err(
                    "no visible surface representation to compute (the state file hides them all)",
                ));
            }
            for RepRequest { id, rep } in &requests {
                if let Some(layer) = engine.layer(*id)
                    && !layer.is_dynamic()
                    && layer.atoms(&first).is_empty()
                {
                    return Err(PyValueError::new_err(format!(
                        "{file}: selection '{}' of representation '{}' matches no atom",
                        rep.selection, rep.name
                    )));
                }
            }
            Ok(SceneCore {
                topology,
                engine: Mutex::new(engine),
                meshes: Mutex::new(meshes),
                frames,
                reps: requests,
                params,
                selections: HashMap::new(),
                summary,
            })
        })
    }

    /// The visible surface representations: (name, selection) in order.
    fn representations(&self) -> Vec<(String, String)> {
        self.reps
            .iter()
            .map(|r| (r.rep.name.clone(), r.rep.selection.clone()))
            .collect()
    }

    /// What the transformation chain does, e.g. `whole (bonds guessed from distances)`.
    #[getter]
    fn transforms(&self) -> String {
        self.summary.clone()
    }

    /// Number of atoms.
    #[getter]
    fn n_atoms(&self) -> usize {
        self.topology.len()
    }

    /// Radius of every atom in Å, as the command line assigns them.
    fn radii<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.topology.radii)
    }

    /// Element of every atom (given, else guessed; empty for beads and unknown particles).
    fn elements(&self) -> Vec<String> {
        self.topology.elements.to_strings()
    }

    /// Mass of every atom in amu (given, else from the element).
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.topology.masses)
    }

    /// Frame `index` through the transformations and every representation: a list of
    /// (name, selection, area Å², volume Å³, atoms, grid dims, vertices, triangles), and the
    /// frame's time in ps.
    fn frame(
        &mut self,
        py: Python<'_>,
        index: usize,
        reader: Py<PyAny>,
    ) -> PyResult<(Vec<RepRow>, Option<f64>)> {
        let this = &mut *self;
        in_pool(py, || {
            let frame = Arc::new(this.read(index, &reader)?);
            let computed = engine_mut(&mut this.engine)
                .frame(&this.topology, index, &frame, &this.reps)
                .map_err(scene_err)?;
            let rows = computed
                .layers
                .iter()
                .map(|l| {
                    let o = &l.output;
                    (
                        l.rep.name.clone(),
                        l.rep.selection.clone(),
                        o.area,
                        o.volume,
                        l.particles.positions.len(),
                        (o.grid.dims[0], o.grid.dims[1], o.grid.dims[2]),
                        o.vertex_count(),
                        o.triangle_count(),
                    )
                })
                .collect();
            Ok((rows, frame.time_ps))
        })
    }

    /// Frame `index` through the transformations: positions (N, 3) float32 in Å, when
    /// `selection` is given the indices of the atoms it picks in that frame (uint32), and the
    /// frame's box after the transformations ((3, 3) float32, rows a, b, c in Å; `None`
    /// without one).
    #[pyo3(signature = (index, reader, selection = None))]
    #[allow(clippy::type_complexity)]
    fn transformed<'py>(
        &mut self,
        py: Python<'py>,
        index: usize,
        reader: Py<PyAny>,
        selection: Option<&str>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Option<Bound<'py, PyArray1<u32>>>,
        Option<Bound<'py, PyArray2<f32>>>,
    )> {
        let this = &mut *self;
        let (frame, indices) = in_pool(py, || {
            let frame = this.read(index, &reader)?;
            let indices = selection
                .map(|text| this.bound(text).map(|b| b.indices(&frame)))
                .transpose()?;
            Ok((frame, indices))
        })?;
        let rows: Vec<[f32; 3]> = frame.positions.iter().map(|p| p.to_array()).collect();
        let indices = indices.map(|i| PyArray1::from_vec(py, i));
        let cell = frame
            .cell
            .map(|rows| arrays::array_f32(py, &rows.map(|r| r.to_array())));
        Ok((arrays::array_f32(py, &rows), indices, cell))
    }

    /// Checks that `selection` parses (a `ValueError` naming it otherwise) and whether it
    /// depends on positions.
    fn check_selection(&mut self, py: Python<'_>, selection: &str) -> PyResult<bool> {
        let this = &mut *self;
        in_pool(py, || Ok(this.bound(selection)?.is_dynamic()))
    }
}

impl SceneCore {
    /// Frame `index` through the transformations (`reader` as for [`SceneCore::frame`]).
    pub(crate) fn read(&mut self, index: usize, reader: &Py<PyAny>) -> PyResult<Frame> {
        let atoms = self.topology.len();
        self.frames
            .read(index, |i| {
                read_frame(reader, i, atoms).map_err(ReadError::Py)
            })
            .map_err(PyErr::from)
    }

    fn bound(&mut self, text: &str) -> PyResult<&BoundSelection> {
        if !self.selections.contains_key(text) {
            let sel = Selection::parse(text)
                .map_err(|e| PyValueError::new_err(format!("selection '{text}': {e}")))?;
            self.selections
                .insert(text.to_string(), sel.bind(&self.topology));
        }
        Ok(&self.selections[text])
    }
}
