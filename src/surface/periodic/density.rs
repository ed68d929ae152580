//! Stages 1 and 2 of the periodic engine: the periodic grid, the images of the atoms that reach
//! the box (binned by z-slab in a canonical order), and the density and colour volumes.
//!
//! Data flow: [`AtomSet`] -> [`bin_images`] -> [`AtomBins`] (the dense engine's binned atoms,
//! here images) -> [`compute_volume`] (the dense engine's plane walk and axis terms,
//! [`crate::surface::density`], on the box's lattice) -> Marching Cubes ([`super::mc`]).
//!
//! Coordinates are local to the box (Å from its origin). Each atom is wrapped into the box and
//! every image `p + n L` whose cutoff sphere reaches the box's samples is kept, so a sample's
//! density is a plain sum over images, as in [`crate::surface::density`]: per-pair cutoff test
//! `d^2 < (q alpha)^2` before the exponential, the exponential evaluated per axis. Images are
//! sorted by the grid cell holding them (z-major) with ties broken by the bits of position,
//! radius and colour, so the volume does not depend on the order of the input atoms.

use std::cmp::Ordering;

use glam::Vec3;
use rayon::prelude::*;

use super::PeriodicBox;
use crate::surface::bin::{AtomBins, PreparedAtom, sample_range};
use crate::surface::density::{SampleLattice, fill_binned_into};
use crate::surface::{AtomSet, DensityVolume, SurfaceParams};

/// The sampling grid of a periodic box: sample `(i, j, k)` (each from 0 to `N - 1`) at
/// `origin + (i h_x, j h_y, k h_z)`; sample `N` along an axis is sample 0 again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicGrid {
    /// The box's origin (Å).
    pub origin: Vec3,
    /// Samples per axis.
    pub dims: [u32; 3],
    /// Spacing per axis, `L_i / N_i` (Å).
    pub spacing: Vec3,
}

impl PeriodicGrid {
    /// The grid of `pbox` with `dims` samples per axis.
    pub fn new(pbox: &PeriodicBox, dims: [u32; 3]) -> PeriodicGrid {
        PeriodicGrid {
            origin: pbox.origin,
            dims,
            spacing: pbox.lengths / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32),
        }
    }

    /// The box edge lengths as the mesh sees them, `N_i h_i` in f32 (Å; equal to L_i up to
    /// rounding). Vertices on the upper faces have exactly these local coordinates.
    pub fn extent(&self) -> Vec3 {
        Vec3::new(
            self.dims[0] as f32 * self.spacing.x,
            self.dims[1] as f32 * self.spacing.y,
            self.dims[2] as f32 * self.spacing.z,
        )
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// True when the grid has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of the sample at `(i, j, k)` taken modulo the dims (x fastest); any
    /// non-negative indices are allowed.
    #[inline]
    pub fn index(&self, p: [usize; 3]) -> usize {
        let [nx, ny, nz] = self.dims.map(|d| d as usize);
        (p[0] % nx) + nx * ((p[1] % ny) + ny * (p[2] % nz))
    }
}

/// Lattice shifts `n` (in box lengths) along one axis such that the image at local coordinate
/// `w + n L` reaches the samples `0..N` (conservative).
fn shifts(w: f32, cut: f32, l: f32, h: f32) -> impl Iterator<Item = f32> {
    let m = ((cut + h) / l).ceil() as i32 + 1;
    (-m..=m)
        .map(move |n| n as f32 * l)
        .filter(move |&s| w + s + cut > -h && w + s - cut < l)
}

/// The images of `atoms` (validated) that reach `grid`, in local coordinates (Å from the box
/// origin), sorted canonically and binned by z-slab.
pub fn bin_images(atoms: &AtomSet<'_>, params: &SurfaceParams, grid: &PeriodicGrid) -> AtomBins {
    let q = params.cutoff();
    let l = grid.extent();
    let h = grid.spacing;
    let mut images: Vec<PreparedAtom> = atoms
        .positions
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, &p)| {
            let alpha = atoms.radii[i] * params.radius_scale;
            let cut = q * alpha;
            let mut w = p - grid.origin;
            for a in 0..3 {
                w[a] -= (w[a] / l[a]).floor() * l[a];
                if w[a] >= l[a] {
                    w[a] = 0.0;
                }
            }
            let base = PreparedAtom {
                pos: w.to_array(),
                k: 0.5 / (alpha * alpha),
                cut,
                cut2: cut * cut,
                colour: atoms.colour(i),
            };
            let xs: Vec<f32> = shifts(w.x, cut, l.x, h.x).collect();
            let ys: Vec<f32> = shifts(w.y, cut, l.y, h.y).collect();
            let zs: Vec<f32> = shifts(w.z, cut, l.z, h.z).collect();
            let mut out = Vec::with_capacity(xs.len() * ys.len() * zs.len());
            for &sz in &zs {
                for &sy in &ys {
                    for &sx in &xs {
                        let mut img = base;
                        img.pos = [w.x + sx, w.y + sy, w.z + sz];
                        out.push(img);
                    }
                }
            }
            out
        })
        .collect();

    let cell = |p: f32, h: f32, n: u32| ((p / h).floor().max(0.0) as u64).min(n as u64 - 1);
    let [nx, ny, nz] = grid.dims;
    let key = |a: &PreparedAtom| {
        (cell(a.pos[2], h.z, nz) * ny as u64 + cell(a.pos[1], h.y, ny)) * nx as u64
            + cell(a.pos[0], h.x, nx)
    };
    let tie = |a: &PreparedAtom, b: &PreparedAtom| -> Ordering {
        (0..3)
            .map(|k| a.pos[k].total_cmp(&b.pos[k]))
            .chain(std::iter::once(a.k.total_cmp(&b.k)))
            .chain((0..3).map(|k| a.colour[k].total_cmp(&b.colour[k])))
            .find(|o| o.is_ne())
            .unwrap_or(Ordering::Equal)
    };
    images.par_sort_unstable_by(|a, b| key(a).cmp(&key(b)).then_with(|| tie(a, b)));

    let threads = rayon::current_num_threads().max(1) as u32;
    let slab_planes = (nz / (8 * threads)).clamp(2, 64);
    let slab_count = nz.div_ceil(slab_planes) as usize;
    let ranges: Vec<Option<(u32, u32)>> = images
        .par_iter()
        .map(|a| {
            sample_range(a.pos[2], a.cut, 0.0, h.z, nz)
                .map(|(k0, k1)| (k0 / slab_planes, k1 / slab_planes))
        })
        .collect();
    let mut slab_start = vec![0usize; slab_count + 1];
    for &(s0, s1) in ranges.iter().flatten() {
        for s in s0..=s1 {
            slab_start[s as usize + 1] += 1;
        }
    }
    for s in 0..slab_count {
        slab_start[s + 1] += slab_start[s];
    }
    let mut fill = slab_start.clone();
    let mut slab_images = vec![0u32; slab_start[slab_count]];
    for (i, r) in ranges.iter().enumerate() {
        if let Some((s0, s1)) = *r {
            for s in s0..=s1 {
                slab_images[fill[s as usize]] = i as u32;
                fill[s as usize] += 1;
            }
        }
    }
    AtomBins {
        atoms: images,
        slab_planes,
        slab_start,
        slab_atoms: slab_images,
    }
}

/// The density (and colour, divided by the isovalue `iso`, when `with_colour`) of the binned
/// images on `grid` into `vol`, reusing its buffers when the grid keeps its size: the dense
/// engine's kernel on the box's samples (local coordinates, a spacing per axis).
pub fn compute_volume(
    bins: &AtomBins,
    grid: &PeriodicGrid,
    iso: f32,
    with_colour: bool,
    vol: &mut DensityVolume,
) {
    let lattice = SampleLattice {
        origin: [0.0; 3],
        spacing: grid.spacing.to_array(),
        dims: grid.dims,
    };
    fill_binned_into(bins, &lattice, iso, with_colour, vol);
}
