//! The surface definition and the CPU reference engine: parameters, grid, density and colour
//! volumes, Marching Cubes, area and volume (DESIGN section 2). The GPU engine in [`crate::gpu`]
//! is tested against this module.

pub mod analytic;
pub mod bin;
pub(crate) mod brick_mc;
pub(crate) mod bricks;
pub mod cpu;
pub mod curved;
pub mod density;
pub(crate) mod engine;
pub(crate) mod grid;
pub(crate) mod kept_density;
pub mod marching_cubes;
pub(crate) mod mc_vertex;
pub(crate) mod memory;
pub(crate) mod mesh;
pub(crate) mod params;
pub mod periodic;
pub(crate) mod preset;
pub mod same_grid;
pub(crate) mod scan;
pub mod tables;

pub use analytic::VertexMode;
pub use bricks::BrickStats;
pub use cpu::CpuEngine;
pub use density::DensityVolume;
pub use engine::{AtomSet, MeshCounts, StageTimings, SurfaceEngine, SurfaceOutput};
pub use grid::{GridSpec, available_memory_bytes, estimate_grid_bytes};
pub use kept_density::KeptDensity;
pub use mesh::Mesh;
pub use params::{Quality, SurfaceParams};
pub use preset::{Preset, RadiusSet};
pub use tables::McTables;

/// Why a surface could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// H, R or I was not a positive finite number.
    #[error("{name} must be a positive number, got {value}")]
    InvalidParameter {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: String,
    },
    /// H, R or I was a positive number outside the range that makes sense for it
    /// ([`params::SPACING_RANGE`] and its siblings).
    #[error("{name} = {value} is outside {min} to {max}")]
    OutOfRange {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: String,
        /// Smallest value allowed.
        min: f32,
        /// Largest value allowed.
        max: f32,
    },
    /// There were no atoms.
    #[error("the system has no atoms")]
    EmptySystem,
    /// An atom had a NaN or infinite coordinate.
    #[error("atom {atom} has a NaN or infinite coordinate")]
    NonFiniteCoordinate {
        /// Index of the atom (from 0).
        atom: usize,
    },
    /// An atom had a radius that is not positive and finite.
    #[error("atom {atom} has radius {radius} Å; radii must be positive")]
    InvalidRadius {
        /// Index of the atom (from 0).
        atom: usize,
        /// Its radius in Å.
        radius: f32,
    },
    /// The per-atom slices have different lengths.
    #[error("{got} {what} given for {expected} atoms")]
    LengthMismatch {
        /// Which slice (`radii`, `colours`).
        what: &'static str,
        /// Number of atoms (positions).
        expected: usize,
        /// Length of the slice.
        got: usize,
    },
    /// An atom had a NaN or infinite colour component.
    #[error("atom {atom} has a NaN or infinite colour")]
    NonFiniteColour {
        /// Index of the atom (from 0).
        atom: usize,
    },
    /// The GPU engine failed (no adapter, device lost, readback failed, too large).
    #[error("{0}")]
    Gpu(String),
    /// The grid would not fit in memory.
    #[error(
        "a {}x{}x{} grid needs {:.1} GB but only {:.1} GB is available; use a larger grid spacing H",
        dims[0], dims[1], dims[2], *bytes_needed as f64 / 1e9, *bytes_available as f64 / 1e9
    )]
    GridTooLarge {
        /// Grid samples along x, y, z.
        dims: [u64; 3],
        /// Bytes the computation would need.
        bytes_needed: u64,
        /// Bytes the engine may use.
        bytes_available: u64,
    },
}
