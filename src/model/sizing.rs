//! Radii for particles of unknown type (DESIGN section 2: "unknown particle types get a radius
//! that fits their size"). A LAMMPS dump names particles `1`, `2`, ... with no element; giving
//! them all 1.5 Å would be arbitrary. Instead each such type gets half the median distance from
//! its particles to their nearest neighbour of the same type in the first frame: about the
//! contact radius of a packed particle (argon 1.9 Å, water oxygen 1.4 Å).

use std::collections::HashMap;

use glam::{IVec3, Vec3};

use super::Topology;
use super::cells::CellList;

/// Fitted radii are clamped to this range in Å.
const RADIUS_RANGE: (f32, f32) = (0.5, 3.0);

/// Types with fewer particles keep their table radius: a few scattered ions say nothing about
/// their size through their spacing.
const MIN_PARTICLES: usize = 100;

/// Particles of a type used to measure it (a sample keeps the cost linear and small).
const SAMPLE: usize = 2000;

/// Replaces the table radius of every particle with no element by a radius fitted to its
/// type's spacing in `positions` (Å), per the module notes. Types with fewer than 100 particles,
/// or whose particles have no neighbour nearby, keep their radius. Does nothing for
/// coarse-grained systems (their beads already have the bead radius) or when `positions` does
/// not match the topology.
pub fn fit_untyped_radii(topology: &mut Topology, positions: &[Vec3]) {
    let n = topology.len();
    if positions.len() != n || topology.elements.len() != n || topology.radii.len() != n {
        return;
    }
    if super::elements::looks_coarse_grained(topology.names.iter()) {
        return;
    }
    let mut types: HashMap<&str, Vec<usize>> = HashMap::new();
    for i in (0..n).filter(|&i| topology.elements[i].is_empty()) {
        types.entry(&topology.names[i]).or_default().push(i);
    }
    let fitted: Vec<(Vec<usize>, f32)> = types
        .into_iter()
        .filter(|(_, atoms)| atoms.len() >= MIN_PARTICLES)
        .filter_map(|(_, atoms)| {
            let points: Vec<Vec3> = atoms.iter().map(|&i| positions[i]).collect();
            let spacing = median_nearest_distance(&points)?;
            let radius = (spacing / 2.0).clamp(RADIUS_RANGE.0, RADIUS_RANGE.1);
            Some((atoms, radius))
        })
        .collect();
    for (atoms, radius) in fitted {
        atoms.iter().for_each(|&i| topology.radii[i] = radius);
    }
}

/// Median over (a sample of) `points` of the distance to the nearest other point, in Å; `None`
/// for fewer than two finite points.
fn median_nearest_distance(points: &[Vec3]) -> Option<f32> {
    let points: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    if points.len() < 2 {
        return None;
    }
    let (lo, hi) = points
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), &p| (a.min(p), b.max(p)));
    let extent = (hi - lo).max(Vec3::splat(1e-3));
    // Twice the mean spacing per cell, so most nearest neighbours lie in the 27 cells around.
    let mean_spacing = (extent.x * extent.y * extent.z / points.len() as f32).cbrt();
    let cell = (2.0 * mean_spacing).max(0.1);
    // Cells at least `cell` wide (wider when a flat or thin cloud would need more than a few
    // per point): every point within `cell` of another lies in the 27 cells around it.
    let items: Vec<(u32, Vec3)> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| (i as u32, p))
        .collect();
    let dims_for = |edge: f32| (extent.as_dvec3() / edge as f64).floor() + 1.0;
    let limit = (8 * points.len()).max(1 << 12) as f64;
    let mut edge = cell;
    while dims_for(edge).element_product() > limit {
        edge *= 1.25;
    }
    let grid = CellList::new(&items, lo, edge, dims_for(edge).as_ivec3());
    let step = points.len().div_ceil(SAMPLE).max(1);
    let mut nearest: Vec<f32> = (0..points.len())
        .step_by(step)
        .filter_map(|i| {
            let p = points[i];
            let c = grid.cell_of(p);
            let mut best = f32::INFINITY;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (near, ids) = grid.cell(c + IVec3::new(dx, dy, dz));
                        for (q, _) in near.iter().zip(ids).filter(|&(_, &j)| j as usize != i) {
                            best = best.min(p.distance(*q));
                        }
                    }
                }
            }
            // Within the searched cells only; farther neighbours do not set a size.
            (best <= cell && best > 0.0).then_some(best)
        })
        .collect();
    if nearest.is_empty() {
        return None;
    }
    nearest.sort_unstable_by(f32::total_cmp);
    Some(nearest[nearest.len() / 2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Labels;

    fn lattice(spacing: f32, side: usize) -> Vec<Vec3> {
        let mut v = Vec::new();
        for x in 0..side {
            for y in 0..side {
                for z in 0..side {
                    v.push(Vec3::new(x as f32, y as f32, z as f32) * spacing);
                }
            }
        }
        v
    }

    #[test]
    fn lattice_spacing_sets_the_radius() {
        let d = median_nearest_distance(&lattice(3.8, 6)).expect("distance");
        assert!((d - 3.8).abs() < 1e-4, "{d}");
        assert_eq!(median_nearest_distance(&[Vec3::ZERO]), None);
        let points = lattice(3.0, 5);
        let n = points.len();
        let mut top = Topology {
            names: Labels::filled("1", n),
            elements: Labels::filled("", n),
            radii: vec![1.5; n],
            ..Default::default()
        };
        top.names.set(0, "C");
        top.elements.set(0, "C");
        fit_untyped_radii(&mut top, &points);
        assert_eq!(top.radii[0], 1.5, "atoms with an element keep their radius");
        assert!(
            top.radii[1..].iter().all(|&r| (r - 1.5).abs() < 1e-4),
            "3 Å spacing -> 1.5 Å"
        );
        let mut wide = top.clone();
        fit_untyped_radii(&mut wide, &lattice(8.0, 5));
        assert!(
            wide.radii[1..].iter().all(|&r| r == 3.0),
            "8 Å spacing is clamped to 3 Å"
        );
    }
}
