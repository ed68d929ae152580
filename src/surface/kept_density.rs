//! A surface's sampled density kept after its computation, so that a later surface on the same
//! grid can be computed as a difference instead of from its atoms' Gaussians: the buried area
//! of an interface needs A, B and A with B on one grid, and the density is a sum over atoms, so
//! B's is the complex's less A's ([`crate::measure::interface_on`]).
//!
//! Only the CPU engine's dense path keeps one (a grid of at most
//! [`super::cpu::DENSE_MAX_SAMPLES`] samples); see [`super::SurfaceEngine::set_keep_density`].

use rayon::prelude::*;

use super::{GridSpec, SurfaceParams};

/// Samples per parallel chunk of [`KeptDensity::difference_into`].
const CHUNK: usize = 1 << 14;

/// The density of one surface at every sample of its grid.
#[derive(Debug, Clone, PartialEq)]
pub struct KeptDensity {
    /// The grid the density was sampled on.
    pub grid: GridSpec,
    /// The parameters the engine sampled with (refined vertices sample at quality max: the
    /// effective parameters, [`super::VertexMode::effective`]).
    pub params: SurfaceParams,
    /// Density per sample (dimensionless), x fastest ([`GridSpec::index`]).
    pub values: Vec<f32>,
}

impl KeptDensity {
    /// True when this density was sampled on `grid` under `params`, with a value per sample.
    pub fn fits(&self, grid: &GridSpec, params: &SurfaceParams) -> bool {
        self.grid == *grid
            && self.params == *params
            && self.values.len() as u64 == grid.voxel_count()
    }

    /// Writes `self - minus` sample by sample into `out` (resized to the grid). With `self` the
    /// density of atoms S and `minus` that of a subset M, sampled on the same grid, this is the
    /// density of S less M to rounding (a few f32 ulps of `self`'s value), and exactly it where
    /// no atom of M reaches (there `minus` is 0).
    pub(crate) fn difference_into(&self, minus: &KeptDensity, out: &mut Vec<f32>) {
        out.resize(self.values.len(), 0.0);
        out.par_chunks_mut(CHUNK)
            .zip(self.values.par_chunks(CHUNK))
            .zip(minus.values.par_chunks(CHUNK))
            .for_each(|((out, whole), minus)| {
                for ((o, w), m) in out.iter_mut().zip(whole).zip(minus) {
                    *o = w - m;
                }
            });
    }
}
