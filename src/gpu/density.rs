//! Density and colour stage (the paper's t_d): `shaders/density.wgsl` gathers, for every voxel of
//! a slab, the Gaussians of the atoms in the neighbouring bin cells, eight voxels along x per
//! thread. Density and colour are fused in one pass; pipeline variants skip the colour volume
//! (no colours) or the density write (a colour-only change keeps the density as it is). Each
//! variant has a dense entry point (every voxel of the slab) and two sparse ones (the bricks
//! [`super::bricks`] listed, dispatched indirectly, writing brick-local slots): each thread
//! loading its own atoms ([`DensityGather::Rows`]), or the brick's threads staging the atoms
//! around the brick in workgroup memory and sharing them ([`DensityGather::Tiled`]). Both
//! sparse gathers give every voxel the same bits.

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

/// How the sparse-brick gather reads its atoms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DensityGather {
    /// Each thread walks the bin cells around its own run of voxels and loads their atoms.
    Rows,
    /// The 64 threads of a brick load the atoms of the cells around the brick once, in
    /// chunks of 64, into workgroup memory, and each thread tests every staged atom.
    Tiled,
    /// Tiled where a brick is small against the bin cells, rows where it is large (see
    /// [`DensityGather::resolve`]).
    #[default]
    Auto,
}

/// The largest brick edge, in bin cells, for which [`DensityGather::Auto`] tiles. A brick
/// spans (BRICK - 1) H; the cells around it are more than each thread's own by a factor that
/// grows with that span, and past about three cells the extra atoms every thread tests cost
/// more than the loads it shares (NVIDIA H100, Table 1 rows, 2026-11-26: tiled 1.6x faster at
/// H = 1 Å, 1.1x at H = 2 Å, 1.6x slower at H = 4 Å, with cells of 4.5 to 6 Å).
pub const TILED_MAX_BRICK_CELLS: f32 = 3.0;

impl DensityGather {
    /// The gather that runs for a grid of spacing `h` (Å) binned in cells of `cell_size` (Å):
    /// [`DensityGather::Auto`] becomes tiled when a brick spans at most
    /// [`TILED_MAX_BRICK_CELLS`] cells, else rows.
    pub fn resolve(self, h: f32, cell_size: f32) -> DensityGather {
        match self {
            DensityGather::Auto => {
                let span = (super::plan::BRICK - 1) as f32 * h;
                if span <= TILED_MAX_BRICK_CELLS * cell_size {
                    DensityGather::Tiled
                } else {
                    DensityGather::Rows
                }
            }
            g => g,
        }
    }
}

/// The density kernels (three variants, dense and sparse, on one layout) and their cached bind
/// group.
#[derive(Debug)]
pub struct DensityStage {
    /// Dense entry points: with colour, plain, colour only.
    dense: [Kernel; 3],
    /// Sparse-brick entry points, each thread loading its own atoms, in the same order.
    sparse: [Kernel; 3],
    /// Sparse-brick entry points with the atoms staged per brick, in the same order.
    tiled: [Kernel; 3],
    /// Which sparse entry points [`DensityStage::record_sparse`] records (resolved for the
    /// frame's grid, never [`DensityGather::Auto`]).
    pub gather: DensityGather,
    bind: Bound,
}

impl DensityStage {
    /// Compiles the variants.
    pub fn new(ctx: &GpuContext) -> DensityStage {
        let m = module(&ctx.device, "density.wgsl", super::shaders::DENSITY);
        let layout = Layout::new(ctx, "density", b::ALL);
        let variants: [&[(&str, f64)]; 3] = [
            &[("WITH_COLOUR", 1.0)],
            &[("WITH_COLOUR", 0.0)],
            &[("WITH_COLOUR", 1.0), ("WRITE_DENSITY", 0.0)],
        ];
        DensityStage {
            dense: variants.map(|c| Kernel::new(ctx, &m, "main", c, &layout)),
            sparse: variants.map(|c| Kernel::new(ctx, &m, "bricks", c, &layout)),
            tiled: variants.map(|c| Kernel::new(ctx, &m, "bricks_tiled", c, &layout)),
            gather: DensityGather::default(),
            bind: Bound::default(),
        }
    }

    fn variant(mode: DensityMode) -> usize {
        match mode {
            DensityMode::WithColour => 0,
            DensityMode::Plain => 1,
            DensityMode::ColourOnly => 2,
        }
    }

    /// Refreshes the bind group (every variant and slab shares it; the slab uniform is bound
    /// at a dynamic offset).
    pub fn prepare(&mut self, ctx: &GpuContext, bufs: &Buffers) {
        self.dense[0].bind(
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
                (b::ACTIVE_BRICKS, &bufs.active_bricks.buffer),
                (b::COUNTERS, &bufs.counters),
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
        self.dense[Self::variant(mode)].dispatch(
            pass,
            &self.bind,
            &[offset],
            [runs.div_ceil(4), dims[1].div_ceil(4), layers.div_ceil(4)],
        );
    }

    /// Records the gather over the reached bricks of the slab whose uniform is at `offset`
    /// (one workgroup per listed brick; indirect, with the arguments of [`super::bricks`]),
    /// into the brick slots of the density and colour buffers.
    pub fn record_sparse(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offset: u32,
        args: &wgpu::Buffer,
        mode: DensityMode,
    ) {
        let kernels = match self.gather {
            DensityGather::Rows => &self.sparse,
            DensityGather::Tiled | DensityGather::Auto => &self.tiled,
        };
        kernels[Self::variant(mode)].dispatch_indirect(pass, &self.bind, &[offset], args);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_tiles_small_bricks_only() {
        // 5 Å cells: a brick of 7 Å (H = 1) or 14 Å (H = 2) spans at most three cells, one
        // of 28 Å (H = 4) more.
        assert_eq!(DensityGather::Auto.resolve(1.0, 5.0), DensityGather::Tiled);
        assert_eq!(DensityGather::Auto.resolve(2.0, 5.0), DensityGather::Tiled);
        assert_eq!(DensityGather::Auto.resolve(4.0, 5.0), DensityGather::Rows);
        // Explicit choices stay.
        assert_eq!(DensityGather::Rows.resolve(1.0, 5.0), DensityGather::Rows);
        assert_eq!(DensityGather::Tiled.resolve(4.0, 5.0), DensityGather::Tiled);
    }
}
