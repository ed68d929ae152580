//! Sizing one frame before anything is dispatched: the bin cell grid, the z-slabs the density and
//! Marching Cubes run in (so no buffer exceeds the device's binding limit or the memory budget),
//! the sparse bricks of [`BRICK`]^3 samples, and the bytes that costs. Pure arithmetic, tested
//! without a GPU.
//!
//! The bytes are computed in one place, [`BufferPlan`]: the engine's buffers
//! ([`super::resources::Buffers`]) are grown to exactly its sizes, and
//! [`BufferPlan::fresh_memory`] adds up what a fresh engine holds after a frame, so the GPU
//! memory of a frame is known without a device (`mdsurf bench --table1 --plan-only`) and
//! cannot drift from what the engine allocates (`tests/it/gpu_plan_memory.rs` checks both
//! against [`super::GpuEngine::gpu_bytes`]).

use crate::surface::{GridSpec, SurfaceParams};

use super::GpuError;
use super::types::{DrawIndexedArgs, GpuCounters, GpuVertex, McTablesUniform, SlabUniform};

mod bricks;
mod buffers;
#[cfg(test)]
mod tests;

pub use bricks::*;
pub use buffers::*;

/// Bytes per voxel of a slab: density 4, colour 12, class word 4, vertex base 4, active cell 8
/// (on sparse bricks density and colour are held per reached brick instead).
pub const BYTES_PER_VOXEL: u64 = 32;
/// Samples per sparse-brick edge (`BRICK` in `shaders/brick_const.wgsl`); one density thread's run of [`super::density::RUN`] voxels spans a brick row.
pub const BRICK: u32 = 8;
const _: () = assert!(BRICK == super::density::RUN);

/// Bytes per atom: positions 12, radius 4, packed colour 8, sorted atom 16, sorted colour 8.
pub const BYTES_PER_ATOM: u64 = 48;

/// One z-slab: the layers it owns and the layers of density it computes (owned plus one below
/// for the normals and two above for the shared top layer's edges and normals).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slab {
    /// First owned layer.
    pub own_z0: u32,
    /// One past the last owned layer.
    pub own_z1: u32,
    /// First density layer computed.
    pub dens_z0: u32,
    /// Density layers computed.
    pub dens_layers: u32,
}

/// Everything sized for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlan {
    /// The density grid.
    pub grid: GridSpec,
    /// Bin cell edge in Å.
    pub cell_size: f32,
    /// Bin cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Largest cutoff distance in Å.
    pub max_cut: f32,
    /// The slabs, bottom to top.
    pub slabs: Vec<Slab>,
    /// Layers classified per slab (largest owned count + 1, capped at nz).
    pub class_layers: u32,
    /// Largest density layer count of any slab.
    pub dens_layers: u32,
    /// Sparse bricks of [`BRICK`]^3 samples along x, y, z, covering the whole grid (the last
    /// brick along an axis may stick out of it).
    pub brick_dims: [u32; 3],
}

impl FramePlan {
    /// Number of bin cells.
    pub fn cell_count(&self) -> u64 {
        self.cell_dims.iter().map(|&d| d as u64).product()
    }

    /// Points classified per slab.
    pub fn class_points(&self) -> u64 {
        self.grid.dims[0] as u64 * self.grid.dims[1] as u64 * self.class_layers as u64
    }

    /// Voxels held in the density buffer.
    pub fn slab_voxels(&self) -> u64 {
        self.grid.dims[0] as u64 * self.grid.dims[1] as u64 * self.dens_layers as u64
    }

    /// Number of sparse bricks covering the grid.
    pub fn brick_count(&self) -> u64 {
        self.brick_dims.iter().map(|&d| d as u64).product()
    }

    /// Workgroups of 256 points in classification.
    pub fn class_blocks(&self) -> u64 {
        self.class_points().div_ceil(256)
    }

    /// Bricks the density layers of `slab` touch (whole brick layers).
    pub fn slab_bricks(&self, slab: &Slab) -> u64 {
        let bz0 = slab.dens_z0 / BRICK;
        let bz1 = (slab.dens_z0 + slab.dens_layers.max(1) - 1) / BRICK;
        (bz1 - bz0 + 1) as u64 * self.brick_dims[0] as u64 * self.brick_dims[1] as u64
    }

    /// The most brick slots one slab can use: every brick its density layers touch.
    pub fn max_slab_bricks(&self) -> u64 {
        self.slabs
            .iter()
            .map(|s| self.slab_bricks(s))
            .max()
            .unwrap_or(1)
    }
}

/// Plans a frame on `grid` for atoms of largest radius `max_radius` (Å). `max_binding` is the
/// largest storage binding (bytes), `volume_budget` the bytes allowed for slab buffers, and
/// `max_slab_layers` an optional cap on owned layers per slab (tests force slabs with it).
pub fn plan_frame(
    grid: GridSpec,
    params: &SurfaceParams,
    max_radius: f32,
    max_binding: u64,
    volume_budget: u64,
    max_slab_layers: Option<u32>,
) -> Result<FramePlan, GpuError> {
    let [nx, ny, nz] = grid.dims;
    let h = grid.spacing;
    let max_cut = params.cutoff() * params.radius_scale * max_radius;
    // Cells at least one cutoff wide (so 3 cells per axis reach) and one voxel wide, and few
    // enough that the per-cell arrays fit one binding.
    let mut cell_size = max_cut.max(h);
    let extent = [
        (nx - 1) as f32 * h,
        (ny - 1) as f32 * h,
        (nz - 1) as f32 * h,
    ];
    let dims_for = |c: f32| extent.map(|e| (e / c).floor() as u32 + 1);
    let limit = (max_binding / 4).min(u32::MAX as u64 / 2);
    loop {
        let d = dims_for(cell_size);
        let count: u64 = d.iter().map(|&v| v as u64).product();
        if count <= limit {
            break;
        }
        cell_size *= ((count as f64 / limit as f64).cbrt() as f32).max(1.01);
    }
    let cell_dims = dims_for(cell_size);

    let layer = nx as u64 * ny as u64;
    // The colour volume (12 bytes per voxel) is the largest per-voxel binding.
    let by_binding = max_binding / (12 * layer);
    let by_budget = volume_budget / (BYTES_PER_VOXEL * layer);
    let fit = by_binding
        .min(by_budget)
        .min(u32::MAX as u64 / layer.max(1));
    if fit < 4 {
        return Err(GpuError::TooLarge {
            what: "one 4-layer slab of the density grid",
            needed: 4 * BYTES_PER_VOXEL * layer,
            limit: by_binding.min(by_budget) * BYTES_PER_VOXEL * layer,
        });
    }
    let mut own = if fit as u32 >= nz { nz } else { fit as u32 - 3 };
    if let Some(cap) = max_slab_layers {
        own = own.min(cap.max(1));
    }
    let mut slabs = Vec::new();
    let mut z0 = 0;
    while z0 < nz {
        let z1 = (z0 + own).min(nz);
        let d0 = z0.saturating_sub(1);
        let d1 = (z1 + 2).min(nz);
        slabs.push(Slab {
            own_z0: z0,
            own_z1: z1,
            dens_z0: d0,
            dens_layers: d1 - d0,
        });
        z0 = z1;
    }
    let dens_layers = slabs.iter().map(|s| s.dens_layers).max().unwrap_or(1);
    Ok(FramePlan {
        grid,
        cell_size,
        cell_dims,
        max_cut,
        slabs,
        class_layers: (own + 1).min(nz),
        dens_layers,
        brick_dims: grid.dims.map(|d| d.div_ceil(BRICK)),
    })
}
