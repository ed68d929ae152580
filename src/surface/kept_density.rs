//! A surface's sampled density kept after its computation, so that a later surface on the same
//! grid can be computed as a difference instead of from its atoms' Gaussians: the buried area
//! of an interface needs A, B and A with B on one grid, and the density is a sum over atoms, so
//! B's is the complex's less A's ([`crate::measure::interface_on`]).
//!
//! The CPU engine keeps it on request ([`super::SurfaceEngine::set_keep_density`]), as every
//! sample of a dense grid or as the occupied sparse bricks.

use rayon::prelude::*;

use super::bricks::BrickVolume;
use super::{GridSpec, SurfaceParams};

/// Samples per parallel chunk of [`dense_difference_into`].
const CHUNK: usize = 1 << 14;

/// The density of one surface on its grid.
#[derive(Debug, Clone)]
pub struct KeptDensity {
    /// The grid the density was sampled on.
    pub grid: GridSpec,
    /// The parameters the engine sampled with (refined vertices sample at quality max: the
    /// effective parameters, [`super::VertexMode::effective`]).
    pub params: SurfaceParams,
    /// The samples, as the engine stored them.
    pub(crate) samples: KeptSamples,
}

/// How a kept density stores its samples.
#[derive(Debug, Clone)]
pub(crate) enum KeptSamples {
    /// Every sample (dimensionless), x fastest ([`GridSpec::index`]).
    Dense(Vec<f32>),
    /// The occupied bricks (every other sample is 0).
    Bricks(BrickVolume),
}

impl KeptDensity {
    /// True when this density was sampled on `grid` under `params`.
    pub fn fits(&self, grid: &GridSpec, params: &SurfaceParams) -> bool {
        let stored = match &self.samples {
            KeptSamples::Dense(values) => values.len() as u64 == grid.voxel_count(),
            KeptSamples::Bricks(bricks) => bricks.grid == *grid,
        };
        self.grid == *grid && self.params == *params && stored
    }

    /// Every sample, when kept dense.
    pub(crate) fn dense(&self) -> Option<&[f32]> {
        match &self.samples {
            KeptSamples::Dense(values) => Some(values),
            KeptSamples::Bricks(_) => None,
        }
    }

    /// The occupied bricks, when kept sparse.
    pub(crate) fn bricks(&self) -> Option<&BrickVolume> {
        match &self.samples {
            KeptSamples::Bricks(bricks) => Some(bricks),
            KeptSamples::Dense(_) => None,
        }
    }
}

/// Writes `whole - minus` sample by sample into `out` (resized to their length). With `whole`
/// the density of atoms S and `minus` that of a subset M on the same grid, this is the density
/// of S less M to rounding (a few f32 ulps of `whole`'s value), and exactly it where no atom of
/// M reaches (there `minus` is 0).
pub(crate) fn dense_difference_into(whole: &[f32], minus: &[f32], out: &mut Vec<f32>) {
    out.resize(whole.len(), 0.0);
    out.par_chunks_mut(CHUNK)
        .zip(whole.par_chunks(CHUNK))
        .zip(minus.par_chunks(CHUNK))
        .for_each(|((out, whole), minus)| {
            for ((o, w), m) in out.iter_mut().zip(whole).zip(minus) {
                *o = w - m;
            }
        });
}
