//! What the scene engine ([`super::engine::SceneEngine`]) hands back for one frame: one
//! [`LayerResult`] per visible representation (its particles, its surface as a host mesh or as
//! GPU buffers, area and volume), in drawing order, and the [`SceneError`] that says which
//! frame and representation failed. The window, `render`, `surface` and `bench --viewer` all read
//! frames in this form.

use std::sync::Arc;

use glam::Vec3;

use super::cavity_layer::CavityLayer;
use super::layer::LayerError;
use super::representation::Representation;
use crate::gpu::{GpuSurface, Work};
use crate::measure::MeasureError;
use crate::surface::SurfaceError;
use crate::surface::SurfaceOutput;
use crate::surface::periodic::PeriodicError;

/// Identity of a representation for the life of a scene engine: slots and GPU engines are kept
/// per id, so reordering or renaming representations recomputes nothing.
pub type RepId = u64;

/// A representation as the scene engine gets it: its stable id and the representation.
#[derive(Debug, Clone, PartialEq)]
pub struct RepRequest {
    /// Stable identity of the representation.
    pub id: RepId,
    /// The representation (hidden ones are not computed).
    pub rep: Representation,
}

/// Particles of one computed representation, for drawing atoms or beads.
#[derive(Debug, Clone)]
pub struct ParticleData {
    /// Positions in Å.
    pub positions: Vec<Vec3>,
    /// Radii in Å: this frame's, or, for a GPU surface whose radii follow exposure, the
    /// particles' own (the engine applied the exposure on the device, [`crate::gpu::exposure`]).
    pub radii: Arc<Vec<f32>>,
    /// Linear RGB colours.
    pub colours: Arc<Vec<[f32; 3]>>,
    /// Bonds between particles (file bonds or guessed; empty for beads and surfaces).
    pub bonds: Arc<Vec<[u32; 2]>>,
}

/// One representation of a computed frame.
#[derive(Debug, Clone)]
pub struct LayerResult {
    /// The representation's id ([`RepRequest::id`]).
    pub id: RepId,
    /// The representation as it was computed.
    pub rep: Representation,
    /// Mesh, area, volume, stage times (empty for atom styles). With the GPU engine the mesh is
    /// empty: the surface is in [`LayerResult::gpu_surface`].
    pub output: SurfaceOutput,
    /// The GPU engine's surface buffers (drawn in place), when the GPU engine computed it.
    pub gpu_surface: Option<GpuSurface>,
    /// The particles the surface or atoms were built from.
    pub particles: ParticleData,
    /// True when the particles are residue beads.
    pub beads: bool,
    /// Which stages the GPU engine ran for this representation (its last submit; `None` for
    /// host engines or a reused result). An isovalue change alone gives [`Work::Mc`].
    pub gpu_work: Option<Work>,
    /// True when this result was reused from an earlier frame request (nothing recomputed).
    pub reused: bool,
    /// Wall-clock time spent on this representation in ms: its particles and its surface
    /// (submit and collect on the GPU), and its cavities when found.
    pub compute_ms: f64,
    /// True when the surface's mesh is closed (every engine's but the periodic one's, whose
    /// meshes are open at the cell faces): the renderer may cull its back faces.
    pub closed: bool,
    /// The surface's cavities, when the representation's `cavities` switch is on (`None`
    /// otherwise, for atom styles, and for a host surface whose mesh was not kept).
    pub cavities: Option<Arc<CavityLayer>>,
}

impl LayerResult {
    /// The parameters the surface was computed with, which measurements on it take: refined
    /// vertices run at quality max ([`crate::surface::VertexMode::effective`]); the periodic
    /// engine interpolates, with the representation's own.
    pub fn measured_params(&self) -> crate::surface::SurfaceParams {
        let params = self.rep.params();
        match self.output.periodic {
            Some(_) => params,
            None => self.rep.vertices.effective(&params),
        }
    }

    /// Triangles of the surface (from the GPU counters when the mesh stayed on the GPU).
    pub fn triangle_count(&self) -> usize {
        match &self.gpu_surface {
            Some(g) => g.stats.map_or(0, |s| s.triangle_count as usize),
            None => self.output.triangle_count(),
        }
    }

    /// True for surface representations.
    pub fn is_surface(&self) -> bool {
        self.rep.style.is_surface()
    }
}

/// Every visible representation of one frame.
#[derive(Debug, Clone)]
pub struct SceneFrame {
    /// Frame index.
    pub frame: usize,
    /// Simulation time in ps, when known.
    pub time_ps: Option<f64>,
    /// GPU memory the scene's surface engines hold after this frame, in bytes (0 on the host
    /// engines).
    pub gpu_bytes: u64,
    /// The visible representations, in the order they were asked for (shared with the
    /// engine's slots: a reused result is not copied).
    pub layers: Vec<Arc<LayerResult>>,
}

impl SceneFrame {
    /// The surface representations.
    pub fn surfaces(&self) -> impl Iterator<Item = &LayerResult> {
        self.layers
            .iter()
            .map(Arc::as_ref)
            .filter(|l| l.is_surface())
    }

    /// The result of representation `id`, when it is visible.
    pub fn layer(&self, id: RepId) -> Option<&LayerResult> {
        self.layers.iter().map(Arc::as_ref).find(|l| l.id == id)
    }
}

/// Why a frame of a scene could not be computed. Each prints as one line naming the frame and,
/// where one is at fault, the representation; callers add the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A representation could not be bound to the topology (its selection does not parse or
    /// bind); the message names the representation.
    #[error(transparent)]
    Bind(LayerError),
    /// The particles of a representation could not be made from the frame.
    #[error("frame {frame}: {source}")]
    Particles {
        /// Frame index.
        frame: usize,
        /// What went wrong (names the representation).
        source: LayerError,
    },
    /// A surface engine failed (CPU or GPU: both report [`SurfaceError`]).
    #[error("frame {frame}: representation '{rep}': {source}")]
    Surface {
        /// Frame index.
        frame: usize,
        /// Representation name.
        rep: String,
        /// What went wrong.
        source: SurfaceError,
    },
    /// The periodic engine failed (no box, a box it cannot use, or the surface itself).
    #[error("frame {frame}: representation '{rep}': {source}")]
    Periodic {
        /// Frame index.
        frame: usize,
        /// Representation name.
        rep: String,
        /// What went wrong.
        source: PeriodicError,
    },
    /// A surface's exposure colours could not be computed.
    #[error("frame {frame}: representation '{rep}': exposure colours: {source}")]
    Exposure {
        /// Frame index.
        frame: usize,
        /// Representation name.
        rep: String,
        /// What went wrong.
        source: MeasureError,
    },
    /// A surface's cavities could not be found.
    #[error("frame {frame}: representation '{rep}': cavities: {source}")]
    Cavities {
        /// Frame index.
        frame: usize,
        /// Representation name.
        rep: String,
        /// What went wrong.
        source: MeasureError,
    },
}

impl SceneError {
    /// The frame the error is about, when it is about one.
    pub fn frame(&self) -> Option<usize> {
        match self {
            SceneError::Bind(_) => None,
            SceneError::Particles { frame, .. }
            | SceneError::Surface { frame, .. }
            | SceneError::Periodic { frame, .. }
            | SceneError::Exposure { frame, .. }
            | SceneError::Cavities { frame, .. } => Some(*frame),
        }
    }
}
