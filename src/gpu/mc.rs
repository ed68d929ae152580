//! Marching Cubes stages (the paper's t_MC) over one slab: [`Classify`] (`shaders/classify.wgsl`:
//! case byte, crossed own edges and triangle count per point, sums per 256-point block), three
//! scans of the block sums ([`super::scan`]), [`Compact`] (`shaders/compact.wgsl`: global vertex
//! base per point and the list of active cells) and [`Emit`] (`shaders/emit.wgsl`: shared
//! vertices per crossed edge and indexed triangles, dispatched indirectly over the active cells).

use super::kernel::{Kernel, groups_1d, module};
use super::resources::Buffers;

/// Classification kernel.
#[derive(Debug)]
pub struct Classify(Kernel);

/// Compaction kernel.
#[derive(Debug)]
pub struct Compact(Kernel);

/// Emission kernels (with and without the colour volume).
#[derive(Debug)]
pub struct Emit {
    with_colour: Kernel,
    plain: Kernel,
}

impl Classify {
    /// Compiles the kernel.
    pub fn new(device: &wgpu::Device) -> Classify {
        let m = module(device, "classify.wgsl", super::shaders::CLASSIFY);
        Classify(Kernel::new(device, &m, "main", &[]))
    }

    /// Bind group for one slab uniform.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        b: &Buffers,
        slab_uniform: wgpu::BindingResource<'_>,
    ) -> wgpu::BindGroup {
        self.0.bind(
            device,
            &[
                (0, slab_uniform),
                (1, b.density.buffer.as_entire_binding()),
                (2, b.mc_tables.as_entire_binding()),
                (3, b.classes.buffer.as_entire_binding()),
                (4, b.block_sums[0].buffer.as_entire_binding()),
                (5, b.block_sums[1].buffer.as_entire_binding()),
                (6, b.block_sums[2].buffer.as_entire_binding()),
            ],
        )
    }

    /// Records classification of `blocks` blocks of 256 points.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &wgpu::BindGroup,
        blocks: u64,
        max_groups: u32,
    ) {
        self.0.dispatch(pass, bind, groups_1d(blocks, max_groups));
    }
}

impl Compact {
    /// Compiles the kernel.
    pub fn new(device: &wgpu::Device) -> Compact {
        let m = module(device, "compact.wgsl", super::shaders::COMPACT);
        Compact(Kernel::new(device, &m, "main", &[]))
    }

    /// Bind group for one slab uniform.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        b: &Buffers,
        slab_uniform: wgpu::BindingResource<'_>,
    ) -> wgpu::BindGroup {
        self.0.bind(
            device,
            &[
                (0, slab_uniform),
                (1, b.classes.buffer.as_entire_binding()),
                (2, b.block_sums[0].buffer.as_entire_binding()),
                (3, b.block_sums[1].buffer.as_entire_binding()),
                (4, b.block_sums[2].buffer.as_entire_binding()),
                (5, b.counters.as_entire_binding()),
                (6, b.vertex_base.buffer.as_entire_binding()),
                (7, b.active.buffer.as_entire_binding()),
            ],
        )
    }

    /// Records compaction of `blocks` blocks of 256 points.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &wgpu::BindGroup,
        blocks: u64,
        max_groups: u32,
    ) {
        self.0.dispatch(pass, bind, groups_1d(blocks, max_groups));
    }
}

impl Emit {
    /// Compiles both variants.
    pub fn new(device: &wgpu::Device) -> Emit {
        let m = module(device, "emit.wgsl", super::shaders::EMIT);
        Emit {
            with_colour: Kernel::new(device, &m, "main", &[("WITH_COLOUR", 1.0)]),
            plain: Kernel::new(device, &m, "main", &[("WITH_COLOUR", 0.0)]),
        }
    }

    fn kernel(&self, colour: bool) -> &Kernel {
        if colour {
            &self.with_colour
        } else {
            &self.plain
        }
    }

    /// Bind group for one slab uniform.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        b: &Buffers,
        slab_uniform: wgpu::BindingResource<'_>,
        colour: bool,
    ) -> wgpu::BindGroup {
        self.kernel(colour).bind(
            device,
            &[
                (0, slab_uniform),
                (1, b.density.buffer.as_entire_binding()),
                (2, b.colour.buffer.as_entire_binding()),
                (3, b.classes.buffer.as_entire_binding()),
                (4, b.vertex_base.buffer.as_entire_binding()),
                (5, b.active.buffer.as_entire_binding()),
                (6, b.mc_tables.as_entire_binding()),
                (8, b.counters.as_entire_binding()),
                (9, b.vertices.buffer.as_entire_binding()),
                (10, b.indices.buffer.as_entire_binding()),
            ],
        )
    }

    /// Records emission over the active cells (indirect: arguments written by `slab_begin`).
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &wgpu::BindGroup,
        b: &Buffers,
        colour: bool,
    ) {
        self.kernel(colour)
            .dispatch_indirect(pass, bind, &b.dispatch_args);
    }
}
