//! The CPU reference engine: validates the input, then runs binning ([`super::bin`]), density
//! ([`super::density`]) and Marching Cubes ([`super::marching_cubes`]) with rayon, timing each
//! stage. It is the oracle the GPU engine is tested against and the engine on machines without
//! a GPU.

use std::time::Instant;

use super::bin::bin_atoms;
use super::marching_cubes::{McScratch, extract_with};
use super::{
    AtomSet, DensityVolume, GridSpec, StageTimings, SurfaceEngine, SurfaceError, SurfaceOutput,
    SurfaceParams, available_memory_bytes, density,
};

/// The multi-threaded CPU surface engine (uses rayon's global thread pool). It keeps the last
/// density volume and the Marching Cubes buffers between calls (about 4 bytes per grid sample,
/// 16 with colours), so a sequence of frames allocates them once.
#[derive(Default)]
pub struct CpuEngine {
    memory_limit: Option<u64>,
    /// Density volume kept between calls (reused when the grid keeps its size).
    volume: DensityVolume,
    /// Marching Cubes working memory kept between calls.
    mc: McScratch,
}

impl std::fmt::Debug for CpuEngine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CpuEngine")
            .field("memory_limit", &self.memory_limit)
            .field("kept_samples", &self.volume.values.len())
            .finish()
    }
}

impl CpuEngine {
    /// An engine that refuses grids larger than the memory currently available.
    pub fn new() -> CpuEngine {
        CpuEngine::default()
    }

    /// An engine that refuses grids whose estimate ([`super::estimate_grid_bytes`]) exceeds
    /// `bytes` instead of the available memory (for tests and embedding).
    pub fn with_memory_limit(bytes: u64) -> CpuEngine {
        CpuEngine {
            memory_limit: Some(bytes),
            ..CpuEngine::default()
        }
    }

    /// The grid `atoms` need under `params`, after checking the atoms, the parameters and that
    /// the grid fits in memory.
    pub fn plan(
        &self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<GridSpec, SurfaceError> {
        params.validate()?;
        atoms.validate()?;
        let grid = GridSpec::for_atoms(atoms.positions, atoms.radii, params)?;
        let needed = grid.estimated_bytes(atoms.colours.is_some());
        let available = self.memory_limit.unwrap_or_else(available_memory_bytes);
        if needed > available {
            return Err(SurfaceError::GridTooLarge {
                dims: grid.dims.map(u64::from),
                bytes_needed: needed,
                bytes_available: available,
            });
        }
        Ok(grid)
    }
}

impl SurfaceEngine for CpuEngine {
    fn name(&self) -> &str {
        "cpu"
    }

    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError> {
        let grid = self.plan(atoms, params)?;
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;

        let t = Instant::now();
        let bins = bin_atoms(atoms, params, &grid, density::slab_planes(&grid));
        let bin_ms = ms(t);

        let t = Instant::now();
        let with_colour = atoms.colours.is_some();
        density::compute_binned_into(&bins, params, &grid, with_colour, &mut self.volume);
        drop(bins);
        let density_ms = ms(t);

        let t = Instant::now();
        let mesh = extract_with(&grid, &self.volume, params.isovalue, &mut self.mc);
        let (area, enclosed) = mesh.area_and_volume();
        let mc_ms = ms(t);

        Ok(SurfaceOutput {
            grid,
            mesh,
            area,
            volume: enclosed,
            timings: StageTimings {
                upload_ms: 0.0,
                bin_ms,
                density_ms,
                mc_ms,
            },
        })
    }
}
