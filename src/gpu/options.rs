//! The caller-facing knobs and reports of [`super::GpuEngine`]: engine options (slab cap, memory
//! budget, mesh capacity, headroom, sparse bricks), what changed since the previous frame, and what a submitted
//! frame did.

use super::GpuContext;
use super::density::DensityGather;
use super::frame::Work;
use crate::surface::GridSpec;

/// Tuning knobs (tests force slabs and overflows with them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineOptions {
    /// Most owned z layers per slab (None: as many as the device limits allow).
    pub max_slab_layers: Option<u32>,
    /// Bytes the per-voxel slab buffers may take (default: a quarter of the largest buffer,
    /// at most 4 GiB).
    pub volume_budget: u64,
    /// Initial mesh capacity (vertices, triangles); None estimates it from the grid.
    pub initial_mesh_capacity: Option<(u32, u32)>,
    /// Factor by which the mesh buffers exceed the last frame's counts when they grow.
    pub headroom: f32,
    /// Sample and classify only the bricks of [`super::plan::BRICK`]^3 samples that some atom
    /// reaches ([`super::bricks`]; default). False: every voxel of the grid (the dense path,
    /// kept to compare with). Both give the same mesh.
    pub sparse_bricks: bool,
    /// Initial brick slots of the sparse density and colour buffers (reached bricks they
    /// hold); None counts the first sparse frame's reached bricks before its density runs
    /// ([`super::plan::settled_brick_slots`]). They grow from the reached-brick count,
    /// re-running density when a frame's bricks did not fit.
    pub initial_brick_slots: Option<u64>,
    /// How the sparse-brick density gather reads its atoms (both give the same bits).
    pub density_gather: DensityGather,
}

impl EngineOptions {
    pub(crate) fn defaults(ctx: &GpuContext) -> EngineOptions {
        EngineOptions {
            max_slab_layers: None,
            volume_budget: ctx.device_limits().volume_budget(),
            initial_mesh_capacity: None,
            headroom: super::plan::DEFAULT_HEADROOM,
            sparse_bricks: true,
            initial_brick_slots: None,
            density_gather: DensityGather::default(),
        }
    }
}

/// What the caller knows changed since its previous frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Changes {
    /// Positions changed (new trajectory frame).
    pub positions: bool,
    /// Radii changed (or the atom set itself).
    pub radii: bool,
    /// Colours changed (colour scheme).
    pub colours: bool,
}

impl Changes {
    /// Everything changed.
    pub const ALL: Changes = Changes {
        positions: true,
        radii: true,
        colours: true,
    };
}

/// What one submit did.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameInfo {
    /// Frame number (matches [`super::FrameStats::frame`]).
    pub frame: u64,
    /// The grid.
    pub grid: GridSpec,
    /// Number of z-slabs the grid was split into.
    pub slabs: usize,
    /// Wall-clock time of validation and upload in ms.
    pub upload_ms: f64,
    /// Which stages ran.
    pub work: Work,
}
