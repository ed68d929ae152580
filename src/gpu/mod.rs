//! The GPU surface engine: the whole per-frame surface computed in wgpu compute shaders
//! (DESIGN section 3). Atoms are uploaded ([`engine`]), binned into cells by counting sort
//! ([`bin`], [`scan`]; before it, the SES preset's exposure radii, [`exposure`]), the sparse bricks the atoms reach listed ([`bricks`]), the density and
//! colour volumes gathered per voxel of those bricks ([`density`]), and the
//! surface extracted by Marching Cubes ([`mc`]: classify, compact, emit) and measured
//! ([`measure`]). [`frame`] records a frame's passes, [`plan`] sizes it (cells, z-slabs),
//! [`timing`] reads timestamp queries, [`output`] brings counters back asynchronously.
//! [`layout`] names every binding once (explicit bind-group layouts, checked against the WGSL);
//! [`kernel`] caches bind groups across frames, so a steady-state frame creates no GPU object
//! ([`GpuEngine::objects_created`] counts them through [`GpuContext`]).
//! [`context`] opens the one headless device (or wraps the viewer's), [`factory`] picks the
//! engine for a backend (viewer, `render`, `surface`, `bench`). [`GpuEngine`] runs a frame:
//! blocking through [`crate::surface::SurfaceEngine`] (CLI, tests)
//! or non-blocking into a [`GpuSurface`] the renderer draws from (viewer). [`tolerance`] holds
//! the CPU-parity tolerances, [`table1`] reproduces the paper's Table 1. The shaders live in
//! `shaders/`, one file per stage.

pub mod bin;
pub(crate) mod bricks;
pub(crate) mod context;
pub(crate) mod density;
pub mod engine;
pub mod exposure;
pub(crate) mod factory;
pub mod frame;
pub mod inputs;
pub(crate) mod kernel;
pub mod layout;
pub(crate) mod mc;
pub(crate) mod measure;
pub(crate) mod options;
pub mod output;
pub mod plan;
pub(crate) mod resources;
pub(crate) mod scan;
#[cfg(test)]
mod shader_constants;
pub mod shaders;
pub mod table1;
pub(crate) mod timing;
pub mod tolerance;
pub(crate) mod types;

pub use context::{GpuContext, GpuObjects, SOFTWARE_ADAPTER, gpu_required};
pub use density::DensityGather;
pub use engine::{Changes, EngineOptions, FrameInfo, GpuEngine};
pub use factory::{Backend, Picked, pick_engine};
pub use frame::Work;
pub use output::{FrameStats, GpuSurface};
pub use types::{DrawIndexedArgs, GpuCounters, GpuVertex};

/// Why the GPU engine failed.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No usable adapter was found.
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// Creating or using the device failed (lost device, validation error, out of memory).
    #[error("GPU device error: {0}")]
    Device(String),
    /// Reading results back failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// The adapter binds too few storage buffers per compute stage for the engine (Mesa 21.2's
    /// lavapipe allows 3).
    #[error(
        "the GPU engine binds {needed} storage buffers in one compute stage; this adapter allows {allowed}"
    )]
    TooFewStorageBuffers {
        /// What the engine's widest compute layout binds.
        needed: u32,
        /// What the device allows.
        allowed: u32,
    },
    /// A problem is too large for this device even when split into slabs.
    #[error("{what} needs {needed} bytes but the device allows {limit}")]
    TooLarge {
        /// What did not fit.
        what: &'static str,
        /// Bytes it needs.
        needed: u64,
        /// Bytes the device allows.
        limit: u64,
    },
}

impl From<GpuError> for crate::surface::SurfaceError {
    fn from(e: GpuError) -> Self {
        crate::surface::SurfaceError::Gpu(e.to_string())
    }
}
