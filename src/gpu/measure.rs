//! Bookkeeping between slabs and the end-of-frame reduction (`shaders/measure.wgsl`): emit
//! dispatch sizes, running vertex/triangle bases, totals, overflow bits, the renderer's indirect
//! draw arguments, and area and volume by a deterministic two-level sum.

use super::kernel::{Kernel, module};
use super::resources::Buffers;

/// The bookkeeping and reduction kernels.
#[derive(Debug)]
pub struct Measure {
    slab_begin: Kernel,
    slab_end: Kernel,
    frame_end: Kernel,
    partial_sums: Kernel,
    final_sum: Kernel,
}

/// Bind groups of one frame.
#[derive(Debug)]
pub struct MeasureFrame {
    slab_begin: wgpu::BindGroup,
    slab_end: wgpu::BindGroup,
    frame_end: wgpu::BindGroup,
    partial_sums: wgpu::BindGroup,
    final_sum: wgpu::BindGroup,
}

impl Measure {
    /// Compiles the kernels.
    pub fn new(device: &wgpu::Device) -> Measure {
        let m = module(device, "measure.wgsl", super::shaders::MEASURE);
        let k = |e| Kernel::new(device, &m, e, &[]);
        Measure {
            slab_begin: k("slab_begin"),
            slab_end: k("slab_end"),
            frame_end: k("frame_end"),
            partial_sums: k("partial_sums"),
            final_sum: k("final_sum"),
        }
    }

    /// Bind groups for a frame; `uniform` holds a [`super::types::MeasureUniform`].
    pub fn frame(
        &self,
        device: &wgpu::Device,
        b: &Buffers,
        uniform: &wgpu::Buffer,
    ) -> MeasureFrame {
        let u = || (0, uniform.as_entire_binding());
        let c = || (1, b.counters.as_entire_binding());
        MeasureFrame {
            slab_begin: self.slab_begin.bind(
                device,
                &[u(), c(), (5, b.dispatch_args.as_entire_binding())],
            ),
            slab_end: self.slab_end.bind(device, &[c()]),
            frame_end: self
                .frame_end
                .bind(device, &[c(), (6, b.draw_args.as_entire_binding())]),
            partial_sums: self.partial_sums.bind(
                device,
                &[
                    u(),
                    c(),
                    (2, b.vertices.buffer.as_entire_binding()),
                    (3, b.indices.buffer.as_entire_binding()),
                    (4, b.partials.as_entire_binding()),
                ],
            ),
            final_sum: self
                .final_sum
                .bind(device, &[c(), (4, b.partials.as_entire_binding())]),
        }
    }

    /// After a slab's scans: emit dispatch size.
    pub fn slab_begin(&self, pass: &mut wgpu::ComputePass<'_>, f: &MeasureFrame) {
        self.slab_begin.dispatch(pass, &f.slab_begin, [1, 1, 1]);
    }

    /// After a slab's emission: advance the bases.
    pub fn slab_end(&self, pass: &mut wgpu::ComputePass<'_>, f: &MeasureFrame) {
        self.slab_end.dispatch(pass, &f.slab_end, [1, 1, 1]);
    }

    /// After the last slab: totals, draw arguments, area and volume.
    pub fn frame_end(&self, pass: &mut wgpu::ComputePass<'_>, f: &MeasureFrame) {
        self.frame_end.dispatch(pass, &f.frame_end, [1, 1, 1]);
        self.partial_sums
            .dispatch(pass, &f.partial_sums, [256, 1, 1]);
        self.final_sum.dispatch(pass, &f.final_sum, [1, 1, 1]);
    }
}
