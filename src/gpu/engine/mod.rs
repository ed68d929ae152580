//! The per-frame orchestrator of the GPU engine: validates and uploads atoms (radii and colours
//! only when they change), sizes the frame ([`super::plan`]), decides which stages must re-run
//! (positions/radii/H/R/quality: everything; colours: the colour pass; I: Marching Cubes only),
//! records them ([`super::frame`]), submits, and hands the counters back asynchronously.
//! [`GpuEngine::submit`] + [`GpuEngine::poll_stats`] + [`GpuEngine::surface`] are the viewer's
//! non-blocking path; [`SurfaceEngine::compute`] waits, grows on overflow and reads the mesh back.

use std::time::Instant;

use glam::Vec3;

use crate::gpu::context::GpuContext;
use crate::gpu::context::GpuObjects;
use crate::gpu::frame::{Recorder, Stages, Work};
pub use crate::gpu::options::{Changes, EngineOptions, FrameInfo};
use crate::gpu::output::{FrameStats, GpuSurface, Readbacks, Staging};
use crate::gpu::plan::{
    BufferPlan, FramePlan, MeshCapacity, SlotTable, first_mesh_want, grown_brick_want,
    grown_mesh_want, plan_frame, settled_brick_slots,
};
use crate::gpu::resources::Buffers;
use crate::gpu::timing::Timer;
use crate::gpu::types::{GpuCounters, pack_colour};
use crate::gpu::{GpuError, inputs};
use crate::model::exposure::ExposureModel;
use crate::surface::{
    AtomSet, GridSpec, Mesh, MeshCounts, StageTimings, SurfaceEngine, SurfaceError, SurfaceOutput,
    SurfaceParams, VertexMode,
};

mod finish;
#[cfg(feature = "test-hooks")]
mod hooks;
mod submit;

#[derive(Debug, Default)]
struct State {
    atoms: u64,
    params: Option<SurfaceParams>,
    plan: Option<FramePlan>,
    last: Option<FrameInfo>,
    with_colour: bool,
    bounds: Option<(Vec3, Vec3, f32)>,
    fingerprints: inputs::Fingerprints,
    mesh_want: (u64, u64),
    /// Brick slots the sparse density and colour buffers should hold (0: not yet counted).
    brick_want: u64,
    /// A frame's reached bricks did not fit the brick slots: the next frame re-runs density.
    redo_density: bool,
    /// The last frame held its class entries per brick slot ([`super::plan::ClassEntries`]).
    sparse_classes: bool,
    /// Bricks of the grid on which the brick slots were last counted (`count_brick_slots`).
    counted_on_bricks: u64,
    /// How many frames counted their reached bricks before density.
    brick_counts: u64,
    /// Output set the last submitted frame wrote ([`super::resources::OUTPUT_SETS`]).
    output_set: usize,
    /// True when the last submitted frame overflowed: nobody draws its output set, so the next
    /// frame (its rerun) writes the same set instead of the one the renderer may be drawing.
    rewrite_set: bool,
    /// Output set the caller shows ([`GpuEngine::hold_output_set`]); no frame writes it.
    held_set: Option<usize>,
}

/// The GPU surface engine (see the module docs).
pub struct GpuEngine {
    ctx: GpuContext,
    stages: Stages,
    buffers: Buffers,
    timer: Timer,
    readbacks: Readbacks,
    options: EngineOptions,
    state: State,
    frame: u64,
    latest: Option<FrameStats>,
    init_error: Option<String>,
    staging: std::sync::Mutex<Staging>,
    /// Vertex placement (refined: `shaders/refine.wgsl` after emission, curved measurement).
    vertices: VertexMode,
    /// True when [`SurfaceEngine::compute`] reports area, volume and counts without reading
    /// the mesh back (see [`SurfaceEngine::set_keep_mesh`]).
    measure_only: bool,
}

impl std::fmt::Debug for GpuEngine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuEngine")
            .field("adapter", &self.ctx.adapter_name)
            .field("frame", &self.frame)
            .finish_non_exhaustive()
    }
}

impl GpuEngine {
    /// Opens the best adapter headless (its own limits, timestamps when supported). Under
    /// `REQUIRE_GPU=1` and without it alike, a missing adapter is [`GpuError::NoAdapter`].
    pub fn new() -> Result<GpuEngine, GpuError> {
        Self::with_context(GpuContext::new_headless()?)
    }

    /// Wraps a device created elsewhere (the viewer shares eframe's device); its limits bound
    /// the problem sizes and slabs. Never fails itself: when the device cannot build the
    /// pipelines, every frame returns that error (see [`GpuEngine::try_from_device`]).
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue) -> GpuEngine {
        let (engine, error) = Self::build(GpuContext::from_device(
            device,
            queue,
            "shared device".into(),
        ));
        GpuEngine {
            init_error: error.map(|e| e.to_string()),
            ..engine
        }
    }

    /// Like [`GpuEngine::from_device`], failing at once when the pipelines cannot be built.
    pub fn try_from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<GpuEngine, GpuError> {
        Self::with_context(GpuContext::from_device(
            device,
            queue,
            "shared device".into(),
        ))
    }

    /// An engine on `ctx` (compiles every stage).
    pub fn with_context(ctx: GpuContext) -> Result<GpuEngine, GpuError> {
        match Self::build(ctx) {
            (engine, None) => Ok(engine),
            (_, Some(e)) => Err(e),
        }
    }

    fn build(ctx: GpuContext) -> (GpuEngine, Option<GpuError>) {
        let max_groups = ctx.limits.max_compute_workgroups_per_dimension;
        let ((stages, (buffers, table_error)), scope_error) =
            ctx.capture(|| (Stages::new(&ctx, max_groups), Buffers::new(&ctx)));
        let engine = GpuEngine {
            stages,
            buffers,
            timer: Timer::new(&ctx.queue, ctx.timestamps),
            readbacks: Readbacks::default(),
            options: EngineOptions::defaults(&ctx),
            state: State::default(),
            frame: 0,
            latest: None,
            init_error: None,
            staging: Default::default(),
            vertices: VertexMode::default(),
            measure_only: false,
            ctx,
        };
        // Said before the validation error such a device gives for the first wider layout.
        let needed = engine.ctx.widest_storage_layout();
        let allowed = engine.ctx.limits.max_storage_buffers_per_shader_stage;
        let too_few =
            (allowed < needed).then_some(GpuError::TooFewStorageBuffers { needed, allowed });
        (engine, too_few.or(scope_error).or(table_error))
    }

    /// The device context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Current options.
    pub fn options(&self) -> EngineOptions {
        self.options
    }

    /// Replaces the options (the next frame re-runs every stage).
    pub fn set_options(&mut self, options: EngineOptions) {
        self.options = options;
        self.state.params = None;
    }

    /// The plan of the last submitted frame.
    pub fn plan(&self) -> Option<&FramePlan> {
        self.state.plan.as_ref()
    }

    /// What the last submit did (which stages ran, grid, slabs).
    pub fn last_frame(&self) -> Option<&FrameInfo> {
        self.state.last.as_ref()
    }

    /// Which output set (0 or 1) the last submitted frame wrote its mesh into: frames alternate,
    /// except that the rerun of an overflowed frame writes the same set again.
    pub fn output_set(&self) -> usize {
        self.state.output_set
    }

    /// Marks the output set of the last submitted frame as the one the caller shows: later
    /// frames write the other set until this is called again, even when a frame in between
    /// is never shown (it failed, or the caller dropped it). Without calls, frames simply
    /// alternate.
    pub fn hold_output_set(&mut self) {
        self.state.held_set = Some(self.state.output_set);
    }

    /// GPU objects (buffers, bind groups, textures, query sets) the engine has created so far,
    /// through its context. In steady state (same atom count, a grid that fits the buffers) a
    /// frame creates none: compare two snapshots.
    pub fn objects_created(&self) -> GpuObjects {
        self.ctx.objects()
    }

    /// Bytes of GPU memory the engine's buffers hold (the exposure pass's only while it runs:
    /// unused, its nine placeholders of 16 bytes are left out, as the plan leaves them out).
    pub fn gpu_bytes(&self) -> u64 {
        let exposure = &self.stages.exposure;
        self.buffers.bytes()
            + if exposure.active() {
                exposure.bytes()
            } else {
                0
            }
    }

    /// Makes the engine compute the atoms' radii from exposure ([`crate::gpu::exposure`]):
    /// `Some((model, heavy))`, one heavy flag per atom, and the radii each frame gives are the
    /// atoms' own, which the device multiplies by the model's factor of their heavy neighbour
    /// counts; `None` (the default): the radii given are used as they are. A model that does
    /// not [`crate::gpu::exposure::runs_on_gpu`] counts as `None`. Returns true when the
    /// engine now computes the radii (otherwise the caller gives the frame's radii). A change
    /// makes the next frame a full one.
    pub fn set_exposure(&mut self, exposure: Option<(ExposureModel, &[bool])>) -> bool {
        if self.stages.exposure.set(exposure) {
            self.state.params = None;
        }
        self.stages.exposure.active()
    }

    /// True when the engine computes radii from exposure ([`GpuEngine::set_exposure`]).
    pub fn exposure_on_device(&self) -> bool {
        self.stages.exposure.active()
    }

    /// Makes the next [`SurfaceEngine::compute`] a full frame (upload, binning, density) even
    /// when its atoms are the last frame's: `bench` repeats a single-frame file, and the CPU
    /// engine recomputes such a frame from scratch too.
    pub fn forget_inputs(&mut self) {
        self.state.fingerprints = Default::default();
    }

    /// How many frames counted their reached bricks before their density ran: a system's
    /// first sparse frame does (see [`super::bricks`]), a frame of the same system does not.
    pub fn brick_counts(&self) -> u64 {
        self.state.brick_counts
    }

    /// True when the last submitted frame held its class words, vertex bases and active cells
    /// per brick slot ([`super::plan::ClassEntries`]) instead of per point of its slab.
    pub fn sparse_classes(&self) -> bool {
        self.state.sparse_classes
    }

    /// Sparse bricks of the last frame whose counters arrived: bricks covering the grid and
    /// bricks some atom reaches. Both the occupied and the active count are the reached bricks:
    /// the GPU samples and classifies every reached brick (it does not skip those whose
    /// samples all lie on one side of I). None on the dense path or before the first counters.
    pub fn brick_stats(&self) -> Option<crate::surface::BrickStats> {
        let plan = self.state.plan.as_ref()?;
        let stats = self.latest?;
        self.options
            .sparse_bricks
            .then(|| crate::surface::BrickStats {
                brick_size: super::plan::BRICK,
                bricks: plan.brick_count(),
                occupied: stats.reached_bricks as u64,
                active: stats.reached_bricks as u64,
            })
    }

    /// The GPU-resident surface of the last submitted frame (for the renderer), with its
    /// counters once they have arrived. Frames alternate between two output sets, so these
    /// buffers keep this frame's mesh while the next frame is computed; the frame after that
    /// (or a rerun of an overflowed frame) writes them again.
    pub fn surface(&self) -> GpuSurface {
        let set = &self.buffers.outputs[self.state.output_set];
        GpuSurface {
            vertices: set.vertices.buffer.clone(),
            indices: set.indices.buffer.clone(),
            draw_args: set.draw_args.clone(),
            grid: self.state.plan.as_ref().map(|p| p.grid).unwrap_or_default(),
            frame: self.frame,
            stats: self.latest.filter(|s| s.frame == self.frame),
        }
    }
}

#[cfg(test)]
mod tests {
    /// The viewer keeps the engine as `Box<dyn SurfaceEngine + Send>`.
    #[test]
    fn engine_is_send() {
        fn send<T: Send>() {}
        send::<super::GpuEngine>();
        send::<super::GpuSurface>();
    }
}
