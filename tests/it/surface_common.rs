//! Shared helpers for the surface tests: small atom systems and a one-call CPU surface.

#![allow(dead_code)]

use glam::Vec3;
use mdsurf::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceOutput, SurfaceParams};

/// Computes the surface of `positions` with `radii` (and optional colours) on the CPU engine.
pub fn surface(
    positions: &[Vec3],
    radii: &[f32],
    colours: Option<&[[f32; 3]]>,
    params: &SurfaceParams,
) -> SurfaceOutput {
    let atoms = AtomSet {
        positions,
        radii,
        colours,
    };
    CpuEngine::new()
        .compute(&atoms, params)
        .expect("surface of a valid system")
}

/// A small deterministic pseudo-random generator (xorshift), values in 0..1.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A compact random cluster of `n` atoms in a cube of side `side` Å around `centre`, with radii
/// between 1.0 and 1.9 Å.
pub fn cluster(n: usize, side: f32, centre: Vec3, seed: u64) -> (Vec<Vec3>, Vec<f32>) {
    let mut rng = Rng(seed);
    let positions = (0..n)
        .map(|_| centre + side * (Vec3::new(rng.next(), rng.next(), rng.next()) - 0.5))
        .collect();
    let radii = (0..n).map(|_| 1.0 + 0.9 * rng.next()).collect();
    (positions, radii)
}

/// Radius in Å of the sphere an isolated atom of width `alpha` (Å) gives at isovalue `iso`.
pub fn sphere_radius(alpha: f32, iso: f32) -> f64 {
    alpha as f64 * (2.0 * (1.0 / iso as f64).ln()).sqrt()
}
