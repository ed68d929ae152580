//! Bookkeeping between slabs and the end-of-frame reduction (`shaders/measure.wgsl`): emit
//! dispatch sizes, running vertex/triangle bases, totals, overflow bits, the renderer's indirect
//! draw arguments, and area and volume by a deterministic two-level sum (of the flat triangles,
//! or with refined vertices curvature-corrected as [`crate::surface::curved`] does).

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Uniform, module};
use super::layout::measure as m;
use super::resources::{Buffers, OUTPUT_SETS};
use super::types::MeasureUniform;

/// Workgroups of the partial area/volume sums (`PARTIAL_GROUPS` in `shaders/measure.wgsl`): each
/// writes one partial, and the final sum's one workgroup of as many threads adds them.
pub(crate) const PARTIAL_GROUPS: u32 = 256;

/// The bookkeeping and reduction kernels, their uniform and cached bind groups.
#[derive(Debug)]
pub struct Measure {
    slab_begin: Kernel,
    slab_end: Kernel,
    frame_end: Kernel,
    partial_sums: Kernel,
    /// `partial_sums` with `CURVED` (refined vertices).
    partial_sums_curved: Kernel,
    final_sum: Kernel,
    uniform: Uniform<MeasureUniform>,
    /// `slab_begin`, `slab_end`, `final_sum` (no output buffer bound).
    binds: [Bound; 3],
    /// `frame_end` and `partial_sums` per output set (they bind its draw arguments and mesh).
    set_binds: [[Bound; 2]; OUTPUT_SETS],
}

impl Measure {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext) -> Measure {
        let module = module(&ctx.device, "measure.wgsl", super::shaders::MEASURE);
        let k = |e, slots| Kernel::with_slots(ctx, &module, e, slots);
        // One layout for both variants, so they share the bind group.
        let sums = super::kernel::Layout::new(ctx, "partial_sums", m::PARTIAL_SUMS);
        Measure {
            slab_begin: k("slab_begin", m::SLAB_BEGIN),
            slab_end: k("slab_end", m::SLAB_END),
            frame_end: k("frame_end", m::FRAME_END),
            partial_sums: Kernel::new(ctx, &module, "partial_sums", &[], &sums),
            partial_sums_curved: Kernel::new(
                ctx,
                &module,
                "partial_sums",
                &[("CURVED", 1.0)],
                &sums,
            ),
            final_sum: k("final_sum", m::FINAL_SUM),
            uniform: Uniform::new(ctx, "measure uniform"),
            binds: Default::default(),
            set_binds: Default::default(),
        }
    }

    /// Writes the frame's uniform and refreshes the bind groups.
    pub fn prepare(&mut self, ctx: &GpuContext, b: &Buffers, uniform: &MeasureUniform) {
        self.uniform.write(&ctx.queue, uniform);
        let u = &self.uniform.buffer;
        let [slab_begin, slab_end, final_sum] = &mut self.binds;
        self.slab_begin.bind(
            ctx,
            slab_begin,
            &[
                (m::U, u),
                (m::COUNTERS, &b.counters),
                (m::DISPATCH_ARGS, &b.dispatch_args),
            ],
        );
        self.slab_end
            .bind(ctx, slab_end, &[(m::COUNTERS, &b.counters)]);
        for ([frame_end, partial_sums], out) in self.set_binds.iter_mut().zip(&b.outputs) {
            self.frame_end.bind(
                ctx,
                frame_end,
                &[(m::COUNTERS, &b.counters), (m::DRAW_ARGS, &out.draw_args)],
            );
            self.partial_sums.bind(
                ctx,
                partial_sums,
                &[
                    (m::U, u),
                    (m::COUNTERS, &b.counters),
                    (m::VERTICES, &out.vertices.buffer),
                    (m::INDICES, &out.indices.buffer),
                    (m::PARTIALS, &b.partials),
                    (m::SORTED_ATOMS, &b.sorted_atoms.buffer),
                    (m::CELL_END, &b.cell_end.buffer),
                ],
            );
        }
        self.final_sum.bind(
            ctx,
            final_sum,
            &[(m::COUNTERS, &b.counters), (m::PARTIALS, &b.partials)],
        );
    }

    /// After a slab's scans: emit dispatch size.
    pub fn slab_begin(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.slab_begin
            .dispatch(pass, &self.binds[0], &[], [1, 1, 1]);
    }

    /// After a slab's emission: advance the bases.
    pub fn slab_end(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.slab_end.dispatch(pass, &self.binds[1], &[], [1, 1, 1]);
    }

    /// After the last slab: totals, draw arguments of output set `set`, area and volume of its
    /// mesh (`curved`: with the curvature correction, for refined vertices).
    pub fn frame_end(&self, pass: &mut wgpu::ComputePass<'_>, set: usize, curved: bool) {
        let [frame_end, partial_sums] = &self.set_binds[set];
        self.frame_end.dispatch(pass, frame_end, &[], [1, 1, 1]);
        let sums = if curved {
            &self.partial_sums_curved
        } else {
            &self.partial_sums
        };
        sums.dispatch(pass, partial_sums, &[], [PARTIAL_GROUPS, 1, 1]);
        self.final_sum
            .dispatch(pass, &self.binds[2], &[], [1, 1, 1]);
    }
}
