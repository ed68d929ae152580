//! Radii shrunk on exposed atoms, frame by frame: the SES preset's correction for a sum of
//! Gaussians swelling around atoms with few neighbours (issue 13 section 2).
//!
//! An atom is exposed when fewer than [`EXPOSED_BELOW`] heavy atoms of its representation lie
//! within [`EXPOSURE_RADIUS`] of it (itself included when heavy). Its radius is multiplied by
//! `1 - beta (EXPOSED_BELOW - n) / EXPOSED_BELOW` (n the count), so an atom with no heavy
//! neighbour shrinks by the fraction beta and one with [`EXPOSED_BELOW`] or more keeps its
//! radius. The counts depend on positions, so the radii are recomputed every frame (the
//! engines detect new radii and upload them). `scripts/ses_models.py --model exposed` fits beta
//! with the preset's R, I and radii.

use glam::Vec3;
use rayon::prelude::*;

/// Neighbourhood radius (Å) in which heavy atoms are counted.
pub const EXPOSURE_RADIUS: f32 = 10.0;
/// Heavy atoms within [`EXPOSURE_RADIUS`] from which an atom counts as buried.
pub const EXPOSED_BELOW: f32 = 60.0;

/// For every atom of `positions` (Å), the heavy atoms (`heavy[i]`) within
/// [`EXPOSURE_RADIUS`] of it, itself included when heavy, counted up to `cap` (an atom stops
/// counting there: the shrink needs no more than [`EXPOSED_BELOW`], and most atoms of a
/// protein or a solvated system reach it in their first cells). Cells of [`EXPOSURE_RADIUS`];
/// atoms in parallel.
pub fn heavy_neighbour_counts(positions: &[Vec3], heavy: &[bool], cap: u32) -> Vec<u32> {
    let heavy_positions: Vec<Vec3> = positions
        .iter()
        .zip(heavy)
        .filter_map(|(&p, &h)| h.then_some(p))
        .collect();
    if heavy_positions.is_empty() {
        return vec![0; positions.len()];
    }
    let lo = heavy_positions
        .iter()
        .fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
    let hi = heavy_positions
        .iter()
        .fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
    let dims = ((hi - lo) / EXPOSURE_RADIUS).floor().as_uvec3() + 1;
    let cell_of = |p: Vec3| ((p - lo) / EXPOSURE_RADIUS).floor().as_ivec3();
    let index = |c: glam::IVec3| (c.x + dims.x as i32 * (c.y + dims.y as i32 * c.z)) as usize;
    // Heavy atoms sorted by cell (counting sort): cell k holds start[k]..start[k + 1].
    let cell_count = (dims.x * dims.y * dims.z) as usize;
    let mut start = vec![0u32; cell_count + 1];
    for &p in &heavy_positions {
        start[index(cell_of(p)) + 1] += 1;
    }
    for k in 0..cell_count {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut sorted = vec![Vec3::ZERO; heavy_positions.len()];
    for &p in &heavy_positions {
        let k = index(cell_of(p));
        sorted[fill[k] as usize] = p;
        fill[k] += 1;
    }
    let r2 = EXPOSURE_RADIUS * EXPOSURE_RADIUS;
    let max = dims.as_ivec3() - 1;
    positions
        .par_iter()
        .map(|&p| {
            let c = cell_of(p);
            let (from, to) = ((c - 1).max(glam::IVec3::ZERO), (c + 1).min(max));
            // The atom's own cell first (it holds most of the neighbours; clamped into the grid
            // for an atom outside the heavy atoms' box: any cell may be visited, each once).
            let around = (from.z..=to.z).flat_map(|z| {
                (from.y..=to.y)
                    .flat_map(move |y| (from.x..=to.x).map(move |x| glam::IVec3::new(x, y, z)))
            });
            let mut n = 0u32;
            let own = c.clamp(glam::IVec3::ZERO, max);
            for cell in std::iter::once(own).chain(around.filter(|&q| q != own)) {
                let k = index(cell);
                let atoms = &sorted[start[k] as usize..start[k + 1] as usize];
                n += atoms.iter().filter(|q| q.distance_squared(p) <= r2).count() as u32;
                if n >= cap {
                    return cap;
                }
            }
            n
        })
        .collect()
}

/// `radii` (Å) of the atoms at `positions` (Å) with the exposed ones shrunk by up to the
/// fraction `beta` (see the module docs); `heavy[i]` says which atoms count as neighbours.
pub fn shrink_exposed(radii: &[f32], positions: &[Vec3], heavy: &[bool], beta: f32) -> Vec<f32> {
    let counts = heavy_neighbour_counts(positions, heavy, EXPOSED_BELOW as u32);
    radii
        .iter()
        .zip(counts)
        .map(|(&r, n)| {
            let exposure = ((EXPOSED_BELOW - n as f32) / EXPOSED_BELOW).clamp(0.0, 1.0);
            r * (1.0 - beta * exposure)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force counts, for comparison.
    fn brute(positions: &[Vec3], heavy: &[bool]) -> Vec<u32> {
        let r2 = EXPOSURE_RADIUS * EXPOSURE_RADIUS;
        positions
            .iter()
            .map(|&p| {
                (positions.iter().zip(heavy))
                    .filter(|&(&q, &h)| h && q.distance_squared(p) <= r2)
                    .count() as u32
            })
            .collect()
    }

    #[test]
    fn cell_counts_match_brute_force_on_a_spread_of_atoms() {
        // A deterministic scatter over 60 Å with some hydrogens, and points near cell faces.
        let mut positions = Vec::new();
        let mut heavy = Vec::new();
        let mut s = 12345u32;
        for i in 0..800 {
            let mut next = || {
                s = s.wrapping_mul(1664525).wrapping_add(1013904223);
                (s >> 8) as f32 / (1u32 << 24) as f32
            };
            positions.push(Vec3::new(next(), next(), next()) * 60.0 - 7.0);
            heavy.push(i % 3 != 0);
        }
        positions.push(Vec3::new(3.0, 13.0, 23.0));
        heavy.push(true);
        let all = brute(&positions, &heavy);
        assert_eq!(heavy_neighbour_counts(&positions, &heavy, u32::MAX), all);
        let capped: Vec<u32> = all.iter().map(|&n| n.min(8)).collect();
        assert!(all.iter().any(|&n| n > 8) && all.iter().any(|&n| n < 8));
        assert_eq!(heavy_neighbour_counts(&positions, &heavy, 8), capped);
    }

    #[test]
    fn an_isolated_atom_shrinks_by_beta_and_a_buried_one_keeps_its_radius() {
        // One lone heavy atom far away, and a 4 x 4 x 4 block of 64 heavy atoms 1 Å apart
        // (each has all 64 within 10 Å: buried).
        let mut positions = vec![Vec3::new(100.0, 0.0, 0.0)];
        for z in 0..4 {
            for y in 0..4 {
                for x in 0..4 {
                    positions.push(Vec3::new(x as f32, y as f32, z as f32));
                }
            }
        }
        let heavy = vec![true; positions.len()];
        let radii = vec![1.5; positions.len()];
        let out = shrink_exposed(&radii, &positions, &heavy, 0.2);
        // The lone atom counts itself: n = 1.
        let expected = 1.5 * (1.0 - 0.2 * (EXPOSED_BELOW - 1.0) / EXPOSED_BELOW);
        assert!((out[0] - expected).abs() < 1e-6, "{} vs {expected}", out[0]);
        assert!(out[1..].iter().all(|&r| r == 1.5), "{:?}", &out[1..5]);
        // Hydrogens are not neighbours: the same lone atom among hydrogens stays as exposed.
        let mut heavy_lone = vec![false; positions.len()];
        heavy_lone[0] = true;
        let lone = shrink_exposed(&radii, &positions, &heavy_lone, 0.2);
        assert!((lone[0] - expected).abs() < 1e-6);
        assert!(lone[1] < 1.5 * (1.0 - 0.2 * 0.99));
    }
}
