//! A brick volume made from two kept ones on the same grid, `whole - minus` sample by sample
//! (the interface's larger side: the complex less the smaller side, see
//! [`crate::surface::KeptDensity`]), and a volume copied into another's buffers.
//!
//! `minus`'s atoms are among `whole`'s, so its occupied bricks are among `whole`'s: the
//! difference is stored in `whole`'s bricks (those where only `minus` had atoms come out 0 to
//! rounding) and its active bricks are found again for the new values by the sampled path's
//! rule ([`super::active`]). No vertex colours.

use rayon::prelude::*;

use super::active::LayerMasks;
use super::{BRICK, BRICK_SAMPLES, BrickStats, BrickVolume, EMPTY, Layer};

impl BrickVolume {
    /// Makes this volume `whole - minus` (same grid and isovalue; `minus`'s occupied bricks
    /// among `whole`'s), reusing its buffers, with its active bricks and no colours.
    pub(crate) fn difference_of(&mut self, whole: &BrickVolume, minus: &BrickVolume) {
        self.grid = whole.grid;
        self.bdims = whole.bdims;
        self.iso = whole.iso;
        self.with_colour = false;
        self.slots.clone_from(&whole.slots);
        let count = whole.data.len() / BRICK_SAMPLES;
        let mut brick_of = vec![0usize; count];
        for (b, &s) in whole.slots.iter().enumerate() {
            if s != EMPTY {
                brick_of[s as usize] = b;
            }
        }
        // Every stored sample is written below.
        self.data.resize(whole.data.len(), 0.0);
        self.data
            .par_chunks_mut(BRICK_SAMPLES)
            .zip(whole.data.par_chunks(BRICK_SAMPLES))
            .zip(brick_of.par_iter())
            .for_each(|((dst, src), &b)| match minus.slots.get(b) {
                Some(&m) if m != EMPTY => {
                    let m = m as usize * BRICK_SAMPLES;
                    let less = &minus.data[m..m + BRICK_SAMPLES];
                    for ((d, w), l) in dst.iter_mut().zip(src).zip(less) {
                        *d = w - l;
                    }
                }
                _ => dst.copy_from_slice(src),
            });
        let mut layers = std::mem::take(&mut self.layers);
        layers.resize_with(self.bdims[2], Layer::default);
        layers
            .par_iter_mut()
            .enumerate()
            .for_each(|(bk, layer)| self.find_layer_active(bk, layer));
        self.layers = layers;
        let [bx, by, bz] = self.bdims;
        self.stats = BrickStats {
            brick_size: BRICK as u32,
            bricks: (bx * by * bz) as u64,
            occupied: count as u64,
            active: self.layers.iter().map(|l| l.cols.len() as u64).sum(),
        };
    }

    /// Makes this volume a copy of `other`, reusing its buffers (a kept copy of a volume that
    /// the engine computes again next frame).
    pub(crate) fn copy_from(&mut self, other: &BrickVolume) {
        self.grid = other.grid;
        self.bdims = other.bdims;
        self.iso = other.iso;
        self.with_colour = other.with_colour;
        self.slots.clone_from(&other.slots);
        self.data.clone_from(&other.data);
        self.layers.clone_from(&other.layers);
        self.stats = other.stats;
    }

    /// Finds the active bricks of brick layer `bk` from the stored samples into `layer`.
    fn find_layer_active(&self, bk: usize, layer: &mut Layer) {
        let [nx, ny, nz] = self.grid.dims.map(|d| d as usize);
        let [bx, by, bz] = self.bdims;
        // The layer's own planes and the first of the next layer.
        let planes = (BRICK + 1).min(nz - bk * BRICK);
        let mut masks = vec![0u8; planes * ny * bx];
        for kk in 0..planes {
            for j in 0..ny {
                for bi in 0..bx {
                    // Not stored: all 0, below I.
                    if let Some(row) = self.brick_row(bi * BRICK, j, bk * BRICK + kk) {
                        masks[(kk * ny + j) * bx + bi] = row
                            .iter()
                            .enumerate()
                            .fold(0u8, |m, (t, &v)| m | (u8::from(v >= self.iso) << t));
                    }
                }
            }
        }
        let occupied = |k: usize, y: usize, x: usize| self.slots[(k * by + y) * bx + x] != EMPTY;
        let touched = |bi: usize, bj: usize| {
            (bk..=(bk + 1).min(bz - 1)).any(|k| {
                (bj..=(bj + 1).min(by - 1))
                    .any(|y| (bi..=(bi + 1).min(bx - 1)).any(|x| occupied(k, y, x)))
            })
        };
        let masks = LayerMasks {
            masks: &masks,
            dims: [nx, ny],
            bdims: [bx, by],
            planes,
        };
        masks.find_active(touched, layer);
        layer.colours.clear();
    }
}
