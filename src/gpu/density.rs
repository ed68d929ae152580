//! Density and colour stage (the paper's t_d): `shaders/density.wgsl` gathers, for every voxel of
//! a slab, the Gaussians of the atoms in the neighbouring bin cells, eight voxels along x per
//! thread. Density and colour are fused in one pass; pipeline variants skip the colour volume
//! (no colours) or the density write (a colour-only change keeps the density as it is).

use super::kernel::{Kernel, module};
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

/// The density kernels.
#[derive(Debug)]
pub struct DensityStage {
    with_colour: Kernel,
    plain: Kernel,
    colour_only: Kernel,
}

impl DensityStage {
    /// Compiles both variants.
    pub fn new(device: &wgpu::Device) -> DensityStage {
        let m = module(device, "density.wgsl", super::shaders::DENSITY);
        DensityStage {
            with_colour: Kernel::new(device, &m, "main", &[("WITH_COLOUR", 1.0)]),
            plain: Kernel::new(device, &m, "main", &[("WITH_COLOUR", 0.0)]),
            colour_only: Kernel::new(
                device,
                &m,
                "main",
                &[("WITH_COLOUR", 1.0), ("WRITE_DENSITY", 0.0)],
            ),
        }
    }

    fn kernel(&self, mode: DensityMode) -> &Kernel {
        match mode {
            DensityMode::Plain => &self.plain,
            DensityMode::WithColour => &self.with_colour,
            DensityMode::ColourOnly => &self.colour_only,
        }
    }

    /// Bind group for one slab uniform.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        b: &Buffers,
        slab_uniform: wgpu::BindingResource<'_>,
        mode: DensityMode,
    ) -> wgpu::BindGroup {
        self.kernel(mode).bind(
            device,
            &[
                (0, slab_uniform),
                (1, b.sorted_atoms.buffer.as_entire_binding()),
                (2, b.sorted_colours.buffer.as_entire_binding()),
                (3, b.cell_start.buffer.as_entire_binding()),
                (4, b.cell_end.buffer.as_entire_binding()),
                (5, b.density.buffer.as_entire_binding()),
                (6, b.colour.buffer.as_entire_binding()),
            ],
        )
    }

    /// Records the gather over `dims[0] x dims[1] x layers` voxels.
    pub fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &wgpu::BindGroup,
        dims: [u32; 3],
        layers: u32,
        mode: DensityMode,
    ) {
        let runs = dims[0].div_ceil(RUN);
        self.kernel(mode).dispatch(
            pass,
            bind,
            [runs.div_ceil(4), dims[1].div_ceil(4), layers.div_ceil(4)],
        );
    }
}
