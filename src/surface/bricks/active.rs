//! Which bricks of a layer Marching Cubes visits: the rule shared by the sampled bricks
//! ([`super::BrickVolume::compute`]) and a difference of two kept volumes ([`super::difference`]).

use super::{BRICK, Layer};

/// One brick layer's inside flags as bit masks: bit t of `masks[(kk * ny + j) * bx + bi]` is
/// set when sample (8 bi + t, j, 8 bk + kk) has rho >= I, for the layer's `planes` planes (its
/// own and the first of the next layer).
pub(super) struct LayerMasks<'a> {
    pub masks: &'a [u8],
    /// Grid samples along x and y.
    pub dims: [usize; 2],
    /// Bricks along x and y.
    pub bdims: [usize; 2],
    /// Planes the masks cover (at most 9).
    pub planes: usize,
}

impl LayerMasks<'_> {
    /// The 9 samples 8 bi ..= 8 bi + 8 of row (j, kk).
    pub fn mask9(&self, kk: usize, j: usize, bi: usize) -> u32 {
        let [_, ny] = self.dims;
        let [bx, _] = self.bdims;
        let q = (kk * ny + j) * bx + bi;
        let next = if bi + 1 < bx {
            self.masks[q + 1] & 1
        } else {
            0
        };
        u32::from(self.masks[q]) | u32::from(next) << 8
    }

    /// Writes the layer's active bricks into `layer` (by row, ascending x): those whose 9³
    /// footprint holds samples on both sides of I. `touched(bi, bj)` is false where no occupied
    /// brick is near, so that every footprint sample is 0 < I.
    pub fn find_active(&self, touched: impl Fn(usize, usize) -> bool, layer: &mut Layer) {
        let [nx, ny] = self.dims;
        let [bx, by] = self.bdims;
        layer.row_start.clear();
        layer.cols.clear();
        layer.row_start.push(0);
        let kmax = self.planes - 1; // last plane of the footprint
        for bj in 0..by {
            for bi in 0..bx {
                if !touched(bi, bj) {
                    continue;
                }
                let (i0, i1) = (bi * BRICK, (bi * BRICK + BRICK).min(nx - 1));
                let (j0, j1) = (bj * BRICK, (bj * BRICK + BRICK).min(ny - 1));
                let full = (1u32 << (i1 - i0 + 1)) - 1;
                let (mut any, mut all) = (false, true);
                for kk in 0..=kmax.min(BRICK) {
                    for j in j0..=j1 {
                        let m = self.mask9(kk, j, bi) & full;
                        any |= m != 0;
                        all &= m == full;
                    }
                    if any && !all {
                        break;
                    }
                }
                if any && !all {
                    layer.cols.push(bi as u32);
                }
            }
            layer.row_start.push(layer.cols.len() as u32);
        }
    }
}
