//! Synthetic large systems for benchmarks: a real structure tiled on a 3D lattice up to a
//! requested particle count, or particles on hollow spherical shells (a capsid-like system that
//! is mostly empty space inside its box), with fresh random jitter in every frame so no frame
//! repeats data. Feeds `mdsurf bench --synthetic N`, `--synthetic-shell N` and `--table1` in
//! place of a trajectory file.

use glam::Vec3;
use rayon::prelude::*;

/// Why a synthetic system could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SyntheticError {
    /// The structure to tile has no particles.
    #[error("cannot tile an empty structure")]
    EmptySource,
    /// Positions and radii (or colours) differ in length.
    #[error("the structure has {positions} positions but {other} radii or colours")]
    LengthMismatch {
        /// Number of positions.
        positions: usize,
        /// Length of the other array.
        other: usize,
    },
    /// A coordinate or radius is not finite.
    #[error("particle {0} of the structure has a NaN or infinite coordinate or radius")]
    NonFinite(usize),
    /// Zero particles were requested.
    #[error("the synthetic system must have at least one particle")]
    ZeroParticles,
}

/// A tiled system: static base positions plus per-frame jitter.
#[derive(Debug, Clone)]
pub struct SyntheticSystem {
    base: Vec<Vec3>,
    radii: Vec<f32>,
    colours: Option<Vec<[f32; 3]>>,
    copies: [usize; 3],
    jitter: f32,
    seed: u64,
}

/// Gap in Å between the bounding boxes of neighbouring copies.
pub const TILE_GAP: f32 = 2.0;
/// Layers of a synthetic shell ([`SyntheticSystem::shell`]): with [`SHELL_SPACING`] a coat
/// about 9 Å thick, a thin capsid-like shell that grows in radius with the particle count.
pub const SHELL_LAYERS: usize = 6;
/// Distance in Å between a shell's layers and between neighbouring particles on a layer.
pub const SHELL_SPACING: f32 = 1.5;
/// Radius in Å of a shell's innermost layer when the particles fit (the paper's hollow-shell
/// test uses 60 Å).
pub const SHELL_INNER_RADIUS: f32 = 60.0;
/// Default jitter amplitude in Å (each coordinate moves uniformly within ± this per frame).
pub const DEFAULT_JITTER: f32 = 0.1;

impl SyntheticSystem {
    /// Tiles the structure (`positions` in Å, `radii` in Å, optional linear RGB `colours`) on a
    /// near-cubic lattice with [`TILE_GAP`] between copies' bounding boxes until `count`
    /// particles exist; the last copy is truncated. Copies fill x first, then y, then z.
    pub fn tile(
        positions: &[Vec3],
        radii: &[f32],
        colours: Option<&[[f32; 3]]>,
        count: usize,
    ) -> Result<SyntheticSystem, SyntheticError> {
        let n = positions.len();
        if n == 0 {
            return Err(SyntheticError::EmptySource);
        }
        if count == 0 {
            return Err(SyntheticError::ZeroParticles);
        }
        for other in [Some(radii.len()), colours.map(|c| c.len())]
            .into_iter()
            .flatten()
        {
            if other != n {
                return Err(SyntheticError::LengthMismatch {
                    positions: n,
                    other,
                });
            }
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (i, (p, r)) in positions.iter().zip(radii).enumerate() {
            if !p.is_finite() || !r.is_finite() {
                return Err(SyntheticError::NonFinite(i));
            }
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let stride = (hi - lo) + Vec3::splat(TILE_GAP);
        let total_copies = count.div_ceil(n);
        let copies = lattice_shape(total_copies);

        let mut base = Vec::with_capacity(count);
        let mut out_radii = Vec::with_capacity(count);
        let mut out_colours = colours.map(|_| Vec::with_capacity(count));
        'outer: for c in 0..total_copies {
            let cell = [
                c % copies[0],
                (c / copies[0]) % copies[1],
                c / (copies[0] * copies[1]),
            ];
            let shift = stride * Vec3::new(cell[0] as f32, cell[1] as f32, cell[2] as f32) - lo;
            for i in 0..n {
                if base.len() == count {
                    break 'outer;
                }
                base.push(positions[i] + shift);
                out_radii.push(radii[i]);
                if let (Some(out), Some(src)) = (out_colours.as_mut(), colours) {
                    out.push(src[i]);
                }
            }
        }
        Ok(SyntheticSystem {
            base,
            radii: out_radii,
            colours: out_colours,
            copies,
            jitter: DEFAULT_JITTER,
            seed: 0x6d64_7375_7266,
        })
    }

    /// Places `count` particles on hollow concentric spherical shells around the origin, like a
    /// virus capsid: [`SHELL_LAYERS`] layers [`SHELL_SPACING`] Å apart, particles
    /// [`SHELL_SPACING`] Å apart on each layer (Fibonacci spirals), the innermost layer at
    /// [`SHELL_INNER_RADIUS`] Å or further out when `count` needs more room. The bounding box
    /// is mostly empty inside, which the sparse bricks skip. Radii and colours are those of the
    /// structure (`radii` in Å, optional linear RGB `colours`), repeated in order.
    pub fn shell(
        radii: &[f32],
        colours: Option<&[[f32; 3]]>,
        count: usize,
    ) -> Result<SyntheticSystem, SyntheticError> {
        let n = radii.len();
        if n == 0 {
            return Err(SyntheticError::EmptySource);
        }
        if count == 0 {
            return Err(SyntheticError::ZeroParticles);
        }
        if let Some(c) = colours
            && c.len() != n
        {
            return Err(SyntheticError::LengthMismatch {
                positions: n,
                other: c.len(),
            });
        }
        if let Some(i) = radii.iter().position(|r| !r.is_finite()) {
            return Err(SyntheticError::NonFinite(i));
        }
        let per_layer = |r: f32| {
            (4.0 * std::f32::consts::PI * r * r / (SHELL_SPACING * SHELL_SPACING)) as usize
        };
        let capacity = |inner: f32| -> usize {
            (0..SHELL_LAYERS)
                .map(|k| per_layer(inner + SHELL_SPACING * k as f32).max(1))
                .sum()
        };
        let mut inner = SHELL_INNER_RADIUS;
        while capacity(inner) < count {
            inner += 1.0;
        }
        // Spread the particles over the layers in proportion to their area.
        let total = capacity(inner);
        let mut base = Vec::with_capacity(count);
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        for k in 0..SHELL_LAYERS {
            let r = inner + SHELL_SPACING * k as f32;
            let want = (per_layer(r).max(1) * count).div_ceil(total);
            let m = want.min(count - base.len());
            for i in 0..m {
                let y = 1.0 - 2.0 * (i as f32 + 0.5) / m as f32;
                let ring = (1.0 - y * y).max(0.0).sqrt();
                let phi = golden * i as f32 + k as f32;
                base.push(r * Vec3::new(ring * phi.cos(), y, ring * phi.sin()));
            }
        }
        let out_radii = (0..count).map(|i| radii[i % n]).collect();
        let out_colours = colours.map(|c| (0..count).map(|i| c[i % n]).collect());
        base.truncate(count);
        Ok(SyntheticSystem {
            base,
            radii: out_radii,
            colours: out_colours,
            copies: [1, 1, 1],
            jitter: DEFAULT_JITTER,
            seed: 0x6d64_7375_7266,
        })
    }

    /// Sets the jitter amplitude in Å (0 makes every frame the tiled structure itself).
    pub fn with_jitter(mut self, jitter: f32) -> Self {
        self.jitter = jitter.max(0.0);
        self
    }

    /// Sets the random seed; the same seed gives the same frames.
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.base.len()
    }

    /// True when there are no particles (never, once built).
    pub fn is_empty(&self) -> bool {
        self.base.is_empty()
    }

    /// Copies along x, y and z of the lattice (the last one may be partial or unused).
    pub fn copies(&self) -> [usize; 3] {
        self.copies
    }

    /// Radius of each particle in Å.
    pub fn radii(&self) -> &[f32] {
        &self.radii
    }

    /// Linear RGB colour of each particle, when the source had colours.
    pub fn colours(&self) -> Option<&[[f32; 3]]> {
        self.colours.as_deref()
    }

    /// The tiled positions without jitter, in Å.
    pub fn base_positions(&self) -> &[Vec3] {
        &self.base
    }

    /// Writes frame `frame`'s positions (Å) into `out`: base plus a jitter that depends only on
    /// the seed, the frame and the particle index (deterministic, whatever the thread count).
    pub fn frame_into(&self, frame: usize, out: &mut Vec<Vec3>) {
        const CHUNK: usize = 1 << 14;
        out.resize(self.base.len(), Vec3::ZERO);
        let amp = self.jitter;
        out.par_chunks_mut(CHUNK)
            .zip(self.base.par_chunks(CHUNK))
            .enumerate()
            .for_each(|(c, (dst, src))| {
                let mut rng = SplitMix64::new(
                    self.seed
                        ^ (frame as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                        ^ (c as u64) << 1,
                );
                for (d, s) in dst.iter_mut().zip(src) {
                    let j = Vec3::new(rng.next_signed(), rng.next_signed(), rng.next_signed());
                    *d = *s + amp * j;
                }
            });
    }

    /// Frame `frame`'s positions in Å (see [`SyntheticSystem::frame_into`]).
    pub fn frame(&self, frame: usize) -> Vec<Vec3> {
        let mut out = Vec::new();
        self.frame_into(frame, &mut out);
        out
    }
}

/// Copies per axis for `total` copies on a near-cubic lattice (x >= y >= z, product >= total).
fn lattice_shape(total: usize) -> [usize; 3] {
    let nx = (total as f64).cbrt().ceil().max(1.0) as usize;
    let ny = ((total as f64 / nx as f64).sqrt().ceil() as usize).max(1);
    let nz = total.div_ceil(nx * ny).max(1);
    [nx, ny, nz]
}

/// SplitMix64: a tiny, fast, well-mixed generator; plenty for jitter.
struct SplitMix64(u64);

impl SplitMix64 {
    fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [-1, 1).
    fn next_signed(&mut self) -> f32 {
        ((self.next_u64() >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// `count` points spread evenly on a sphere of `radius` Å around `centre` (a Fibonacci spiral
/// about the z axis): the atoms of the hollow shells the cavity tests measure.
pub fn sphere_points(count: usize, radius: f32, centre: Vec3) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..count)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / count as f32;
            let ring = (1.0 - z * z).sqrt();
            let phi = golden * k as f32;
            centre + radius * Vec3::new(ring * phi.cos(), ring * phi.sin(), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair() -> (Vec<Vec3>, Vec<f32>) {
        (vec![Vec3::ZERO, Vec3::new(3.0, 1.0, 2.0)], vec![1.5, 1.0])
    }

    #[test]
    fn tiles_to_exact_count_with_gaps() {
        let (p, r) = pair();
        let s = SyntheticSystem::tile(&p, &r, None, 15).unwrap();
        assert_eq!(s.len(), 15);
        assert_eq!(s.radii().len(), 15);
        let [nx, ny, nz] = s.copies();
        assert!(nx * ny * nz >= 8, "{:?}", s.copies());
        // The second copy sits one bounding box (3 Å in x) plus the 2 Å gap further along x.
        let b = s.base_positions();
        assert_eq!(b[2] - b[0], Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(s.radii()[14], 1.5);
    }

    #[test]
    fn frames_are_deterministic_distinct_and_small() {
        let (p, r) = pair();
        let s = SyntheticSystem::tile(&p, &r, None, 50_000).unwrap();
        let f0 = s.frame(0);
        assert_eq!(f0, s.frame(0));
        let f1 = s.frame(1);
        assert_ne!(f0, f1);
        for (a, b) in f0.iter().zip(s.base_positions()) {
            assert!((*a - *b).abs().max_element() <= DEFAULT_JITTER);
        }
    }

    #[test]
    fn shells_are_hollow_and_exact_in_count() {
        let s = SyntheticSystem::shell(&[1.5, 1.7], None, 50_000).unwrap();
        assert_eq!(s.len(), 50_000);
        assert_eq!(s.radii()[1], 1.7);
        let outer = SHELL_INNER_RADIUS + SHELL_SPACING * SHELL_LAYERS as f32;
        for p in s.base_positions() {
            let r = p.length();
            assert!((SHELL_INNER_RADIUS - 1e-3..outer).contains(&r), "{r}");
        }
        let big = SyntheticSystem::shell(&[1.5], None, 2_000_000).unwrap();
        assert_eq!(big.len(), 2_000_000);
        assert!(
            big.base_positions()
                .iter()
                .all(|p| p.length() > SHELL_INNER_RADIUS)
        );
        assert!(SyntheticSystem::shell(&[], None, 10).is_err());
    }

    #[test]
    fn bad_sources_are_errors() {
        assert_eq!(
            SyntheticSystem::tile(&[], &[], None, 10).unwrap_err(),
            SyntheticError::EmptySource
        );
        let (p, _) = pair();
        assert!(SyntheticSystem::tile(&p, &[1.0], None, 10).is_err());
        let nan = [Vec3::new(f32::NAN, 0.0, 0.0)];
        assert!(SyntheticSystem::tile(&nan, &[1.0], None, 10).is_err());
    }
}
