//! Density and colour stage (the paper's t_d): `shaders/density.wgsl` gathers, for every voxel of
//! a slab, the Gaussians of the atoms in the neighbouring bin cells, eight voxels along x per
//! thread. Density and colour are fused in one pass; pipeline variants skip the colour volume
//! (no colours) or the density write (a colour-only change keeps the density as it is).

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Layout, module};
use super::layout::density as b;
use super::resources::Buffers;

/// Voxels per thread along x (`RUN` in the shader).
pub const RUN: u32 = 8;

/// What one density pass computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DensityMode {
    /// Density only (white surface).
    Plain,
    /// Density and colour volume.
    WithColour,
    /// Colour volume only (the colour scheme changed; the density stays).
    ColourOnly,
}

/// The density kernels (three variants on one layout) and their cached bind group.
#[derive(Debug)]
pub struct DensityStage {
    with_colour: Kernel,
    plain: Kernel,
    colour_only: Kernel,
    bind: Bound,
}

impl DensityStage {
    /// Compiles the variants.
    pub fn new(ctx: &GpuContext) -> DensityStage {
        let m = module(&ctx.device, "density.wgsl", super::shaders::DENSITY);
        let layout = Layout::new(ctx, "density", b::ALL);
        DensityStage {
            with_colour: Kernel::new(ctx, &m, "main", &[("WITH_COLOUR", 1.0)], &layout),
            plain: Kernel::new(ctx, &m, "main", &[("WITH_COLOUR", 0.0)], &layout),
            colour_only: Kernel::new(
                ctx,
                &m,
                "main",
                &[("WITH_COLOUR", 1.0), ("WRITE_DENSITY", 0.0)],
                &layout,
            ),
            bind: Bound::default(),
        }
    }

    fn kernel(&self, mode: DensityMode) -> &Kernel {
        match mode {
            DensityMode::Plain => &self.plain,
            DensityMode::WithColour => &self.with_colour,
            DensityMode::ColourOnly => &self.colour_only,
        }
    }

    /// Refreshes the bind group (every variant and slab shares it; the slab uniform is bound
    /// at a dynamic offset).
    pub fn prepare(&mut self, ctx: &GpuContext, bufs: &Buffers) {
        self.plain.bind(
            ctx,
            &mut self.bind,
            &[
                (b::U, &bufs.slab_uniforms.buffer),
                (b::SORTED_ATOMS, &bufs.sorted_atoms.buffer),
                (b::SORTED_COLOURS, &bufs.sorted_colours.buffer),
                (b::CELL_START, &bufs.cell_start.buffer),
                (b::CELL_END, &bufs.cell_end.buffer),
                (b::DENSITY, &bufs.density.buffer),
                (b::COLOUR, &bufs.colour.buffer),
            ],
        );
    }

    /// Records the gather over `dims[0] x dims[1] x layers` voxels of the slab whose uniform is
    /// at `offset`.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offset: u32,
        dims: [u32; 3],
        layers: u32,
        mode: DensityMode,
    ) {
        let runs = dims[0].div_ceil(RUN);
        self.kernel(mode).dispatch(
            pass,
            &self.bind,
            &[offset],
            [runs.div_ceil(4), dims[1].div_ceil(4), layers.div_ceil(4)],
        );
    }
}
