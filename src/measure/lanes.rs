//! The two inner loops of the area per atom ([`super::cells`]): which atoms of a run lie within
//! their cutoff of a box, and which within their cutoff of a point. Each writes the positions
//! of the atoms it picks, ascending, and is compiled twice: portable (one atom at a time, no
//! branch per atom) and, where the CPU has AVX2, eight atoms at a time (a compare gives an
//! 8-bit mask, a table turns the mask into the positions of its set bits, written at once).
//! Both variants do the same IEEE operations in the same order (Rust never fuses a multiply and
//! an add), so they pick the same atoms and give the same distances to the bit.

use glam::Vec3;

/// Room (entries) the picked positions need past the count picked: the AVX2 variant writes
/// eight positions at a time.
pub(crate) const SLACK: usize = 8;

/// The instruction set the loops run with, detected once per measurement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Lanes {
    /// One atom at a time, on any CPU.
    Portable,
    /// Eight atoms at a time (x86-64 with AVX2).
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Lanes {
    /// AVX2 where this CPU has it, else portable.
    pub(crate) fn detect() -> Lanes {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Lanes::Avx2;
        }
        Lanes::Portable
    }
}

/// Coordinates (Å) and squared cutoffs (Å²) of a run of atoms, one array each, equally long.
#[derive(Clone, Copy)]
pub(crate) struct Run<'a> {
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
    pub cutoff2: &'a [f32],
}

impl Run<'_> {
    fn len(&self) -> usize {
        self.x.len()
    }
}

/// Squared distance (Å²) from `(x, y, z)` to the box `lo..hi` (0 inside).
#[inline(always)]
fn box_distance2(x: f32, y: f32, z: f32, lo: Vec3, hi: Vec3) -> f32 {
    let dx = (lo.x - x).max(x - hi.x).max(0.0);
    let dy = (lo.y - y).max(y - hi.y).max(0.0);
    let dz = (lo.z - z).max(z - hi.z).max(0.0);
    dx * dx + dy * dy + dz * dz
}

/// Squared distance (Å²) from atom `k` of `run` to `p`.
#[inline(always)]
fn point_distance2(run: Run<'_>, k: usize, p: Vec3) -> f32 {
    let (dx, dy, dz) = (run.x[k] - p.x, run.y[k] - p.y, run.z[k] - p.z);
    dx * dx + dy * dy + dz * dz
}

/// Writes to `picked[at..]` `base + k` for every atom `k` of `run` whose cutoff reaches the box
/// `lo..hi` (Å), ascending, and returns the new end. `picked` must hold `at + run.len() +
/// SLACK` entries.
pub(crate) fn pick_near_box(
    lanes: Lanes,
    run: Run<'_>,
    lo: Vec3,
    hi: Vec3,
    base: u32,
    picked: &mut [u32],
    at: usize,
) -> usize {
    assert!(picked.len() >= at + run.len() + SLACK);
    match lanes {
        Lanes::Portable => {
            let mut m = at;
            for k in 0..run.len() {
                picked[m] = base + k as u32;
                let d2 = box_distance2(run.x[k], run.y[k], run.z[k], lo, hi);
                m += usize::from(d2 < run.cutoff2[k]);
            }
            m
        }
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Lanes::Avx2` is only made when the CPU has AVX2; the length is checked above.
        Lanes::Avx2 => unsafe { avx2::pick_near_box(run, lo, hi, base, picked, at) },
    }
}

/// Writes to `distance2[k]` the squared distance (Å²) from `p` to atom `k` of `run`, and to
/// `picked[..m]` the atoms whose cutoff reaches `p`, ascending; returns `m`. `distance2` must
/// hold `run.len()` entries, `picked` `run.len() + SLACK`.
pub(crate) fn pick_near_point(
    lanes: Lanes,
    run: Run<'_>,
    p: Vec3,
    distance2: &mut [f32],
    picked: &mut [u32],
) -> usize {
    let n = run.len();
    assert!(distance2.len() >= n && picked.len() >= n + SLACK);
    match lanes {
        Lanes::Portable => {
            for (k, d2) in distance2[..n].iter_mut().enumerate() {
                *d2 = point_distance2(run, k, p);
            }
            let mut m = 0;
            for (k, (&d2, &cut)) in distance2[..n].iter().zip(run.cutoff2).enumerate() {
                picked[m] = k as u32;
                m += usize::from(d2 < cut);
            }
            m
        }
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Lanes::Avx2` is only made when the CPU has AVX2; the lengths are checked above.
        Lanes::Avx2 => unsafe { avx2::pick_near_point(run, p, distance2, picked) },
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! The AVX2 variants of the loops of [`super`], eight atoms per step, the rest one at a time.

    use std::arch::x86_64::*;

    use glam::Vec3;

    use super::{Run, box_distance2, point_distance2};

    /// For each 8-bit mask, the positions of its set bits, ascending (the rest zeros).
    static SET_BITS: [[u32; 8]; 256] = {
        let mut table = [[0u32; 8]; 256];
        let mut mask = 0;
        while mask < 256 {
            let (mut bit, mut k) = (0, 0);
            while bit < 8 {
                if (mask >> bit) & 1 == 1 {
                    table[mask][k] = bit as u32;
                    k += 1;
                }
                bit += 1;
            }
            mask += 1;
        }
        table
    };

    /// Writes `base + k` for each set bit `k` of `mask` to `picked[m..]` (eight entries
    /// written) and returns the new end.
    #[inline(always)]
    unsafe fn write_set_bits(mask: i32, base: u32, picked: &mut [u32], m: usize) -> usize {
        let mask = mask as usize & 0xff;
        let out = &mut picked[m..m + 8];
        // SAFETY: both pointers address eight u32 (the table row and the slice just taken).
        unsafe {
            let bits = _mm256_loadu_si256(SET_BITS[mask].as_ptr().cast());
            let at = _mm256_add_epi32(bits, _mm256_set1_epi32(base as i32));
            _mm256_storeu_si256(out.as_mut_ptr().cast(), at);
        }
        m + mask.count_ones() as usize
    }

    /// Eight floats of `v` from `k` (bounds-checked).
    #[inline(always)]
    unsafe fn load8(v: &[f32], k: usize) -> __m256 {
        // SAFETY: the slice taken holds eight floats.
        unsafe { _mm256_loadu_ps(v[k..k + 8].as_ptr()) }
    }

    /// x, y, z and squared cutoff of atoms `k..k + 8` of `run` (bounds-checked).
    #[inline(always)]
    unsafe fn load_run(run: Run<'_>, k: usize) -> [__m256; 4] {
        // SAFETY: each load is bounds-checked.
        unsafe {
            [
                load8(run.x, k),
                load8(run.y, k),
                load8(run.z, k),
                load8(run.cutoff2, k),
            ]
        }
    }

    /// `v` in every lane, per coordinate.
    #[inline(always)]
    unsafe fn splat(v: Vec3) -> [__m256; 3] {
        // SAFETY: plain register operations.
        unsafe {
            [
                _mm256_set1_ps(v.x),
                _mm256_set1_ps(v.y),
                _mm256_set1_ps(v.z),
            ]
        }
    }

    /// `dx^2 + dy^2 + dz^2` per lane, added in that order.
    #[inline(always)]
    unsafe fn length2(dx: __m256, dy: __m256, dz: __m256) -> __m256 {
        // SAFETY: plain register operations.
        unsafe {
            _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                _mm256_mul_ps(dz, dz),
            )
        }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn pick_near_box(
        run: Run<'_>,
        lo: Vec3,
        hi: Vec3,
        base: u32,
        picked: &mut [u32],
        at: usize,
    ) -> usize {
        let n = run.len();
        let full = n - n % 8;
        let mut m = at;
        let zero = _mm256_setzero_ps();
        // SAFETY: plain register operations.
        let ([lx, ly, lz], [hx, hy, hz]) = unsafe { (splat(lo), splat(hi)) };
        let gap = |v: __m256, lo: __m256, hi: __m256| {
            _mm256_max_ps(
                _mm256_max_ps(_mm256_sub_ps(lo, v), _mm256_sub_ps(v, hi)),
                zero,
            )
        };
        for k in (0..full).step_by(8) {
            // SAFETY: k + 8 <= n for every array of the run (equally long).
            let [x, y, z, cut] = unsafe { load_run(run, k) };
            let (dx, dy, dz) = (gap(x, lx, hx), gap(y, ly, hy), gap(z, lz, hz));
            // SAFETY: plain register operations.
            let d2 = unsafe { length2(dx, dy, dz) };
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, cut));
            // SAFETY: `picked` holds `at + n + 8` entries and m <= at + k.
            m = unsafe { write_set_bits(mask, base + k as u32, picked, m) };
        }
        for k in full..n {
            picked[m] = base + k as u32;
            let d2 = box_distance2(run.x[k], run.y[k], run.z[k], lo, hi);
            m += usize::from(d2 < run.cutoff2[k]);
        }
        m
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn pick_near_point(
        run: Run<'_>,
        p: Vec3,
        distance2: &mut [f32],
        picked: &mut [u32],
    ) -> usize {
        let n = run.len();
        let full = n - n % 8;
        let mut m = 0;
        // SAFETY: plain register operations.
        let [px, py, pz] = unsafe { splat(p) };
        for k in (0..full).step_by(8) {
            // SAFETY: k + 8 <= n for every array of the run (equally long).
            let [x, y, z, cut] = unsafe { load_run(run, k) };
            let (dx, dy, dz) = (
                _mm256_sub_ps(x, px),
                _mm256_sub_ps(y, py),
                _mm256_sub_ps(z, pz),
            );
            // SAFETY: plain register operations.
            let d2 = unsafe { length2(dx, dy, dz) };
            // SAFETY: `distance2` holds n entries and k + 8 <= n.
            unsafe { _mm256_storeu_ps(distance2[k..k + 8].as_mut_ptr(), d2) };
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, cut));
            // SAFETY: `picked` holds n + 8 entries and m <= k.
            m = unsafe { write_set_bits(mask, k as u32, picked, m) };
        }
        let tail = distance2[full..n].iter_mut().zip(&run.cutoff2[full..n]);
        for (k, (d2, &cut)) in (full..n).zip(tail) {
            *d2 = point_distance2(run, k, p);
            picked[m] = k as u32;
            m += usize::from(*d2 < cut);
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of atoms on a jittered line through the box, some inside their cutoffs.
    fn arrays(n: usize) -> [Vec<f32>; 4] {
        let f = |k: usize, s: f32| (k as f32 * s).sin() * 4.0;
        [
            (0..n).map(|k| f(k, 0.37)).collect(),
            (0..n).map(|k| f(k, 0.71)).collect(),
            (0..n).map(|k| f(k, 1.13)).collect(),
            (0..n).map(|k| 1.0 + (k % 5) as f32).collect(),
        ]
    }

    #[test]
    fn every_variant_picks_the_same_atoms_with_the_same_distances() {
        let mut variants = vec![Lanes::Portable];
        if Lanes::detect() != Lanes::Portable {
            variants.push(Lanes::detect());
        }
        for n in [0, 1, 7, 8, 9, 31, 64, 101] {
            let [x, y, z, cutoff2] = arrays(n);
            let run = Run {
                x: &x,
                y: &y,
                z: &z,
                cutoff2: &cutoff2,
            };
            let (lo, hi, p) = (
                Vec3::splat(-0.5),
                Vec3::new(1.0, 0.5, 0.8),
                Vec3::new(0.3, -1.0, 2.0),
            );
            // What the loops must give, written out plainly.
            let near_box: Vec<u32> = (0..n)
                .filter(|&k| box_distance2(x[k], y[k], z[k], lo, hi) < cutoff2[k])
                .map(|k| 100 + k as u32)
                .collect();
            let near_point: Vec<u32> = (0..n)
                .filter(|&k| Vec3::new(x[k], y[k], z[k]).distance_squared(p) < cutoff2[k])
                .map(|k| k as u32)
                .collect();
            let mut distances = Vec::new();
            for &lanes in &variants {
                let mut picked = vec![7u32; 3 + n + SLACK];
                let end = pick_near_box(lanes, run, lo, hi, 100, &mut picked, 3);
                assert_eq!(picked[3..end], near_box[..], "{lanes:?} near box, n = {n}");
                assert_eq!(picked[..3], [7, 7, 7], "{lanes:?} wrote before its start");
                let mut d2 = vec![0.0f32; n];
                let m = pick_near_point(lanes, run, p, &mut d2, &mut picked);
                assert_eq!(picked[..m], near_point[..], "{lanes:?} near point, n = {n}");
                distances.push(d2.iter().map(|d| d.to_bits()).collect::<Vec<_>>());
            }
            assert!(distances.windows(2).all(|w| w[0] == w[1]), "n = {n}");
        }
    }
}
