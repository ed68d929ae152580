//! The atoms near one point or edge, gathered into blocks of eight lanes and summed without
//! branches: the inner loop of refinement and projection, with its polynomial [`exp_fast`].

use super::*;

/// One atom of the field (position in Å, exponent factor in Å⁻², squared cutoff in Å², cutoff
/// in Å).
#[derive(Debug, Clone, Copy)]
pub(super) struct FieldAtom {
    pub(super) pos: Vec3,
    pub(super) k: f32,
    pub(super) cut2: f32,
    pub(super) reach: f32,
}

thread_local! {
    /// Per-thread scratch for the atoms near one edge ([`AnalyticField::refine_edge`]).
    pub(super) static NEAR: std::cell::RefCell<NearAtoms> = std::cell::RefCell::new(NearAtoms::default());
}

/// Lanes of the branch-free sum in [`NearAtoms::eval`] (a multiple of the SIMD width).
pub(super) const LANES: usize = 8;

/// [`LANES`] atoms side by side (Å, Å⁻², Å²); unused lanes have `cut2 = -1` and never count.
#[derive(Debug, Clone, Copy)]
pub(super) struct Block {
    pub(super) x: [f32; LANES],
    pub(super) y: [f32; LANES],
    pub(super) z: [f32; LANES],
    pub(super) k: [f32; LANES],
    pub(super) cut2: [f32; LANES],
}

impl Block {
    const EMPTY: Block = Block {
        x: [0.0; LANES],
        y: [0.0; LANES],
        z: [0.0; LANES],
        k: [0.0; LANES],
        cut2: [-1.0; LANES],
    };
}

/// The atoms near one edge, gathered once and summed at every Newton step: structure of
/// arrays in blocks of [`LANES`], summed without branches (the cutoff is a select) and with
/// [`exp_fast`], so the compiler vectorises the loop. Lane sums are added in a fixed order, so
/// the result does not depend on the thread.
#[derive(Debug, Default)]
pub(super) struct NearAtoms {
    pub(super) blocks: Vec<Block>,
    pub(super) len: usize,
}

impl NearAtoms {
    /// Empties the list (the blocks stay allocated for the next gather).
    pub(super) fn clear(&mut self) {
        self.len = 0;
    }

    /// Makes room for `n` more atoms (whole blocks of empty lanes).
    pub(super) fn reserve(&mut self, n: usize) {
        let need = (self.len + n).div_ceil(LANES) + 1;
        if self.blocks.len() < need {
            self.blocks.resize(need, Block::EMPTY);
        }
    }

    /// Writes `a` into the next lane and keeps it when `keep` (no branch: the gather's filter
    /// is unpredictable); room must have been made with [`Self::reserve`].
    #[inline]
    pub(super) fn push_if(&mut self, a: &FieldAtom, keep: bool) {
        let (i, l) = (self.len / LANES, self.len % LANES);
        if let Some(b) = self.blocks.get_mut(i) {
            (b.x[l], b.y[l], b.z[l]) = (a.pos.x, a.pos.y, a.pos.z);
            (b.k[l], b.cut2[l]) = (a.k, a.cut2);
            self.len += keep as usize;
        }
    }

    /// Ends a gather: the lanes after the last atom in its block are emptied.
    pub(super) fn finish(&mut self) {
        let (i, l) = (self.len / LANES, self.len % LANES);
        if l != 0
            && let Some(b) = self.blocks.get_mut(i)
        {
            b.cut2[l..].fill(-1.0);
        }
    }

    /// The blocks holding the atoms.
    pub(super) fn used(&self) -> &[Block] {
        &self.blocks[..self.len.div_ceil(LANES).min(self.blocks.len())]
    }

    /// `rho(p)` and `grad rho(p)` (Å⁻¹) over these atoms (each counted when
    /// `|p - p_i|² < cut2`).
    #[inline]
    pub(super) fn eval(&self, p: Vec3) -> (f32, Vec3) {
        let mut rho = [0.0f32; LANES];
        let mut gx = [0.0f32; LANES];
        let mut gy = [0.0f32; LANES];
        let mut gz = [0.0f32; LANES];
        for b in self.used() {
            for l in 0..LANES {
                let (dx, dy, dz) = (p.x - b.x[l], p.y - b.y[l], p.z - b.z[l]);
                let d2 = (dx * dx + dy * dy) + dz * dz;
                let e = exp_fast(-b.k[l] * d2);
                let w = if d2 < b.cut2[l] { e } else { 0.0 };
                let s = 2.0 * b.k[l] * w;
                rho[l] += w;
                gx[l] -= s * dx;
                gy[l] -= s * dy;
                gz[l] -= s * dz;
            }
        }
        let sum = |v: [f32; LANES]| v.iter().sum::<f32>();
        (sum(rho), Vec3::new(sum(gx), sum(gy), sum(gz)))
    }
}

/// Adds the terms of `atoms` at `p` to `rho` and `grad` (each counted when
/// `|p - p_i|² < cut2`), one atom after the other, with the C library's `expf`.
#[inline]
pub(super) fn accumulate(atoms: &[FieldAtom], p: Vec3, rho: &mut f32, grad: &mut Vec3) {
    for atom in atoms {
        let d = p - atom.pos;
        let d2 = (d.x * d.x + d.y * d.y) + d.z * d.z;
        if d2 < atom.cut2 {
            let w = (-atom.k * d2).exp();
            *rho += w;
            *grad -= (2.0 * atom.k * w) * d;
        }
    }
}

/// `e^x` (x <= 0; below -87 it returns about 1e-38) with relative error below 1e-6: `x = n ln 2
/// + r`, `|r| <= ln 2 / 2`, a degree-6 Taylor polynomial for `e^r` and `2^n` from the exponent
/// bits. Plain arithmetic, so loops over it vectorise (a call to the C library's `expf` does not).
#[inline(always)]
pub fn exp_fast(x: f32) -> f32 {
    /// 1.5 * 2^23: adding it rounds to an integer held in the low mantissa bits.
    const MAGIC: f32 = 12_582_912.0;
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    let x = x.max(-87.0);
    let t = x * std::f32::consts::LOG2_E + MAGIC;
    let n = t - MAGIC;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let ni = t.to_bits().wrapping_sub(MAGIC.to_bits()) as i32;
    let scale = f32::from_bits((ni.wrapping_add(127) << 23) as u32);
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
    p * scale
}
