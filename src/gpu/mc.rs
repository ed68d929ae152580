//! Marching Cubes stages (the paper's t_MC) over one slab: [`Classify`] (`shaders/classify.wgsl`:
//! case byte, crossed own edges and triangle count per point, sums per 256-point block), three
//! scans of the block sums ([`super::scan`]), [`Compact`] (`shaders/compact.wgsl`: global vertex
//! base per point and the list of active cells) and [`Emit`] (`shaders/emit.wgsl`: shared
//! vertices per crossed edge and indexed triangles, dispatched indirectly over the active cells),
//! then, with refined vertices, [`Refine`] (`shaders/refine.wgsl`: the same cells' vertices moved
//! onto the exact Gaussian sum, normals from its gradient; issue 13).

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Layout, groups_1d, module};
use super::layout::{classify as cl, compact as co, emit as em, refine as rf};
use super::resources::{Buffers, OUTPUT_SETS};

/// Classification kernel and its cached bind group.
#[derive(Debug)]
pub struct Classify(Kernel, Bound);

/// Compaction kernel and its cached bind group.
#[derive(Debug)]
pub struct Compact(Kernel, Bound);

/// Emission kernels (with and without the colour volume, one layout) and their bind groups,
/// one per output set.
#[derive(Debug)]
pub struct Emit {
    with_colour: Kernel,
    plain: Kernel,
    bind: [Bound; OUTPUT_SETS],
}

/// Vertex refinement kernel and its cached bind groups, one per output set.
#[derive(Debug)]
pub struct Refine(Kernel, [Bound; OUTPUT_SETS]);

impl Classify {
    /// Compiles the kernel.
    pub fn new(ctx: &GpuContext) -> Classify {
        let m = module(&ctx.device, "classify.wgsl", super::shaders::CLASSIFY);
        Classify(
            Kernel::with_slots(ctx, &m, "main", cl::ALL),
            Bound::default(),
        )
    }

    /// Refreshes the bind group (shared by every slab; dynamic slab uniform offset).
    pub fn prepare(&mut self, ctx: &GpuContext, b: &Buffers) {
        self.0.bind(
            ctx,
            &mut self.1,
            &[
                (cl::U, &b.slab_uniforms.buffer),
                (cl::DENSITY, &b.density.buffer),
                (cl::MC, &b.mc_tables),
                (cl::CLASSES, &b.classes.buffer),
                (cl::BLOCK_VERTICES, &b.block_sums[0].buffer),
                (cl::BLOCK_TRIANGLES, &b.block_sums[1].buffer),
                (cl::BLOCK_ACTIVE, &b.block_sums[2].buffer),
                (cl::BRICK_FLAGS, &b.brick_flags.buffer),
                (cl::COUNTERS, &b.counters),
            ],
        );
    }

    /// Records classification of `blocks` blocks of 256 points of the slab at `offset`.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offset: u32,
        blocks: u64,
        max_groups: u32,
    ) {
        self.0
            .dispatch(pass, &self.1, &[offset], groups_1d(blocks, max_groups));
    }
}

impl Compact {
    /// Compiles the kernel.
    pub fn new(ctx: &GpuContext) -> Compact {
        let m = module(&ctx.device, "compact.wgsl", super::shaders::COMPACT);
        Compact(
            Kernel::with_slots(ctx, &m, "main", co::ALL),
            Bound::default(),
        )
    }

    /// Refreshes the bind group (shared by every slab; dynamic slab uniform offset).
    pub fn prepare(&mut self, ctx: &GpuContext, b: &Buffers) {
        self.0.bind(
            ctx,
            &mut self.1,
            &[
                (co::U, &b.slab_uniforms.buffer),
                (co::CLASSES, &b.classes.buffer),
                (co::BLOCK_VERTICES, &b.block_sums[0].buffer),
                (co::BLOCK_TRIANGLES, &b.block_sums[1].buffer),
                (co::BLOCK_ACTIVE, &b.block_sums[2].buffer),
                (co::COUNTERS, &b.counters),
                (co::VERTEX_BASE, &b.vertex_base.buffer),
                (co::ACTIVE, &b.active.buffer),
                (co::DENSITY, &b.density.buffer),
            ],
        );
    }

    /// Records compaction of `blocks` blocks of 256 points of the slab at `offset`.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offset: u32,
        blocks: u64,
        max_groups: u32,
    ) {
        self.0
            .dispatch(pass, &self.1, &[offset], groups_1d(blocks, max_groups));
    }
}

impl Emit {
    /// Compiles both variants.
    pub fn new(ctx: &GpuContext) -> Emit {
        let m = module(&ctx.device, "emit.wgsl", super::shaders::EMIT);
        let layout = Layout::new(ctx, "emit", em::ALL);
        Emit {
            with_colour: Kernel::new(ctx, &m, "main", &[("WITH_COLOUR", 1.0)], &layout),
            plain: Kernel::new(ctx, &m, "main", &[("WITH_COLOUR", 0.0)], &layout),
            bind: Default::default(),
        }
    }

    fn kernel(&self, colour: bool) -> &Kernel {
        if colour {
            &self.with_colour
        } else {
            &self.plain
        }
    }

    /// Refreshes the bind group of each output set (shared by both variants and every slab).
    pub fn prepare(&mut self, ctx: &GpuContext, b: &Buffers) {
        for (bind, out) in self.bind.iter_mut().zip(&b.outputs) {
            self.plain.bind(
                ctx,
                bind,
                &[
                    (em::U, &b.slab_uniforms.buffer),
                    (em::DENSITY, &b.density.buffer),
                    (em::COLOUR, &b.colour.buffer),
                    (em::CLASSES, &b.classes.buffer),
                    (em::VERTEX_BASE, &b.vertex_base.buffer),
                    (em::ACTIVE, &b.active.buffer),
                    (em::MC, &b.mc_tables),
                    (em::COUNTERS, &b.counters),
                    (em::VERTICES, &out.vertices.buffer),
                    (em::INDICES, &out.indices.buffer),
                ],
            );
        }
    }

    /// Records emission into output set `set` over the active cells of the slab at `offset`
    /// (indirect: arguments written by `slab_begin`).
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offset: u32,
        b: &Buffers,
        set: usize,
        colour: bool,
    ) {
        self.kernel(colour)
            .dispatch_indirect(pass, &self.bind[set], &[offset], &b.dispatch_args);
    }
}

impl Refine {
    /// Compiles the kernel.
    pub fn new(ctx: &GpuContext) -> Refine {
        let m = module(&ctx.device, "refine.wgsl", super::shaders::REFINE);
        Refine(
            Kernel::with_slots(ctx, &m, "main", rf::ALL),
            Default::default(),
        )
    }

    /// Refreshes the bind group of each output set (shared by every slab).
    pub fn prepare(&mut self, ctx: &GpuContext, b: &Buffers) {
        for (bind, out) in self.1.iter_mut().zip(&b.outputs) {
            self.0.bind(
                ctx,
                bind,
                &[
                    (rf::U, &b.slab_uniforms.buffer),
                    (rf::DENSITY, &b.density.buffer),
                    (rf::CLASSES, &b.classes.buffer),
                    (rf::VERTEX_BASE, &b.vertex_base.buffer),
                    (rf::ACTIVE, &b.active.buffer),
                    (rf::SORTED_ATOMS, &b.sorted_atoms.buffer),
                    (rf::CELL_END, &b.cell_end.buffer),
                    (rf::COUNTERS, &b.counters),
                    (rf::VERTICES, &out.vertices.buffer),
                ],
            );
        }
    }

    /// Records refinement of the vertices the slab at `offset` emitted into output set `set`
    /// (indirect, with the emission's arguments).
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, offset: u32, b: &Buffers, set: usize) {
        self.0
            .dispatch_indirect(pass, &self.1[set], &[offset], &b.dispatch_args);
    }
}
