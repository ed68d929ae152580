//! Radii that follow exposure, frame by frame: the SES preset's correction for a sum of
//! Gaussians that swells around atoms with few neighbours and fills narrow grooves (issue 13
//! section 2).
//!
//! An [`ExposureModel`] counts, for every atom, the heavy atoms of its representation within
//! [`ExposureModel::radius`] (itself included when heavy), n, and multiplies the atom's radius
//! by `1 + sum_k w_k clamp((m_k - n) / m_k, 0, 1)` over its terms (m_k heavy atoms, w_k a
//! weight), never below [`MIN_FACTOR`]. An atom with at least the largest m_k around it keeps
//! its radius. The counts depend on positions, so the radii are recomputed every frame (the
//! engines detect new radii and upload them). `scripts/ses_models.py` fits the terms with the
//! preset's R, I and radii.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::cells::CellList;

/// The smallest factor an [`ExposureModel`] applies to a radius.
pub const MIN_FACTOR: f32 = 0.2;

/// How radii follow the number of heavy atoms around each atom (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExposureModel {
    /// Radius (Å) within which heavy atoms are counted.
    pub radius: f32,
    /// (m, w) of each term: below m heavy atoms (a count), the radius factor changes by w
    /// times the missing fraction (m - n) / m.
    pub terms: &'static [(f32, f32)],
}

impl ExposureModel {
    /// The count from which no term changes a radius: the largest m.
    pub fn saturation(&self) -> u32 {
        self.terms.iter().fold(0.0f32, |a, &(m, _)| a.max(m)).ceil() as u32
    }

    /// The radius factor of an atom with `n` heavy atoms around it.
    pub fn factor(&self, n: u32) -> f32 {
        let n = n as f32;
        let f = self
            .terms
            .iter()
            .fold(1.0, |f, &(m, w)| f + w * ((m - n) / m).clamp(0.0, 1.0));
        f.max(MIN_FACTOR)
    }

    /// `radii` (Å) of the atoms at `positions` (Å), each times its factor; `heavy[i]` says
    /// which atoms count as neighbours.
    pub fn apply(&self, radii: &[f32], positions: &[Vec3], heavy: &[bool]) -> Vec<f32> {
        let counts = heavy_neighbour_counts(positions, heavy, self.radius, self.saturation());
        radii
            .iter()
            .zip(counts)
            .map(|(&r, n)| r * self.factor(n))
            .collect()
    }
}

/// Cells per counting radius along an axis: cells of a quarter of the radius mostly lie wholly
/// inside or wholly outside an atom's sphere, so most are counted or skipped whole, without a
/// distance per atom.
const CELLS_PER_RADIUS: f32 = 4.0;

/// For every atom of `positions` (Å), the heavy atoms (`heavy[i]`) within `radius` (Å) of it,
/// itself included when heavy, counted up to `cap` (an atom stops counting there: a model needs
/// no more than its [`ExposureModel::saturation`], and most atoms of a protein or a solvated
/// system reach it in the cells nearest to them, which are visited first). Atoms in parallel.
pub fn heavy_neighbour_counts(
    positions: &[Vec3],
    heavy: &[bool],
    radius: f32,
    cap: u32,
) -> Vec<u32> {
    let heavy_atoms: Vec<(u32, Vec3)> = positions
        .iter()
        .zip(heavy)
        .enumerate()
        .filter_map(|(i, (&p, &h))| h.then_some((i as u32, p)))
        .collect();
    if heavy_atoms.is_empty() {
        return vec![0; positions.len()];
    }
    let (lo, hi) = heavy_atoms
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &(_, p)| {
            (lo.min(p), hi.max(p))
        });
    // Cells of radius / CELLS_PER_RADIUS, larger where atoms are sparse over a large box (no
    // more than four cells per heavy atom; counted in f64, so that a box of any finite size
    // gets cells).
    let limit = (4 * heavy_atoms.len()).max(1 << 12) as f64;
    let extent = (hi - lo).as_dvec3();
    let mut size = radius / CELLS_PER_RADIUS;
    let dims_for = |size: f32| (extent / size as f64).floor() + 1.0;
    while dims_for(size).element_product() > limit {
        size *= 1.25;
    }
    let cells = CellList::new(&heavy_atoms, lo, size, dims_for(size).as_ivec3());
    // The cells around an atom's own cell that its sphere can reach, nearest first.
    let reach = (radius / size).ceil() as i32;
    let r2 = radius * radius;
    let mut offsets: Vec<IVec3> = (-reach..=reach)
        .flat_map(|z| (-reach..=reach).flat_map(move |y| (-reach..=reach).map(move |x| (x, y, z))))
        .map(|(x, y, z)| IVec3::new(x, y, z))
        .filter(|o| {
            let gap = (o.abs() - 1).max(IVec3::ZERO).as_vec3() * size;
            gap.length_squared() <= r2
        })
        .collect();
    offsets.sort_by_key(|o| o.length_squared());
    positions
        .par_iter()
        .map(|&p| {
            let own = cells.cell_of(p);
            let mut n = 0u32;
            for &o in &offsets {
                let cell = own + o;
                let (atoms, _) = cells.cell(cell);
                if atoms.is_empty() {
                    continue;
                }
                let (box_lo, box_hi) = cells.cell_box(cell);
                let nearest = (box_lo - p).max(p - box_hi).max(Vec3::ZERO);
                if nearest.length_squared() > r2 {
                    continue;
                }
                let farthest = (p - box_lo).abs().max((box_hi - p).abs());
                n += if farthest.length_squared() <= r2 {
                    atoms.len() as u32
                } else {
                    atoms.iter().filter(|q| q.distance_squared(p) <= r2).count() as u32
                };
                if n >= cap {
                    return cap;
                }
            }
            n
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force counts within `radius`, for comparison.
    fn brute(positions: &[Vec3], heavy: &[bool], radius: f32) -> Vec<u32> {
        let r2 = radius * radius;
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
        for radius in [10.0, 16.0] {
            let all = brute(&positions, &heavy, radius);
            let counted = heavy_neighbour_counts(&positions, &heavy, radius, u32::MAX);
            assert_eq!(counted, all, "radius {radius}");
            let capped: Vec<u32> = all.iter().map(|&n| n.min(8)).collect();
            assert!(all.iter().any(|&n| n > 8) && all.iter().any(|&n| n < 8));
            assert_eq!(
                heavy_neighbour_counts(&positions, &heavy, radius, 8),
                capped
            );
        }
    }

    /// A model of two terms: shrink below 40, grow a little below 80 (the SES preset has one
    /// term; a second was among the models compared).
    const TWO_TERMS: ExposureModel = ExposureModel {
        radius: 10.0,
        terms: &[(40.0, -0.5), (80.0, 0.1)],
    };

    #[test]
    fn the_factor_is_piecewise_linear_in_the_count_and_one_from_the_largest_m() {
        let m = TWO_TERMS;
        assert_eq!(m.saturation(), 80);
        assert_eq!(m.factor(80), 1.0);
        assert_eq!(m.factor(500), 1.0);
        // 60 atoms: only the second term, a quarter of its way.
        assert!((m.factor(60) - (1.0 + 0.1 * 0.25)).abs() < 1e-6);
        // 20 atoms: half of the first term, three quarters of the second.
        assert!((m.factor(20) - (1.0 - 0.25 + 0.075)).abs() < 1e-6);
        // No neighbour: both terms whole.
        assert!((m.factor(0) - 0.6).abs() < 1e-6);
        // Never below MIN_FACTOR.
        let steep = ExposureModel {
            radius: 10.0,
            terms: &[(10.0, -2.0)],
        };
        assert_eq!(steep.factor(0), MIN_FACTOR);
    }

    #[test]
    fn an_isolated_atom_takes_the_whole_terms_and_a_buried_one_keeps_its_radius() {
        // One lone heavy atom far away, and a 5 x 5 x 4 block of 100 heavy atoms 1 Å apart
        // (each has all 100 within 10 Å: buried, past the model's 80).
        let mut positions = vec![Vec3::new(100.0, 0.0, 0.0)];
        for z in 0..4 {
            for y in 0..5 {
                for x in 0..5 {
                    positions.push(Vec3::new(x as f32, y as f32, z as f32));
                }
            }
        }
        let heavy = vec![true; positions.len()];
        let radii = vec![1.5; positions.len()];
        let out = TWO_TERMS.apply(&radii, &positions, &heavy);
        // The lone atom counts itself: n = 1.
        let expected = 1.5 * TWO_TERMS.factor(1);
        assert!((out[0] - expected).abs() < 1e-6, "{} vs {expected}", out[0]);
        assert!(out[1..].iter().all(|&r| r == 1.5), "{:?}", &out[1..5]);
        // Hydrogens are not neighbours: the same lone atom among hydrogens stays as exposed,
        // and the block, hydrogens now, has no heavy atom within 10 Å (n = 0).
        let mut heavy_lone = vec![false; positions.len()];
        heavy_lone[0] = true;
        let lone = TWO_TERMS.apply(&radii, &positions, &heavy_lone);
        assert!((lone[0] - expected).abs() < 1e-6);
        assert!((lone[1] - 1.5 * TWO_TERMS.factor(0)).abs() < 1e-6);
    }

    #[test]
    fn an_atom_far_from_the_others_gets_counts_without_a_grid_the_size_of_the_gap() {
        // A protein-sized cluster and one heavy atom 1e30 Å away (an XYZ file can hold it):
        // the cells grow instead of the grid, and the counts stay exact.
        let mut positions: Vec<Vec3> = (0..200)
            .map(|i| Vec3::new((i % 6) as f32, ((i / 6) % 6) as f32, (i / 36) as f32) * 1.5)
            .collect();
        positions.push(Vec3::new(1e30, 0.0, 0.0));
        let heavy = vec![true; positions.len()];
        for radius in [10.0, 16.0] {
            let counted = heavy_neighbour_counts(&positions, &heavy, radius, u32::MAX);
            assert_eq!(
                counted,
                brute(&positions, &heavy, radius),
                "radius {radius}"
            );
            assert_eq!(counted[200], 1);
        }
    }
}
