//! Recording and submitting one frame: detects what changed, uploads it, sizes the frame and
//! its buffers, counts reached bricks when the brick slots must be sized, and records the stages
//! that must re-run.

use super::*;

impl GpuEngine {
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

    pub(super) fn submit_inner(
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
        let Some((lo, hi, own_max_r)) = st.bounds else {
            return Err(SurfaceError::EmptySystem);
        };
        // Radii that follow exposure are computed on the device: the grid is sized for the
        // largest they can be (the largest own radius times the model's largest factor).
        let exposure = &self.stages.exposure;
        if exposure.active() && exposure.atoms() != atoms.positions.len() {
            return Err(SurfaceError::InvalidParameter {
                name: "heavy atom flags",
                value: format!(
                    "{} entries for {} atoms",
                    exposure.atoms(),
                    atoms.positions.len()
                ),
            });
        }
        let max_r = own_max_r * exposure.max_factor();
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
        if (changes.radii || replaced) && self.stages.exposure.active() {
            self.stages.exposure.upload_radii(&self.ctx, atoms.radii);
        } else if changes.radii || replaced {
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
            st.output_set = (st.output_set + 1) % crate::gpu::resources::OUTPUT_SETS;
            // After a frame that was never shown (it failed, or the caller dropped it), the
            // next set in turn may be the one on screen: take the other.
            if st.held_set == Some(st.output_set) {
                st.output_set = (st.output_set + 1) % crate::gpu::resources::OUTPUT_SETS;
            }
        }
        let set = st.output_set;
        self.timer.begin_frame(d, 3 + 2 * plan.slabs.len() as u32);
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
}
