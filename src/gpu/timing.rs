//! Per-stage GPU timing (the paper's t_sort, t_d, t_MC): every compute pass of a frame gets a
//! pair of timestamp queries when the device has `TIMESTAMP_QUERY`; the raw ticks are resolved
//! into a buffer, copied next to the frame counters in the readback buffer, and turned into
//! milliseconds per stage when the readback arrives. Without timestamps the engine falls back to
//! wall-clock times measured around blocking waits (see [`super::engine`]).

use crate::surface::StageTimings;

/// Which paper stage a compute pass belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Exposure counts and radii of the SES preset ([`super::exposure`]).
    Exposure,
    /// Binning (t_sort).
    Bin,
    /// Density and colour gather (t_d).
    Density,
    /// Marching Cubes, area, volume, draw arguments (t_MC).
    Mc,
}

/// Timestamp queries of one engine.
#[derive(Debug)]
pub struct Timer {
    set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    capacity: u32,
    period_ns: f64,
    passes: Vec<Stage>,
}

impl Timer {
    /// A timer that records timestamps when `enabled` (the device has `TIMESTAMP_QUERY`).
    pub fn new(queue: &wgpu::Queue, enabled: bool) -> Timer {
        Timer {
            set: None,
            resolve: None,
            capacity: if enabled { 0 } else { u32::MAX },
            period_ns: queue.get_timestamp_period() as f64,
            passes: Vec::new(),
        }
    }

    /// True when timestamps are recorded.
    pub fn enabled(&self) -> bool {
        self.capacity != u32::MAX
    }

    /// Starts a frame of at most `max_passes` passes.
    pub fn begin_frame(&mut self, ctx: &super::GpuContext, max_passes: u32) {
        self.passes.clear();
        if !self.enabled() || self.capacity >= max_passes {
            return;
        }
        let cap = max_passes.next_power_of_two().min(2048);
        self.set = Some(ctx.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("stage timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * cap,
        }));
        self.resolve = Some(ctx.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamp resolve"),
            size: 16 * cap as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }));
        self.capacity = cap;
    }

    /// Timestamp writes for the next pass of `stage` (None without timestamps or when full).
    pub fn pass(&mut self, stage: Stage) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let n = self.passes.len() as u32;
        if !self.enabled() || n >= self.capacity {
            return None;
        }
        self.passes.push(stage);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: self.set.as_ref()?,
            beginning_of_pass_write_index: Some(2 * n),
            end_of_pass_write_index: Some(2 * n + 1),
        })
    }

    /// Bytes the resolved timestamps of this frame take.
    pub fn frame_bytes(&self) -> u64 {
        16 * self.passes.len() as u64
    }

    /// Resolves this frame's queries and copies them to `dst` at `offset` (a multiple of 8).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder, dst: &wgpu::Buffer, offset: u64) {
        let (Some(set), Some(resolve)) = (&self.set, &self.resolve) else {
            return;
        };
        let n = self.passes.len() as u32;
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(set, 0..2 * n, resolve, 0);
        encoder.copy_buffer_to_buffer(resolve, 0, dst, offset, Some(16 * n as u64));
    }

    /// The stages of this frame's passes, in order (to pair with [`Timer::stage_ms`] later).
    pub fn frame_passes(&self) -> Vec<Stage> {
        self.passes.clone()
    }

    /// Milliseconds per stage from raw ticks (two per pass, in `passes` order); upload stays 0.
    pub fn stage_ms(&self, passes: &[Stage], ticks: &[u64]) -> StageTimings {
        let mut t = StageTimings::default();
        for (stage, pair) in passes.iter().zip(ticks.chunks_exact(2)) {
            let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period_ns / 1e6;
            match stage {
                Stage::Exposure => t.exposure_ms += ms,
                Stage::Bin => t.bin_ms += ms,
                Stage::Density => t.density_ms += ms,
                Stage::Mc => t.mc_ms += ms,
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_sums_follow_pass_order() {
        let timer = Timer {
            set: None,
            resolve: None,
            capacity: 8,
            period_ns: 2.0,
            passes: Vec::new(),
        };
        let passes = [
            Stage::Bin,
            Stage::Density,
            Stage::Mc,
            Stage::Density,
            Stage::Mc,
        ];
        let ticks = [
            0, 500_000, 10, 1_000_010, 0, 250_000, 5, 1_000_005, 1, 250_001,
        ];
        let t = timer.stage_ms(&passes, &ticks);
        assert!((t.bin_ms - 1.0).abs() < 1e-12);
        assert!((t.density_ms - 4.0).abs() < 1e-12);
        assert!((t.mc_ms - 1.0).abs() < 1e-12);
        assert_eq!(t.upload_ms, 0.0);
    }
}
