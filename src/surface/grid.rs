//! The sampling grid: where the density is evaluated. DESIGN section 2: origin = bounding-box
//! minimum minus padding `q * R * max(r) + H`, samples at `origin + H * (i, j, k)`, so the density
//! is below I on the whole boundary and every surface is closed.

use glam::Vec3;
use rayon::prelude::*;

use super::scan::first_failing;
use super::{SurfaceError, SurfaceParams};

/// A regular grid of sample points, x varying fastest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// Position of sample (0, 0, 0) in Å.
    pub origin: Vec3,
    /// Distance between neighbouring samples in Å (H).
    pub spacing: f32,
    /// Number of samples along x, y and z.
    pub dims: [u32; 3],
}

impl GridSpec {
    /// The grid that encloses `positions` (Å) with Gaussians of `radii` (Å) under `params`.
    ///
    /// Fails on an empty system, non-finite coordinates or radii, or bad parameters.
    pub fn for_atoms(
        positions: &[Vec3],
        radii: &[f32],
        params: &SurfaceParams,
    ) -> Result<GridSpec, SurfaceError> {
        params.validate()?;
        if positions.is_empty() {
            return Err(SurfaceError::EmptySystem);
        }
        if let Some(atom) = first_failing(positions, |p| p.is_finite()) {
            return Err(SurfaceError::NonFiniteCoordinate { atom });
        }
        if let Some(atom) = first_failing(radii, |r| r.is_finite() && *r > 0.0) {
            return Err(SurfaceError::InvalidRadius {
                atom,
                radius: radii[atom],
            });
        }
        let far = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let (lo, hi) = positions
            .par_chunks(1 << 14)
            .map(|c| c.iter().fold(far, |(lo, hi), p| (lo.min(*p), hi.max(*p))))
            .reduce(|| far, |(a, b), (c, d)| (a.min(c), b.max(d)));
        let max_radius = radii
            .par_chunks(1 << 14)
            .map(|c| c.iter().fold(0.0f32, |m, &r| m.max(r)))
            .reduce(|| 0.0, f32::max);
        let h = params.spacing;
        let pad = params.cutoff() * params.radius_scale * max_radius + h;
        let origin = lo - Vec3::splat(pad);
        let extent = hi + Vec3::splat(pad) - origin;
        let n = |e: f32| (e / h).ceil() as u64 + 1;
        let dims64 = [n(extent.x), n(extent.y), n(extent.z)];
        if dims64.iter().any(|&d| d > u32::MAX as u64 / 4) {
            return Err(SurfaceError::GridTooLarge {
                dims: dims64,
                bytes_needed: estimate_grid_bytes(dims64, false),
                bytes_available: available_memory_bytes(),
            });
        }
        Ok(GridSpec {
            origin,
            spacing: h,
            dims: [dims64[0] as u32, dims64[1] as u32, dims64[2] as u32],
        })
    }

    /// Number of samples (voxels).
    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// Number of cells (cubes between 8 samples).
    pub fn cell_count(&self) -> u64 {
        self.dims
            .iter()
            .map(|&d| d.saturating_sub(1) as u64)
            .product()
    }

    /// Bytes the CPU engine needs for this grid (see [`estimate_grid_bytes`]).
    pub fn estimated_bytes(&self, with_colour: bool) -> u64 {
        estimate_grid_bytes(self.dims.map(u64::from), with_colour)
    }

    /// Linear index of sample (i, j, k), x fastest.
    pub fn index(&self, i: u32, j: u32, k: u32) -> usize {
        (i as usize) + self.dims[0] as usize * (j as usize + self.dims[1] as usize * k as usize)
    }

    /// Position of sample (i, j, k) in Å.
    pub fn point(&self, i: u32, j: u32, k: u32) -> Vec3 {
        self.origin + self.spacing * Vec3::new(i as f32, j as f32, k as f32)
    }

    /// Position in Å of the sample at linear index `at` (the inverse of [`GridSpec::index`]).
    pub fn point_at(&self, at: usize) -> Vec3 {
        let [nx, ny, _] = self.dims.map(|d| d as usize);
        let (i, j, k) = (at % nx, (at / nx) % ny, at / (nx * ny));
        self.point(i as u32, j as u32, k as u32)
    }
}

/// Bytes the CPU engine needs for a grid of `dims` samples: 4 per sample for the f32 density,
/// 12 more with a colour volume, plus a quarter on top for the mesh, the atom bins and the
/// Marching Cubes slab buffers. Saturates instead of overflowing.
pub fn estimate_grid_bytes(dims: [u64; 3], with_colour: bool) -> u64 {
    let voxels = dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]);
    let per_voxel = if with_colour { 16 } else { 4 };
    let volumes = voxels.saturating_mul(per_voxel);
    volumes.saturating_add(volumes / 4)
}

pub use super::memory::available_memory_bytes;
