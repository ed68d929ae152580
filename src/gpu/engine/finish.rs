//! Finishing frames: polling and waiting for the counters, growing the mesh buffers after an
//! overflow, reading the mesh back, and [`SurfaceEngine`] for [`GpuEngine`] (the blocking path).

use super::*;

impl GpuEngine {
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

    pub(super) fn staging(&self) -> Result<std::sync::MutexGuard<'_, Staging>, GpuError> {
        self.staging
            .lock()
            .map_err(|_| GpuError::Readback("a readback panicked".into()))
    }
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
            density: None,
            sharp: None,
            periodic: None,
        })
    }
}
