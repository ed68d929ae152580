//! The scene engine: the one frame path from a transformed frame to every representation's
//! particles and surface, used by the viewer's worker, `render`, `surface` and
//! `bench --viewer`. Each of those keeps only its own loop (latest-wins thread, frame range,
//! writers, images) around [`SceneEngine::frame`].
//!
//! Each representation keeps a slot between frames: its bound selection ([`Layer`]), its own
//! GPU engine (the first surface uses the main one; the others get siblings on the same
//! device, so every surface keeps its own buffers), its last result, and what its engine was
//! last sent. A representation whose inputs did not change (same frame, selection, style,
//! colours and parameters) reuses its last result; a GPU engine is told only what changed
//! since its last frame (frame, radii, colours; it compares the parameters itself), so an
//! isovalue change re-runs only Marching Cubes and a colour scheme only the colour pass.
//!
//! On the GPU every surface is submitted first (one submit each), then the counters are
//! collected in the same order; a surface that overflowed its buffers is re-run by
//! [`GpuEngine::finish`]. The mesh stays in the engine's buffers ([`LayerResult::gpu_surface`]);
//! [`SceneEngine::read_mesh`] brings it back when a caller needs the triangles. Periodic
//! surfaces (`--periodic`) come from the CPU periodic engine whatever the backend.
//!
//! On the GPU, radii that follow exposure (the SES preset) are counted by the engine
//! ([`crate::gpu::exposure`]): the layer skips its host pass and the result's particles keep
//! their own radii, unless cavities, exposure colours or periodic surfaces need the frame's.
//!
//! A surface coloured by exposure ([`ColorScheme::Exposure`]) takes a second pass once its
//! first gives the areas: see [`super::exposure`].
//!
//! [`gpu`] holds the GPU side: collecting a submit, exposure's colour-only pass, each
//! representation's engine, meshes read back.

use std::collections::HashMap;
use std::collections::hash_map::Entry as MapEntry;
use std::sync::Arc;
use std::time::Instant;

mod gpu;
use gpu::sibling_of;

use super::cavity_layer::CavitySource;
use super::exposure::{
    ColouredSurface, ExposureColouring, ExposureRequest, exposure_failed, exposure_map,
    host_surface,
};
use super::frame::{LayerResult, ParticleData, RepId, RepRequest, SceneError, SceneFrame};
use super::layer::{Layer, LayerFrame};
use super::representation::Representation;
use crate::gpu::exposure::runs_on_gpu;
use crate::gpu::{Changes, GpuEngine, Work};
use crate::model::pbc::PbcCell;
use crate::model::{Frame, RadiusOverrides, Topology};
use crate::surface::periodic::PeriodicEngine;
use crate::surface::{Mesh, MeshCounts, SurfaceEngine, SurfaceOutput};
use crate::transform::Replicate;

/// The engine a scene computes its surfaces with.
pub enum SceneBackend {
    /// Any engine through [`SurfaceEngine::compute`] (the mesh comes back to the host); one
    /// engine serves every representation.
    Host(Box<dyn SurfaceEngine + Send>),
    /// The GPU engine: the mesh stays in its buffers. Each further surface representation gets
    /// its own engine on the same device.
    Gpu(Box<GpuEngine>),
}

impl SceneBackend {
    /// Name of the engine (`cpu`, `gpu`).
    pub fn name(&self) -> &str {
        match self {
            SceneBackend::Host(e) => e.name(),
            SceneBackend::Gpu(e) => e.name(),
        }
    }
}

/// What one representation keeps between frames.
struct RepSlot {
    /// The bound selection and its particles.
    layer: Layer,
    /// Its own GPU engine (GPU backend only; the first surface uses the main engine).
    gpu: Option<Box<GpuEngine>>,
    /// The frame index and result of its last successful frame (shared, not copied).
    last: Option<(usize, Arc<LayerResult>)>,
    /// What its engine's last frame was computed from, to send only what changed since.
    sent: Option<Sent>,
    /// Its exposure colours' table (kept from the first frame coloured by exposure).
    exposure: ExposureColouring,
}

/// Inputs of an engine's last successful frame.
struct Sent {
    /// Frame index: positions follow from it and the particles.
    frame: usize,
    /// Which atoms the particles were (`None`: all) and whether they were beads.
    atoms: (Option<Vec<u32>>, bool),
    radii: Arc<Vec<f32>>,
    colours: Arc<Vec<[f32; 3]>>,
}

/// Which atoms `lf`'s particles come from, and whether they are beads.
fn atoms_key(lf: &LayerFrame) -> (Option<Vec<u32>>, bool) {
    (
        lf.particles.subset().map(<[u32]>::to_vec),
        lf.particles.is_beads(),
    )
}

impl Sent {
    /// What differs between this and the next frame's inputs (the surface parameters are
    /// compared by the engine itself).
    fn changes(&self, frame: usize, lf: &LayerFrame, data: &ParticleData) -> Changes {
        let same_atoms = !lf.rebuilt || self.atoms == atoms_key(lf);
        Changes {
            positions: self.frame != frame || !same_atoms,
            radii: !Arc::ptr_eq(&self.radii, &data.radii) && self.radii != data.radii,
            colours: !Arc::ptr_eq(&self.colours, &data.colours) && self.colours != data.colours,
        }
    }
}

/// The parts of a representation that change what is computed (not its name, opacity or
/// visibility, which only change how it is drawn).
fn compute_key(rep: &Representation) -> impl PartialEq + '_ {
    (
        &rep.selection,
        rep.style,
        rep.colour,
        rep.style
            .is_surface()
            .then(|| (rep.params(), rep.vertices, rep.cavities, rep.cavity_probe)),
    )
}

/// A surface submitted to a GPU engine whose counters are not collected yet.
struct Submitted {
    /// The engine's frame number.
    frame: u64,
    /// Which stages the submit ran.
    work: Work,
    /// Exposure colours to give the surface once it is collected.
    exposure: Option<ExposureRequest>,
}

/// A representation's result while a frame is computed: reused as it was, or new (with a GPU
/// submit still to collect).
enum Entry {
    Reused(Arc<LayerResult>),
    New(Box<LayerResult>, Option<Submitted>, Option<CavitySource>),
}

/// Computes the representations of frames; see the module documentation.
pub struct SceneEngine {
    backend: SceneBackend,
    slots: HashMap<RepId, RepSlot>,
    /// The representation computing on the main GPU engine.
    main_owner: Option<RepId>,
    /// The CPU engine of periodic surfaces, whatever the backend.
    periodic: PeriodicEngine,
    /// The images shown when surfaces are periodic.
    replicate: Option<Replicate>,
    radius_overrides: RadiusOverrides,
}

impl SceneEngine {
    /// A scene computing its surfaces with `backend`, not periodic, with no radius overrides.
    pub fn new(backend: SceneBackend) -> SceneEngine {
        SceneEngine {
            backend,
            slots: HashMap::new(),
            main_owner: None,
            periodic: PeriodicEngine::default(),
            replicate: None,
            radius_overrides: RadiusOverrides::default(),
        }
    }

    /// Name of the engine for messages (`cpu`, `gpu`, `cpu (periodic)`).
    pub fn name(&self) -> &str {
        match self.replicate {
            Some(_) => "cpu (periodic)",
            None => self.backend.name(),
        }
    }

    /// The backend (for settings such as the host engine's vertex mode or mesh keeping).
    pub fn backend_mut(&mut self) -> &mut SceneBackend {
        &mut self.backend
    }

    /// The images shown when surfaces are periodic, `None` when they are not.
    pub fn periodic(&self) -> Option<Replicate> {
        self.replicate
    }

    /// Makes surfaces periodic with `replicate` images (the CPU periodic engine), or not.
    pub fn set_periodic(&mut self, replicate: Option<Replicate>) {
        if self.replicate != replicate {
            self.replicate = replicate;
            self.forget_results();
        }
    }

    /// Starts over on a new system, or with other radius overrides: every representation is
    /// bound again to `topology` (those that no longer bind are dropped) and no result is
    /// reused. The GPU engines are kept (they are expensive to build).
    pub fn reset(&mut self, topology: &Topology, radius_overrides: &RadiusOverrides) {
        self.radius_overrides = radius_overrides.clone();
        self.forget_results();
        self.slots.retain(|_, s| {
            match Layer::new(s.layer.rep().clone(), topology, radius_overrides) {
                Ok(layer) => {
                    s.layer = layer;
                    true
                }
                Err(_) => false,
            }
        });
    }

    fn forget_results(&mut self) {
        for slot in self.slots.values_mut() {
            slot.last = None;
            slot.sent = None;
        }
    }

    /// Binds `reps` to `topology` now (the first [`SceneEngine::frame`] would), so that a
    /// caller can check them before any frame is computed; forgets representations not in
    /// `reps`.
    pub fn bind(&mut self, topology: &Topology, reps: &[RepRequest]) -> Result<(), SceneError> {
        self.retain(reps);
        for RepRequest { id, rep } in reps {
            slot_of(&mut self.slots, &self.radius_overrides, topology, *id, rep)?;
        }
        Ok(())
    }

    /// The bound selection of representation `id`, once bound.
    pub fn layer(&self, id: RepId) -> Option<&Layer> {
        self.slots.get(&id).map(|s| &s.layer)
    }

    /// Forgets representations that are not in `reps` (their GPU engines are dropped).
    fn retain(&mut self, reps: &[RepRequest]) {
        self.slots.retain(|id, _| reps.iter().any(|r| r.id == *id));
        if self
            .main_owner
            .is_some_and(|id| !self.slots.contains_key(&id))
        {
            self.main_owner = None;
        }
    }

    /// Computes frame `index` (`frame`, already transformed) for every visible representation
    /// of `reps`, in their order; representations not in `reps` are forgotten.
    pub fn frame(
        &mut self,
        topology: &Topology,
        index: usize,
        frame: &Arc<Frame>,
        reps: &[RepRequest],
    ) -> Result<SceneFrame, SceneError> {
        self.retain(reps);
        // First every representation: host surfaces computed, GPU surfaces only submitted.
        let mut entries = Vec::with_capacity(reps.len());
        for RepRequest { id, rep } in reps.iter().filter(|r| r.rep.visible) {
            entries.push(self.start(topology, index, frame, *id, rep)?);
        }
        // Then the GPU counters, in the same order; each result is kept for reuse.
        let mut layers = Vec::with_capacity(entries.len());
        for entry in entries {
            let result = match entry {
                Entry::Reused(r) => r,
                Entry::New(r, submitted, cavities) => {
                    self.collect(topology, index, *r, submitted, cavities)?
                }
            };
            layers.push(result);
        }
        Ok(SceneFrame {
            frame: index,
            time_ps: frame.time_ps,
            gpu_bytes: self.gpu_bytes(),
            layers,
        })
    }

    /// Starts representation `id` on frame `index`: reused, computed on the host, or submitted
    /// to its GPU engine.
    fn start(
        &mut self,
        topology: &Topology,
        index: usize,
        frame: &Frame,
        id: RepId,
        rep: &Representation,
    ) -> Result<Entry, SceneError> {
        let started = Instant::now();
        let slot = slot_of(&mut self.slots, &self.radius_overrides, topology, id, rep)?;
        if let Some((f, last)) = &slot.last
            && *f == index
            && !slot.layer.is_dynamic()
            && compute_key(&last.rep) == compute_key(rep)
        {
            return Ok(Entry::Reused(Arc::new(LayerResult {
                rep: rep.clone(),
                reused: true,
                gpu_work: None,
                ..(**last).clone()
            })));
        }
        // Radii that follow exposure are counted by the GPU engine itself (issue 33) when no
        // host step needs this frame's radii (cavities, exposure colours, periodic surfaces
        // read them): the particles then keep their own radii here.
        let exposure_on_gpu = matches!(self.backend, SceneBackend::Gpu(_))
            && rep.style.is_surface()
            && self.replicate.is_none()
            && !rep.cavities
            && exposure_map(rep, false).is_none()
            && rep.radii.exposure().is_some_and(|m| runs_on_gpu(&m));
        let lf = slot
            .layer
            .frame_with(topology, frame, !exposure_on_gpu)
            .map_err(|source| SceneError::Particles {
                frame: index,
                source,
            })?;
        // The particles' radii and colours change only when they were rebuilt (radii that
        // follow exposure: every frame): otherwise keep the same Arcs (no copy per frame, and
        // the engine sees no change).
        let last = slot
            .last
            .as_ref()
            .map(|(_, l)| &l.particles)
            .filter(|_| !lf.rebuilt);
        let radii = match last {
            Some(l) if lf.frame_radii.is_none() => l.radii.clone(),
            _ => Arc::new(lf.radii().to_vec()),
        };
        let colours = match last {
            Some(l) => l.colours.clone(),
            None => Arc::new(lf.particles.colours().to_vec()),
        };
        let mut result = LayerResult {
            id,
            rep: rep.clone(),
            output: SurfaceOutput::default(),
            gpu_surface: None,
            particles: ParticleData {
                positions: Vec::new(),
                radii,
                colours,
                bonds: lf.bonds.clone(),
            },
            beads: lf.particles.is_beads(),
            gpu_work: None,
            reused: false,
            compute_ms: 0.0,
            closed: self.replicate.is_none(),
            cavities: None,
        };
        let mut submitted = None;
        if rep.style.is_surface() && !lf.positions.is_empty() {
            let atoms = lf.atom_set();
            let surface_failed = |source| SceneError::Surface {
                frame: index,
                rep: rep.name.clone(),
                source,
            };
            if let Some(replicate) = self.replicate {
                let periodic_failed = |source| SceneError::Periodic {
                    frame: index,
                    rep: rep.name.clone(),
                    source,
                };
                let (cell, params) = (frame.cell.as_ref(), rep.params());
                let periodic = &mut self.periodic;
                let (output, colours) = host_surface(
                    atoms,
                    exposure_map(rep, lf.particles.is_beads()),
                    |a| {
                        periodic
                            .compute_in_cell(cell, a, &params, replicate)
                            .map_err(periodic_failed)
                    },
                    |out, map| {
                        let surface = ColouredSurface {
                            mesh: &out.mesh,
                            area: out.measured_area(),
                            seams: out.periodic.as_deref(),
                            cell: PbcCell::of(frame),
                        };
                        let subset = lf.particles.subset();
                        (slot.exposure)
                            .colours(topology, subset, &atoms, &params, surface, map)
                            .map_err(exposure_failed(index, &rep.name))
                    },
                )?;
                result.output = output;
                if let Some(colours) = colours {
                    result.particles.colours = Arc::new(colours);
                }
                slot.sent = None;
            } else {
                let changes = match slot.sent.take() {
                    Some(sent) => sent.changes(index, &lf, &result.particles),
                    None => Changes::ALL,
                };
                match &mut self.backend {
                    SceneBackend::Host(e) => {
                        e.set_vertices(rep.vertices);
                        let params = rep.params();
                        let effective = e.vertices().effective(&params);
                        let (output, colours) = host_surface(
                            atoms,
                            exposure_map(rep, lf.particles.is_beads()),
                            |a| e.compute(a, &params).map_err(surface_failed),
                            |out, map| {
                                let surface = ColouredSurface {
                                    mesh: &out.mesh,
                                    area: out.area,
                                    seams: None,
                                    cell: PbcCell::of(frame),
                                };
                                let subset = lf.particles.subset();
                                (slot.exposure)
                                    .colours(topology, subset, &atoms, &effective, surface, map)
                                    .map_err(exposure_failed(index, &rep.name))
                            },
                        )?;
                        result.output = output;
                        if let Some(colours) = colours {
                            result.particles.colours = Arc::new(colours);
                        }
                    }
                    SceneBackend::Gpu(main) => {
                        // The main engine serves one representation (one that never had an
                        // engine of its own, so its change tracking stays valid); each other
                        // surface gets its own engine on the same device.
                        if self.main_owner.is_none() && slot.gpu.is_none() {
                            self.main_owner = Some(id);
                        }
                        let e = if self.main_owner == Some(id) {
                            main.as_mut()
                        } else {
                            slot.gpu.get_or_insert_with(|| sibling_of(main)).as_mut()
                        };
                        e.set_vertices(rep.vertices);
                        let exposure = lf.particles.exposure().filter(|_| exposure_on_gpu);
                        e.set_exposure(exposure);
                        let info = e
                            .submit(&atoms, &rep.params(), changes)
                            .map_err(surface_failed)?;
                        submitted = Some(Submitted {
                            frame: info.frame,
                            work: info.work,
                            exposure: exposure_map(rep, lf.particles.is_beads()).map(|map| {
                                ExposureRequest {
                                    map,
                                    subset: lf.particles.subset().map(<[u32]>::to_vec),
                                    cell: PbcCell::of(frame),
                                }
                            }),
                        });
                    }
                }
                slot.sent = Some(Sent {
                    frame: index,
                    atoms: atoms_key(&lf),
                    radii: result.particles.radii.clone(),
                    colours: result.particles.colours.clone(),
                });
            }
        }
        // Cavities are found once the surface is collected (only when the switch is on).
        let cavities =
            (rep.cavities && rep.style.is_surface() && !lf.positions.is_empty()).then(|| {
                CavitySource {
                    subset: lf.particles.subset().map(<[u32]>::to_vec),
                    beads: lf.particles.is_beads(),
                    probe: rep.cavity_probe,
                }
            });
        result.particles.positions = lf.positions;
        result.compute_ms = started.elapsed().as_secs_f64() * 1e3;
        Ok(Entry::New(Box::new(result), submitted, cavities))
    }

    /// Finishes a new result: collects its GPU counters when it was submitted (and gives it
    /// its exposure colours when it takes them), finds its cavities when `cavities` says from
    /// which atoms, and keeps it in its slot for reuse.
    fn collect(
        &mut self,
        topology: &Topology,
        index: usize,
        mut result: LayerResult,
        submitted: Option<Submitted>,
        cavities: Option<CavitySource>,
    ) -> Result<Arc<LayerResult>, SceneError> {
        let id = result.id;
        if let Some(Submitted {
            frame,
            work,
            exposure,
        }) = submitted
        {
            let started = Instant::now();
            let mut finished = self.finish_gpu(id, (index, frame), &result);
            if let (Ok((stats, _)), Some(request)) = (&finished, exposure) {
                let stats = *stats;
                finished = self
                    .colour_by_exposure(topology, index, &mut result, &stats, request)
                    .and_then(|frame| self.finish_gpu(id, (index, frame), &result));
            }
            let (stats, surface) = match finished {
                Ok(done) => done,
                Err(e) => {
                    if let Some(slot) = self.slots.get_mut(&id) {
                        slot.sent = None;
                    }
                    return Err(e);
                }
            };
            result.output = SurfaceOutput {
                grid: surface.grid,
                mesh: Mesh::default(),
                area: stats.area,
                volume: stats.volume,
                timings: stats.timings,
                // The mesh stays in the engine's buffers.
                counts_without_mesh: Some(MeshCounts {
                    vertices: stats.vertex_count as usize,
                    triangles: stats.triangle_count as usize,
                }),
                density: None,
                sharp: None,
                periodic: None,
            };
            result.gpu_surface = Some(surface);
            result.gpu_work = Some(work);
            result.compute_ms += started.elapsed().as_secs_f64() * 1e3;
        }
        if let Some(source) = cavities {
            let started = Instant::now();
            result.cavities = self.cavities_of(topology, index, &result, &source)?;
            result.compute_ms += started.elapsed().as_secs_f64() * 1e3;
        }
        let result = Arc::new(result);
        if let Some(slot) = self.slots.get_mut(&id) {
            slot.last = Some((index, result.clone()));
        }
        Ok(result)
    }
}

/// The slot of representation `id` in `slots`, bound for `rep`: kept when the selection is the
/// same (binding, engine and what it was last sent), bound anew otherwise (keeping its engine).
fn slot_of<'a>(
    slots: &'a mut HashMap<RepId, RepSlot>,
    radius_overrides: &RadiusOverrides,
    topology: &Topology,
    id: RepId,
    rep: &Representation,
) -> Result<&'a mut RepSlot, SceneError> {
    let bind = || Layer::new(rep.clone(), topology, radius_overrides).map_err(SceneError::Bind);
    Ok(match slots.entry(id) {
        MapEntry::Occupied(o) if o.get().layer.rep().selection == rep.selection => {
            let slot = o.into_mut();
            slot.layer.set_rep(rep.clone());
            slot
        }
        MapEntry::Occupied(o) => {
            let layer = bind()?;
            let slot = o.into_mut();
            *slot = RepSlot {
                layer,
                gpu: slot.gpu.take(),
                last: None,
                sent: None,
                exposure: ExposureColouring::default(),
            };
            slot
        }
        MapEntry::Vacant(v) => v.insert(RepSlot {
            layer: bind()?,
            gpu: None,
            last: None,
            sent: None,
            exposure: ExposureColouring::default(),
        }),
    })
}
