//! The CPU reference engine: validates the input, then runs binning ([`super::bin`]), density
//! ([`super::density`]) and Marching Cubes ([`super::marching_cubes`]) with rayon, timing each
//! stage. It is the oracle the GPU engine is tested against and the engine on machines without
//! a GPU.

use std::time::Instant;

use super::bin::bin_atoms;
use super::{
    AtomSet, GridSpec, StageTimings, SurfaceEngine, SurfaceError, SurfaceOutput, SurfaceParams,
    available_memory_bytes, density, marching_cubes,
};

/// The multi-threaded CPU surface engine (uses rayon's global thread pool).
#[derive(Debug, Clone, Default)]
pub struct CpuEngine {
    memory_limit: Option<u64>,
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
        let volume = density::compute_binned(&bins, params, &grid, atoms.colours.is_some());
        drop(bins);
        let density_ms = ms(t);

        let t = Instant::now();
        let mesh = marching_cubes::extract(&grid, &volume, params.isovalue);
        drop(volume);
        let area = mesh.area();
        let enclosed = mesh.volume();
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
