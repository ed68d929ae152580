//! The GPU side of the scene engine: collecting a submitted surface, the second (colour-only)
//! pass of exposure colours, each representation's engine (the main one or a sibling on the
//! same device), the meshes read back, and the GPU memory the engines hold.

use std::sync::Arc;

use super::{SceneBackend, SceneEngine};
use crate::gpu::{Changes, FrameStats, GpuEngine, GpuSurface};
use crate::model::Topology;
use crate::scene::exposure::{ColouredSurface, ExposureRequest, exposure_failed};
use crate::scene::frame::{LayerResult, RepId, SceneError, SceneFrame};
use crate::surface::{AtomSet, Mesh, SurfaceEngine, SurfaceError};

impl SceneEngine {
    /// Collects GPU frame `frame` of representation `id` (scene frame `index`, computed from
    /// `result`'s particles): its counters and its surface buffers.
    pub(super) fn finish_gpu(
        &mut self,
        id: RepId,
        (index, frame): (usize, u64),
        result: &LayerResult,
    ) -> Result<(FrameStats, GpuSurface), SceneError> {
        let p = &result.particles;
        let atoms = AtomSet {
            positions: &p.positions,
            radii: &p.radii,
            colours: Some(&p.colours),
        };
        let params = result.rep.params();
        let finished = match self.gpu_engine_of(id) {
            Some(e) => e.finish(frame, &atoms, &params).map(|stats| {
                let mut surface = e.surface();
                surface.stats = Some(stats);
                (stats, surface)
            }),
            None => Err(engine_gone()),
        };
        finished.map_err(|source| SceneError::Surface {
            frame: index,
            rep: result.rep.name.clone(),
            source,
        })
    }

    /// Gives the GPU surface of `result` (its counters `stats`) the exposure colours of
    /// `request`: reads its mesh back, computes the colours of its atoms, stores them in
    /// `result`'s particles and submits the colour pass again. Returns the engine's frame
    /// number to collect.
    pub(super) fn colour_by_exposure(
        &mut self,
        topology: &Topology,
        index: usize,
        result: &mut LayerResult,
        stats: &FrameStats,
        request: ExposureRequest,
    ) -> Result<u64, SceneError> {
        let ExposureRequest { map, subset, cell } = request;
        let id = result.id;
        let rep = result.rep.clone();
        let surface_failed = |source| SceneError::Surface {
            frame: index,
            rep: rep.name.clone(),
            source,
        };
        let e = self
            .gpu_engine_of(id)
            .ok_or_else(|| surface_failed(engine_gone()))?;
        let mesh = e
            .read_mesh(stats)
            .map_err(|err| surface_failed(SurfaceError::Gpu(err.to_string())))?;
        let params = e.vertices().effective(&rep.params());
        let Some(slot) = self.slots.get_mut(&id) else {
            return Err(surface_failed(engine_gone()));
        };
        let p = &result.particles;
        let atoms = AtomSet {
            positions: &p.positions,
            radii: &p.radii,
            colours: None,
        };
        let colours = slot
            .exposure
            .colours(
                topology,
                subset.as_deref(),
                &atoms,
                &params,
                ColouredSurface {
                    mesh: &mesh,
                    area: stats.area,
                    seams: None,
                    cell,
                },
                map,
            )
            .map_err(exposure_failed(index, &rep.name))?;
        let colours = Arc::new(colours);
        if let Some(sent) = slot.sent.as_mut() {
            sent.colours = colours.clone();
        }
        result.particles.colours = colours;
        let p = &result.particles;
        let coloured = AtomSet {
            positions: &p.positions,
            radii: &p.radii,
            colours: Some(&p.colours),
        };
        let e = self
            .gpu_engine_of(id)
            .ok_or_else(|| surface_failed(engine_gone()))?;
        let only_colours = Changes {
            positions: false,
            radii: false,
            colours: true,
        };
        let info = e
            .submit(&coloured, &rep.params(), only_colours)
            .map_err(surface_failed)?;
        Ok(info.frame)
    }

    /// The GPU engine of representation `id`, when the backend is the GPU.
    pub(super) fn gpu_engine_of(&mut self, id: RepId) -> Option<&mut GpuEngine> {
        let SceneBackend::Gpu(main) = &mut self.backend else {
            return None;
        };
        if self.main_owner == Some(id) {
            Some(main.as_mut())
        } else {
            self.slots.get_mut(&id)?.gpu.as_deref_mut()
        }
    }

    /// Tells each GPU engine behind a surface of `shown` (about to be drawn) that its output
    /// set is on screen, so that no later frame writes it, even one that fails.
    pub fn hold_shown(&mut self, shown: &SceneFrame) {
        for layer in shown.layers.iter().filter(|l| l.gpu_surface.is_some()) {
            if let Some(e) = self.gpu_engine_of(layer.id) {
                e.hold_output_set();
            }
        }
    }

    /// The triangles of `layer` (a result of this engine's last frame) on the host: its mesh,
    /// or the GPU engine's buffers read back.
    pub fn read_mesh(&mut self, index: usize, layer: &LayerResult) -> Result<Mesh, SceneError> {
        let stats = match &layer.gpu_surface {
            Some(g) => g.stats,
            None => return Ok(layer.output.mesh.clone()),
        };
        let failed = |source| SceneError::Surface {
            frame: index,
            rep: layer.rep.name.clone(),
            source,
        };
        let stats =
            stats.ok_or_else(|| failed(SurfaceError::Gpu("the surface has no counters".into())))?;
        match self.gpu_engine_of(layer.id) {
            Some(e) => e
                .read_mesh(&stats)
                .map_err(|e| failed(SurfaceError::Gpu(e.to_string()))),
            None => Err(failed(engine_gone())),
        }
    }

    /// GPU memory the scene's engines hold, in bytes (0 on the host engines).
    pub fn gpu_bytes(&self) -> u64 {
        let main = match &self.backend {
            SceneBackend::Gpu(e) => e.gpu_bytes(),
            SceneBackend::Host(_) => 0,
        };
        let siblings: u64 = self
            .slots
            .values()
            .filter_map(|s| s.gpu.as_ref().map(|e| e.gpu_bytes()))
            .sum();
        main + siblings
    }
}

/// The error of a representation whose GPU engine was dropped under it.
pub(super) fn engine_gone() -> SurfaceError {
    SurfaceError::Gpu("the representation's GPU engine is gone".into())
}

/// A new GPU engine on the same device as `engine` (for a further surface representation).
pub(super) fn sibling_of(engine: &GpuEngine) -> Box<GpuEngine> {
    let ctx = engine.context();
    Box::new(GpuEngine::from_device(
        ctx.device.clone(),
        ctx.queue.clone(),
    ))
}
