//! Stages 1 and 2 of the periodic engine: the periodic grid, the images of the atoms that reach
//! the box (binned by z-slab in a canonical order), and the density and colour volumes.
//!
//! Data flow: [`AtomSet`] -> [`bin_images`] -> [`ImageBins`] -> [`PeriodicVolume::compute`] ->
//! Marching Cubes ([`super::mc`]).
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
use crate::surface::{AtomSet, SurfaceParams};

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

/// One atom image ready for the density stage (local coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Image {
    /// Position relative to the box origin (Å); may lie outside the box.
    pub pos: [f32; 3],
    /// Exponent factor `0.5 / alpha^2` (Å⁻²).
    pub k: f32,
    /// Cutoff radius `q alpha` (Å).
    pub cut: f32,
    /// Squared cutoff (Å²).
    pub cut2: f32,
    /// Linear RGB colour (white without colours).
    pub colour: [f32; 3],
}

/// Images in canonical order plus the images that reach each z-slab.
#[derive(Debug, Clone, Default)]
pub struct ImageBins {
    /// All images, canonical order.
    pub images: Vec<Image>,
    /// z-planes per slab.
    pub slab_planes: u32,
    /// `slab_start[s]..slab_start[s + 1]` indexes `slab_images`.
    pub slab_start: Vec<usize>,
    /// Indices into `images`, ascending per slab.
    pub slab_images: Vec<u32>,
}

/// Inclusive sample range `0..n` along one axis that a sphere of radius `cut` around local
/// coordinate `p` may reach (one sample of margin), `None` when it misses.
fn reach(p: f32, cut: f32, h: f32, n: u32) -> Option<(u32, u32)> {
    let lo = ((p - cut) / h).floor() as i64 - 1;
    let hi = ((p + cut) / h).ceil() as i64 + 1;
    let (lo, hi) = (lo.max(0), hi.min(n as i64 - 1));
    (lo <= hi).then_some((lo as u32, hi as u32))
}

/// Lattice shifts `n` (in box lengths) along one axis such that the image at local coordinate
/// `w + n L` reaches the samples `0..N` (conservative).
fn shifts(w: f32, cut: f32, l: f32, h: f32) -> impl Iterator<Item = f32> {
    let m = ((cut + h) / l).ceil() as i32 + 1;
    (-m..=m)
        .map(move |n| n as f32 * l)
        .filter(move |&s| w + s + cut > -h && w + s - cut < l)
}

/// The images of `atoms` (validated) that reach `grid`, sorted canonically and binned by z-slab.
pub fn bin_images(atoms: &AtomSet<'_>, params: &SurfaceParams, grid: &PeriodicGrid) -> ImageBins {
    let q = params.cutoff();
    let l = grid.extent();
    let h = grid.spacing;
    let mut images: Vec<Image> = atoms
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
            let base = Image {
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
    let key = |a: &Image| {
        (cell(a.pos[2], h.z, nz) * ny as u64 + cell(a.pos[1], h.y, ny)) * nx as u64
            + cell(a.pos[0], h.x, nx)
    };
    let tie = |a: &Image, b: &Image| -> Ordering {
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
            reach(a.pos[2], a.cut, h.z, nz).map(|(k0, k1)| (k0 / slab_planes, k1 / slab_planes))
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
    ImageBins {
        images,
        slab_planes,
        slab_start,
        slab_images,
    }
}

/// Density (and colour) of one periodic box, x fastest, `N_x N_y N_z` samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PeriodicVolume {
    /// Density per sample (dimensionless).
    pub values: Vec<f32>,
    /// Colour per sample, `sum w colour / I` (linear RGB), when the atoms carry colours.
    pub colours: Option<Vec<[f32; 3]>>,
}

/// Per-axis samples an image reaches: first index, squared distances (Å²), exponentials.
#[derive(Default)]
struct Axis {
    first: usize,
    d2: Vec<f32>,
    e: Vec<f32>,
}

impl Axis {
    /// Terms for samples `lo..=hi` at spacing `h` (Å) of coordinate `p` (Å), exponent factor
    /// `k` (Å⁻²); samples with `d^2 >= cut2` on this axis alone are dropped from both ends.
    fn fill(&mut self, (lo, hi): (u32, u32), h: f32, p: f32, k: f32, cut2: f32) -> bool {
        self.d2.clear();
        self.e.clear();
        let mut first = None;
        for i in lo..=hi {
            let d = h * i as f32 - p;
            let d2 = d * d;
            if d2 < cut2 {
                first.get_or_insert(i);
                self.d2.push(d2);
            } else if first.is_some() {
                break;
            }
        }
        self.first = first.unwrap_or(lo) as usize;
        self.e.extend(self.d2.iter().map(|&d2| (-k * d2).exp()));
        !self.d2.is_empty()
    }
}

impl PeriodicVolume {
    /// Fills the volume from `bins` on `grid` (colours divided by the isovalue `iso` when
    /// `with_colour`), reusing the buffers when the grid keeps its size.
    pub fn compute(&mut self, bins: &ImageBins, grid: &PeriodicGrid, iso: f32, with_colour: bool) {
        let total = grid.len();
        let plane = grid.dims[0] as usize * grid.dims[1] as usize;
        if self.values.len() != total {
            self.values = vec![0.0; total];
        }
        if !with_colour {
            self.colours = None;
        } else if self.colours.as_ref().is_none_or(|c| c.len() != total) {
            self.colours = Some(vec![[0.0; 3]; total]);
        }
        let slab_len = plane * bins.slab_planes as usize;
        let inv_iso = 1.0 / iso;
        match self.colours.as_mut() {
            None => self
                .values
                .par_chunks_mut(slab_len)
                .enumerate()
                .for_each(|(s, vals)| {
                    vals.fill(0.0);
                    fill_slab(bins, grid, s, vals, None);
                }),
            Some(cols) => self
                .values
                .par_chunks_mut(slab_len)
                .zip(cols.par_chunks_mut(slab_len))
                .enumerate()
                .for_each(|(s, (vals, cols))| {
                    vals.fill(0.0);
                    cols.fill([0.0; 3]);
                    fill_slab(bins, grid, s, vals, Some(&mut *cols));
                    for c in cols.iter_mut() {
                        *c = c.map(|v| v * inv_iso);
                    }
                }),
        }
    }
}

/// Adds the images of slab `s` to its samples (`vals`, `cols` hold the slab's planes).
fn fill_slab(
    bins: &ImageBins,
    grid: &PeriodicGrid,
    s: usize,
    vals: &mut [f32],
    mut cols: Option<&mut [[f32; 3]]>,
) {
    let [nx, ny, nz] = grid.dims;
    let h = grid.spacing;
    let plane = nx as usize * ny as usize;
    let z0 = s as u32 * bins.slab_planes;
    let z1 = (z0 + bins.slab_planes).min(nz) - 1;
    let list = &bins.slab_images[bins.slab_start[s]..bins.slab_start[s + 1]];
    let (mut tx, mut ty, mut tz) = (Axis::default(), Axis::default(), Axis::default());
    for &a in list {
        let img = &bins.images[a as usize];
        let [px, py, pz] = img.pos;
        let (Some(rx), Some(ry), Some(rz)) = (
            reach(px, img.cut, h.x, nx),
            reach(py, img.cut, h.y, ny),
            reach(pz, img.cut, h.z, nz),
        ) else {
            continue;
        };
        let rz = (rz.0.max(z0), rz.1.min(z1));
        if rz.0 > rz.1 {
            continue;
        }
        let cut2 = img.cut2;
        if !(tx.fill(rx, h.x, px, img.k, cut2)
            && ty.fill(ry, h.y, py, img.k, cut2)
            && tz.fill(rz, h.z, pz, img.k, cut2))
        {
            continue;
        }
        for (kz, (&dz2, &ez)) in tz.d2.iter().zip(&tz.e).enumerate() {
            let zoff = (tz.first + kz - z0 as usize) * plane;
            for (jy, (&dy2, &ey)) in ty.d2.iter().zip(&ty.e).enumerate() {
                let dyz = dy2 + dz2;
                if dyz >= cut2 {
                    continue;
                }
                let eyz = ey * ez;
                // The samples of the row passing the cutoff are contiguous: trim both ends.
                let pass = |d: f32| (d + dy2) + dz2 < cut2;
                let (mut i0, mut i1) = (0, tx.d2.len());
                while i0 < i1 && !pass(tx.d2[i0]) {
                    i0 += 1;
                }
                while i1 > i0 && !pass(tx.d2[i1 - 1]) {
                    i1 -= 1;
                }
                let row = zoff + (ty.first + jy) * nx as usize + tx.first + i0;
                let exs = &tx.e[i0..i1];
                for (v, &ex) in vals[row..row + exs.len()].iter_mut().zip(exs) {
                    *v += ex * eyz;
                }
                if let Some(cols) = cols.as_deref_mut() {
                    let c = img.colour;
                    for (v, &ex) in cols[row..row + exs.len()].iter_mut().zip(exs) {
                        let w = ex * eyz;
                        v[0] += w * c[0];
                        v[1] += w * c[1];
                        v[2] += w * c[2];
                    }
                }
            }
        }
    }
}
