//! The per-frame orchestrator of the GPU engine: validates and uploads atoms (radii and colours
//! only when they change), sizes the frame ([`super::plan`]), decides which stages must re-run
//! (positions/radii/H/R/quality: everything; colours: the colour pass; I: Marching Cubes only),
//! records them ([`super::frame`]), submits, and hands the counters back asynchronously.
//! [`GpuEngine::submit`] + [`GpuEngine::poll_stats`] + [`GpuEngine::surface`] are the viewer's
//! non-blocking path; [`SurfaceEngine::compute`] waits, grows on overflow and reads the mesh back.

use std::time::Instant;

use glam::Vec3;

use super::context::GpuContext;
use super::context::GpuObjects;
use super::frame::{Recorder, Stages, Work};
pub use super::options::{Changes, EngineOptions, FrameInfo};
use super::output::{FrameStats, GpuSurface, Readbacks, Staging};
use super::plan::{
    BRICK, BRICK_SAMPLES, BufferPlan, CLASS_ENTRIES_PER_SLOT, FramePlan, MeshCapacity, SlotTable,
    first_mesh_want, grown_brick_want, grown_mesh_want, plan_frame, settled_brick_slots,
};
use super::resources::Buffers;
use super::timing::Timer;
use super::types::{GpuCounters, pack_colour};
use super::{GpuError, inputs};
use crate::surface::{
    AtomSet, GridSpec, Mesh, MeshCounts, StageTimings, SurfaceEngine, SurfaceError, SurfaceOutput,
    SurfaceParams, VertexMode,
};

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
        (engine, scope_error.or(table_error))
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

    /// Bytes of GPU memory the engine's buffers hold.
    pub fn gpu_bytes(&self) -> u64 {
        self.buffers.bytes()
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

    /// Computes a surface without waiting: uploads what changed, records and submits the frame.
    /// Counters arrive later through [`GpuEngine::poll_stats`]. `changes` says what changed
    /// since the previous submit (parameter changes are detected here).
    pub fn submit(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        changes: Changes,
    ) -> Result<FrameInfo, SurfaceError> {
        self.submit_inner(atoms, params, changes, false)
            .map(|(info, _)| info)
    }

    fn submit_inner(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        changes: Changes,
        wall_clock: bool,
    ) -> Result<(FrameInfo, Option<StageTimings>), SurfaceError> {
        if let Some(e) = &self.init_error {
            return Err(SurfaceError::Gpu(format!(
                "the GPU engine could not start: {e}"
            )));
        }
        let ctx = self.ctx.clone();
        let mut inner = Ok(None);
        let scoped = ctx.scoped(|| {
            inner = self
                .submit_unscoped(atoms, params, changes, wall_clock, false)
                .map(Some);
            Ok(())
        });
        let result = match (inner, scoped) {
            (Err(e), _) => Err(e),
            (Ok(_), Err(e)) => Err(e.into()),
            (Ok(Some(r)), Ok(())) => Ok(r),
            (Ok(None), Ok(())) => Err(SurfaceError::Gpu("frame was not submitted".into())),
        };
        if result.is_err() {
            // Whatever was half uploaded: the next frame starts afresh and uploads everything.
            self.state.params = None;
            self.state.fingerprints = Default::default();
        }
        result
    }

    /// `bricks_counted`: the brick slots were just sized from this frame's count of reached
    /// bricks (`count_brick_slots`), so it goes on to compute.
    fn submit_unscoped(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        changes: Changes,
        wall_clock: bool,
        bricks_counted: bool,
    ) -> Result<(FrameInfo, Option<StageTimings>), SurfaceError> {
        let start = Instant::now();
        // Refined vertices run at quality max (grid and refinement, issue 33); a switch of
        // vertex mode then re-runs the density like any change of quality.
        let params = &self.vertices.effective(params);
        params.validate()?;
        inputs::check_lengths(atoms)?;
        let n = atoms.positions.len() as u64;
        let st = &mut self.state;
        let colour = atoms.colours.is_some();
        let first = st.params.is_none() || st.atoms != n || st.with_colour != colour;
        let changes = if first { Changes::ALL } else { changes };
        let prev = st.params.unwrap_or(*params);
        let density_params = prev.spacing != params.spacing
            || prev.radius_scale != params.radius_scale
            || prev.quality != params.quality;
        if changes.positions || changes.radii || st.bounds.is_none() {
            let old_r = st.bounds.map(|b| b.2);
            let (lo, hi, max_r) = inputs::bounds(atoms, changes.radii, old_r)?;
            st.bounds = Some((lo, hi, max_r));
        }
        let Some((lo, hi, max_r)) = st.bounds else {
            return Err(SurfaceError::EmptySystem);
        };
        let grid = GridSpec::for_atoms(&[lo, hi], &[max_r], params)?;
        let plan = plan_frame(
            grid,
            params,
            max_r,
            self.ctx.max_binding(),
            self.options.volume_budget,
            self.options.max_slab_layers,
        )
        .map_err(SurfaceError::from)?;
        let single = plan.slabs.len() == 1 && st.plan.as_ref().is_some_and(|p| p.slabs.len() == 1);
        let mut work = if first || changes.positions || changes.radii || density_params || !single {
            Work::Full
        } else if changes.colours {
            Work::Colour
        } else {
            Work::Mc
        };

        // Buffers: replaced per-atom buffers lose their contents, so re-upload everything then.
        let d = &self.ctx;
        // The sorted atoms (16 bytes each) are the largest per-atom binding.
        if n * 16 > self.ctx.max_binding() {
            return Err(GpuError::TooLarge {
                what: "the sorted atom array",
                needed: n * 16,
                limit: self.ctx.max_binding(),
            }
            .into());
        }
        let (want_v, want_t) = if st.mesh_want == (0, 0) {
            self.options
                .initial_mesh_capacity
                .map(|(v, t)| (v as u64, t as u64))
                .unwrap_or_else(|| first_mesh_want(&plan))
        } else {
            st.mesh_want
        };
        st.mesh_want = (want_v, want_t);
        let mesh = MeshCapacity::clipped((want_v, want_t), self.ctx.max_binding());
        // Every buffer size comes from the plan's byte count, so `gpu_bytes` and the
        // device-free estimate (`BufferPlan::fresh_memory`) cannot drift apart.
        let sparse = self.options.sparse_bricks;
        if sparse
            && st.brick_want == 0
            && let Some(s) = self.options.initial_brick_slots
        {
            st.brick_want = s.max(1);
        }
        // The first sparse frame of a system counts its reached bricks before density runs
        // (`count_brick_slots`): the engine's first, and a new system's (a new atom count on
        // a grid of half as many bricks again as the one last counted, so a `within`
        // selection whose atoms come and go does not wait on the device each frame). Until the
        // engine's first count the buffers hold one slot.
        let grown_system = first && plan.brick_count() * 2 > st.counted_on_bricks * 3;
        let probing = sparse
            && !bricks_counted
            && self.options.initial_brick_slots.is_none()
            && (st.brick_want == 0 || grown_system);
        let brick_slots = sparse.then_some(st.brick_want.max(1));
        let sizes = BufferPlan::new(
            &plan,
            n,
            colour,
            mesh,
            brick_slots,
            &self.ctx.device_limits(),
        );
        let replaced = self.buffers.ensure_atoms(d, &sizes);
        // A replaced density or colour buffer lost its samples, and a frame whose reached
        // bricks overflowed their slots left some unsampled: density runs again.
        let volumes_replaced = self.buffers.ensure_plan(d, &sizes);
        let redo = std::mem::take(&mut st.redo_density);
        if volumes_replaced || redo {
            work = Work::Full;
        }
        self.buffers.ensure_mesh(d, &sizes);
        let q = &self.ctx.queue;
        if changes.positions || replaced {
            inputs::write_in_parallel(
                q,
                &self.buffers.positions.buffer,
                bytemuck::cast_slice(atoms.positions),
            );
        }
        if changes.radii || replaced {
            q.write_buffer(
                &self.buffers.radii.buffer,
                0,
                bytemuck::cast_slice(atoms.radii),
            );
        }
        if let Some(c) = atoms.colours
            && (changes.colours || replaced)
        {
            let packed: Vec<[u32; 2]> = c.iter().map(|&c| pack_colour(c)).collect();
            q.write_buffer(
                &self.buffers.colours.buffer,
                0,
                bytemuck::cast_slice(&packed),
            );
        }
        let (vcap, tcap) = self.buffers.mesh_capacity();
        let counters = GpuCounters {
            vertex_capacity: vcap,
            triangle_capacity: tcap,
            ..Default::default()
        };
        q.write_buffer(&self.buffers.counters, 0, bytemuck::bytes_of(&counters));
        if probing {
            let sparse_classes = sizes.class_entries.sparse;
            self.state.brick_want = self.count_brick_slots(&plan, params, n, sparse_classes)?;
            return self.submit_unscoped(atoms, params, changes, wall_clock, true);
        }
        let upload_ms = start.elapsed().as_secs_f64() * 1e3;

        self.frame += 1;
        let frame = self.frame;
        let st = &mut self.state;
        if !std::mem::take(&mut st.rewrite_set) {
            st.output_set = (st.output_set + 1) % super::resources::OUTPUT_SETS;
            // After a frame that was never shown (it failed, or the caller dropped it), the
            // next set in turn may be the one on screen: take the other.
            if st.held_set == Some(st.output_set) {
                st.output_set = (st.output_set + 1) % super::resources::OUTPUT_SETS;
            }
        }
        let set = st.output_set;
        self.timer.begin_frame(d, 2 + 2 * plan.slabs.len() as u32);
        self.stages.prepare(
            &self.ctx,
            &mut self.buffers,
            &plan,
            params,
            n,
            work,
            sparse,
            sizes.class_entries.sparse,
            self.options.density_gather,
        );
        self.state.sparse_classes = sizes.class_entries.sparse;
        let mut rec = Recorder::new(&self.ctx, wall_clock && !self.timer.enabled());
        self.stages
            .record(
                &mut rec,
                &mut self.timer,
                &self.buffers,
                &plan,
                work,
                set,
                colour,
                self.vertices == VertexMode::Refined,
            )
            .map_err(SurfaceError::from)?;
        let slot =
            self.readbacks
                .record(d, rec.encoder(), &self.buffers.counters, &self.timer, frame);
        let (cmd, wall) = rec.finish();
        self.ctx.queue.submit([cmd]);
        if let Some(slot) = slot {
            self.readbacks.map(slot);
        }
        let st = &mut self.state;
        st.atoms = n;
        st.params = Some(*params);
        st.with_colour = colour;
        let info = FrameInfo {
            frame,
            grid,
            slabs: plan.slabs.len(),
            upload_ms,
            work,
        };
        st.plan = Some(plan);
        st.last = Some(info.clone());
        Ok((info, wall))
    }

    /// The brick slots of a system's first sparse frame on `plan`: runs binning and the
    /// sparse-brick pass alone, waits for them, reads the brick slot table back and sizes the
    /// slots for the most reached bricks of one slab ([`settled_brick_slots`]), so that the
    /// frame's density runs once, in slots that hold its bricks. Once per system (the one wait
    /// of the viewer's worker on the device): later frames grow the slots from their counters.
    fn count_brick_slots(
        &mut self,
        plan: &FramePlan,
        params: &SurfaceParams,
        atoms: u64,
        sparse_classes: bool,
    ) -> Result<u64, SurfaceError> {
        self.stages.prepare(
            &self.ctx,
            &mut self.buffers,
            plan,
            params,
            atoms,
            Work::Full,
            true,
            sparse_classes,
            self.options.density_gather,
        );
        let mut rec = Recorder::new(&self.ctx, false);
        self.stages.record_bricks(&mut rec, &self.buffers);
        let (cmd, _) = rec.finish();
        self.ctx.queue.submit([cmd]);
        self.ctx.wait()?;
        let table: Vec<u32> = self.staging()?.read_pod(
            &self.ctx,
            &self.buffers.density.buffer,
            plan.brick_count(),
        )?;
        let need = SlotTable::new(plan, &table).reached().slab_need(plan);
        self.state.counted_on_bricks = plan.brick_count();
        self.state.brick_counts += 1;
        Ok(settled_brick_slots(plan, need, self.ctx.max_binding()))
    }

    /// Non-blocking: the newest counters that have arrived since the last call, if any. Grows
    /// the mesh buffers for the next frame when a frame overflowed or came close. A frame with
    /// `overflow` set draws nothing: submit again (with `Changes::default()` only Marching
    /// Cubes re-runs) to get its surface.
    pub fn poll_stats(&mut self) -> Result<Option<FrameStats>, GpuError> {
        let _ = self.ctx.device.poll(wgpu::PollType::Poll);
        self.take_arrived()
    }

    fn take_arrived(&mut self) -> Result<Option<FrameStats>, GpuError> {
        let arrived = self.readbacks.collect(&self.timer)?;
        let (cap_v, cap_t) = self.buffers.mesh_capacity();
        for s in &arrived {
            // Grow (to the count plus headroom) only past 90 % of the capacity, so counts that
            // wander a little from frame to frame settle instead of growing the buffers at
            // each new maximum.
            let want =
                |c: u32, cap: u32| grown_mesh_want(c as u64, cap as u64, self.options.headroom);
            let (v, t) = (want(s.vertex_count, cap_v), want(s.triangle_count, cap_t));
            let m = &mut self.state.mesh_want;
            if *m == (0, 0) && (v.is_some() || t.is_some()) {
                // Leaving the first estimate: keep what the buffers already hold.
                *m = (cap_v as u64, cap_t as u64);
            }
            if let Some(v) = v {
                m.0 = m.0.max(v);
            }
            if let Some(t) = t {
                m.1 = m.1.max(t);
            }
            // Sparse bricks: grow the brick slots once a slab of a frame reached more bricks
            // than they were sized for; a frame whose bricks did not fit the buffers re-runs
            // density (an overflowed frame draws nothing; `finish` and `run_blocking` submit
            // again).
            if let Some(plan) = &self.state.plan
                && self.options.sparse_bricks
            {
                let want = &mut self.state.brick_want;
                if let Some(w) =
                    grown_brick_want(plan, s.brick_slots as u64, *want, self.ctx.max_binding())
                {
                    *want = (*want).max(w);
                }
                if s.brick_overflow {
                    self.state.redo_density = true;
                }
            }
        }
        if let Some(last) = arrived.last() {
            self.latest = Some(*last);
            // An overflowed last frame draws nothing: its rerun may write the same set.
            self.state.rewrite_set = last.frame == self.frame && last.overflow;
        }
        Ok(arrived.last().copied())
    }

    /// Blocks until the counters of frame `frame` (as [`GpuEngine::submit`] numbered it) or of
    /// a later frame have arrived, and returns them; no extra submit (the viewer's worker
    /// collects a submitted frame with it). After an overflow, submit again with
    /// `Changes::default()` (only Marching Cubes re-runs, into the same output set).
    pub fn wait_stats(&mut self, frame: u64) -> Result<FrameStats, GpuError> {
        loop {
            self.ctx.wait()?;
            let arrived = self.take_arrived()?;
            if let Some(s) = self.latest.filter(|s| s.frame >= frame) {
                return Ok(s);
            }
            if arrived.is_none() && !self.readbacks.pending() {
                return Err(GpuError::Readback(format!(
                    "counters of frame {frame} never arrived"
                )));
            }
        }
    }

    /// Finishes frame `frame` (as [`GpuEngine::submit`] numbered it) without timing stages:
    /// waits for its counters and, while the mesh overflowed, submits again with nothing changed
    /// (Marching Cubes only, grown buffers, the same output set). `atoms` and `params` are the
    /// submitted ones. The viewer's worker and `mdsurf render` finish frames with it; the mesh
    /// stays in [`GpuEngine::surface`].
    pub fn finish(
        &mut self,
        frame: u64,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<FrameStats, SurfaceError> {
        let mut frame = frame;
        for _ in 0..MAX_SUBMITS {
            let stats = self.wait_stats(frame)?;
            if !stats.overflow {
                return Ok(stats);
            }
            frame = self.submit(atoms, params, Changes::default())?.frame;
        }
        Err(overflowing())
    }

    /// Computes one frame and waits for its counters, growing the mesh buffers and re-running
    /// Marching Cubes when it overflowed. Stage timings come from timestamps when the device has
    /// them, else from waiting after each stage.
    pub fn run_blocking(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        changes: Changes,
    ) -> Result<FrameStats, SurfaceError> {
        let mut changes = changes;
        for _ in 0..MAX_SUBMITS {
            let (info, wall) = self.submit_inner(atoms, params, changes, true)?;
            let mut stats = self.wait_stats(info.frame)?;
            if let Some(w) = wall {
                stats.timings = w;
            }
            stats.timings.upload_ms = info.upload_ms;
            if !stats.overflow {
                return Ok(stats);
            }
            changes = Changes::default();
        }
        Err(overflowing())
    }

    /// Reads the mesh of the last finished frame back to the host.
    pub fn read_mesh(&self, stats: &FrameStats) -> Result<crate::surface::Mesh, GpuError> {
        self.staging()?.read_mesh(
            &self.ctx,
            &self.surface(),
            stats.vertex_count,
            stats.triangle_count,
        )
    }

    fn staging(&self) -> Result<std::sync::MutexGuard<'_, Staging>, GpuError> {
        self.staging
            .lock()
            .map_err(|_| GpuError::Readback("a readback panicked".into()))
    }

    /// Test hook: the density volume of the last slab (whole grid when there was one slab),
    /// voxel `i + nx * (j + ny * (k - dens_z0))`; on sparse bricks gathered from the brick slots
    /// (samples of unreached bricks are 0).
    pub fn read_density(&self) -> Result<Vec<f32>, GpuError> {
        if !self.options.sparse_bricks {
            return self.read_planned(&self.buffers.density.buffer, FramePlan::slab_voxels);
        }
        let Some(plan) = self.state.plan.as_ref() else {
            return Ok(Vec::new());
        };
        let words: Vec<u32> = self.staging()?.read_pod(
            &self.ctx,
            &self.buffers.density.buffer,
            self.buffers.density.size() / 4,
        )?;
        Ok(sparse_volume(plan, &words))
    }

    /// Test hook: class words of the last slab (see `shaders/classify.wgsl`), point
    /// `i + nx * (j + ny * (k - own_z0))`; on sparse classes gathered from the brick slots'
    /// entries (points without an entry are 0).
    pub fn read_classes(&self) -> Result<Vec<u32>, GpuError> {
        if !self.state.sparse_classes {
            return self.read_planned(&self.buffers.classes.buffer, FramePlan::class_points);
        }
        let Some(plan) = self.state.plan.as_ref() else {
            return Ok(Vec::new());
        };
        let mut staging = self.staging()?;
        let table: Vec<u32> =
            staging.read_pod(&self.ctx, &self.buffers.density.buffer, plan.brick_count())?;
        let entries: Vec<u32> = staging.read_pod(
            &self.ctx,
            &self.buffers.classes.buffer,
            self.buffers.classes.size() / 4,
        )?;
        Ok(sparse_classes(plan, &table, &entries))
    }

    /// Test hook: first slot of every bin cell after the scan.
    pub fn read_cell_starts(&self) -> Result<Vec<u32>, GpuError> {
        self.read_planned(&self.buffers.cell_start.buffer, FramePlan::cell_count)
    }

    /// Reads the first `len(plan)` elements of `buffer` (none before the first frame).
    fn read_planned<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        len: fn(&FramePlan) -> u64,
    ) -> Result<Vec<T>, GpuError> {
        let n = self.state.plan.as_ref().map(len).unwrap_or(0);
        self.staging()?.read_pod(&self.ctx, buffer, n)
    }
}

/// The density of the last slab of `plan` as a dense slab volume, from the words of the sparse
/// density buffer: the brick slot table ([`SlotTable`]), then [`BRICK_SAMPLES`] samples per
/// slot counted from the slab's first brick layer.
fn sparse_volume(plan: &FramePlan, words: &[u32]) -> Vec<f32> {
    let [nx, ny, _] = plan.grid.dims;
    let Some(slab) = plan.slabs.last() else {
        return Vec::new();
    };
    let slots = SlotTable::new(plan, words);
    let first = slots.first_slot(slab);
    let samples_from = plan.brick_count();
    let mut out = Vec::with_capacity(plan.slab_voxels() as usize);
    for kl in 0..slab.dens_layers {
        let k = slab.dens_z0 + kl;
        for j in 0..ny {
            for i in 0..nx {
                let v = slots
                    .slot([i / BRICK, j / BRICK, k / BRICK])
                    .map_or(0.0, |t| {
                        let local = i % BRICK + BRICK * (j % BRICK + BRICK * (k % BRICK));
                        let at = samples_from + (t - first) as u64 * BRICK_SAMPLES + local as u64;
                        f32::from_bits(words.get(at as usize).copied().unwrap_or(0))
                    });
                out.push(v);
            }
        }
    }
    out
}

/// The class words of the last slab of `plan` per classified point, from the brick slot table
/// (`table`, [`SlotTable`]) and the class entries of sparse classes: the host twin of
/// `class_entry` in `shaders/class_entries.wgsl`.
fn sparse_classes(plan: &FramePlan, table: &[u32], entries: &[u32]) -> Vec<u32> {
    let dims = plan.grid.dims;
    let Some(slab) = plan.slabs.last() else {
        return Vec::new();
    };
    let slots = SlotTable::new(plan, table);
    let first = slots.first_slot(slab);
    let apron = BRICK + 1;
    let entry = |p: [u32; 3]| -> Option<usize> {
        // Along an axis where p is the last sample of its brick, the brick above may hold it.
        let up = [0, 1, 2].map(|a| u32::from(p[a] % BRICK == BRICK - 1 && p[a] + 1 < dims[a]));
        for dz in 0..=up[2] {
            for dy in 0..=up[1] {
                for dx in 0..=up[0] {
                    let d = [dx, dy, dz];
                    if let Some(t) = slots.slot([0, 1, 2].map(|a| p[a] / BRICK + d[a])) {
                        let l = [0, 1, 2].map(|a| p[a] % BRICK + 1 - BRICK * d[a]);
                        let local = l[0] + apron * (l[1] + apron * l[2]);
                        let e = (t - first) as u64 * CLASS_ENTRIES_PER_SLOT + local as u64;
                        return Some(e as usize);
                    }
                }
            }
        }
        None
    };
    let class_z1 = (slab.own_z1 + 1).min(dims[2]);
    let mut out = Vec::with_capacity(plan.class_points() as usize);
    for kl in 0..plan.class_layers {
        let k = slab.own_z0 + kl;
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let word = (k < class_z1)
                    .then(|| entry([i, j, k]))
                    .flatten()
                    .and_then(|e| entries.get(e).copied());
                out.push(word.unwrap_or(0));
            }
        }
    }
    out
}

/// Most submits of one frame whose mesh keeps overflowing the grown buffers.
const MAX_SUBMITS: usize = 4;

fn overflowing() -> SurfaceError {
    GpuError::Device(format!(
        "the mesh kept overflowing its buffers after {MAX_SUBMITS} attempts"
    ))
    .into()
}

impl SurfaceEngine for GpuEngine {
    fn name(&self) -> &str {
        "gpu"
    }

    fn set_keep_mesh(&mut self, keep: bool) {
        self.measure_only = !keep;
    }

    fn set_vertices(&mut self, mode: VertexMode) {
        self.vertices = mode;
    }

    fn vertices(&self) -> VertexMode {
        self.vertices
    }

    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError> {
        let changes = self.state.fingerprints.update(atoms);
        let stats = self.run_blocking(atoms, params, changes)?;
        // Area and volume come from the GPU's reductions; the mesh is read back only if kept.
        let (mesh, counts_without_mesh) = if self.measure_only {
            let counts = MeshCounts {
                vertices: stats.vertex_count as usize,
                triangles: stats.triangle_count as usize,
            };
            (Mesh::default(), Some(counts))
        } else {
            (self.read_mesh(&stats)?, None)
        };
        Ok(SurfaceOutput {
            grid: self.surface().grid,
            mesh,
            area: stats.area,
            volume: stats.volume,
            timings: stats.timings,
            counts_without_mesh,
        })
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
