//! The interface every surface engine offers (the CPU reference here, the GPU engine in
//! [`crate::gpu`]): atoms in, mesh plus measurements and stage timings out.

use glam::Vec3;

use super::{GridSpec, Mesh, SurfaceError, SurfaceParams};

/// The particles one surface is built from. All slices have the same length.
#[derive(Debug, Clone, Copy)]
pub struct AtomSet<'a> {
    /// Positions in Å.
    pub positions: &'a [Vec3],
    /// Radii in Å (before scaling by R).
    pub radii: &'a [f32],
    /// Linear RGB colour per atom in 0..1; `None` gives a white surface and skips the colour pass.
    pub colours: Option<&'a [[f32; 3]]>,
}

/// Wall-clock or GPU-timestamp time of each stage, in milliseconds (0 where a stage did not run).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimings {
    /// Upload of positions (and radii/colours when they changed) to the engine.
    pub upload_ms: f64,
    /// Binning atoms into cells (the paper's t_sort).
    pub bin_ms: f64,
    /// Density and colour volumes (the paper's t_d).
    pub density_ms: f64,
    /// Marching Cubes, area and volume (the paper's t_MC).
    pub mc_ms: f64,
}

impl StageTimings {
    /// Binning + density + Marching Cubes in ms (the paper's Table 1 total).
    pub fn compute_ms(&self) -> f64 {
        self.bin_ms + self.density_ms + self.mc_ms
    }
}

/// One computed surface.
#[derive(Debug, Clone, Default)]
pub struct SurfaceOutput {
    /// The grid the density was sampled on.
    pub grid: GridSpec,
    /// The isosurface.
    pub mesh: Mesh,
    /// Surface area in Å².
    pub area: f64,
    /// Enclosed volume in Å³.
    pub volume: f64,
    /// Time spent per stage.
    pub timings: StageTimings,
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims: [0; 3],
        }
    }
}

/// A surface engine (CPU or GPU).
pub trait SurfaceEngine {
    /// Short name for messages and benchmark tables (`cpu`, `gpu`).
    fn name(&self) -> &str;

    /// Computes the surface of `atoms` under `params`.
    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError>;
}
