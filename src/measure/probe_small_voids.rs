//! Probe cavities whose free centres all fall between the points of the probe grid
//! ([`super::probe_cavities`]). A void that just holds one probe (about 11.5 Å³ for water) has
//! its free centres in a region smaller than the grid step, often with no grid point in it: on
//! the grid alone it is missed.
//!
//! The clearance of a point `x` is `c(x) = min_i(|x - x_i| - r_i) - probe` (Å, atoms `i` of
//! radius `r_i`); `x` is a free probe centre when `c(x) >= 0`. `c` changes by at most the
//! distance moved, and every point lies within `m = h·√3/2` of a grid point (spacing `h`), so a
//! free centre has a grid point with `c >= -m` near it. The search:
//! 1. Seeds: blocked grid points with `c >= -m`, none of whose 26 neighbours is free, where `c`
//!    is at least that of every such neighbour (local maxima).
//! 2. From each seed, `c` is climbed to a local maximum (steps to the 26 neighbours, from `h/2`
//!    halved down to 0.001 Å, within one grid step of the seed). A maximum with `c >= 0` is a
//!    free centre.
//! 3. From it, the free points of a lattice of step `h/4` are flooded (26 neighbours). When the
//!    flood comes within a lattice diagonal (`h·√3/4`) of a free grid point, the centres belong
//!    to the outside or to a cavity the grid found already; otherwise the flooded points are a
//!    void's free centres.
//!    Seeds that climb into a void already flooded add nothing.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

use super::grid_balls::draw_balls;
use super::grid_flood::{BLOCKED, neighbours};
use super::probe_surface::near_atoms;
use crate::model::cells::CellList;
use crate::surface::{AtomSet, GridSpec};

/// Finer lattice steps per grid step in the flood of a void.
const SUBDIVISIONS: f32 = 4.0;

/// The most lattice points one flood visits; a larger free set is kept as it is (it would
/// hold grid points, and so be found on the grid, unless it is very thin).
const FLOOD_LIMIT: usize = 20_000;

/// The free centre sets (Å) of the voids between grid points: one set per void, none of them
/// connected to a free grid point. `marks` are the grid's marks after the outside and the
/// cavities were labelled ([`BLOCKED`] where a probe overlaps an atom).
pub(super) fn voids_between_grid_points(
    atoms: &AtomSet<'_>,
    grid: &GridSpec,
    marks: &[u32],
    probe: f32,
) -> Vec<Vec<Vec3>> {
    let h = grid.spacing;
    let margin = h * 3f32.sqrt() / 2.0;
    // Points deeper than the margin in the atoms: a probe shrunk by the margin overlaps one.
    let mut deep = vec![false; marks.len()];
    draw_balls(
        grid,
        &mut deep,
        atoms.positions,
        |a| (atoms.radii[a] + probe - margin).max(0.0),
        |mark, at| {
            *mark |= at.dx * at.dx < at.left;
        },
    );
    let clearance = Clearance::new(atoms, probe);
    let seeds = seeds(grid, marks, &deep, &clearance);
    drop(deep);
    let maxima: Vec<(Vec3, f32)> = seeds
        .par_iter()
        .map(|&(x, c)| {
            let reach = Vec3::splat(h);
            climb((x, c), h / 2.0, x - reach, x + reach, &clearance)
        })
        .filter(|&(_, c)| c >= 0.0)
        .collect();
    // Each void's flooded points (all of them, so that a seed climbing into it is known).
    let mut voids: Vec<Vec<Vec3>> = Vec::new();
    let step = h / SUBDIVISIONS;
    let mut joined: Vec<Vec3> = Vec::new();
    for (top, _) in maxima {
        let close = |x: &Vec3| x.distance_squared(top) <= 3.0 * step * step;
        if voids.iter().flatten().any(close) || joined.iter().any(close) {
            continue;
        }
        match flood(top, step, grid, marks, &clearance) {
            Some(points) => voids.push(points.iter().map(|&p| lattice(top, step, p)).collect()),
            None => joined.push(top),
        }
    }
    // Every second lattice point along each axis stands for a void's centres: their probe
    // balls cover those of the others to within h·√3/4 (0.1 Å at h = 0.25 Å).
    voids
        .into_iter()
        .map(|points| {
            let top = points[0];
            points
                .into_iter()
                .filter(|p| {
                    let index = ((*p - top) / step).round().as_ivec3();
                    index.to_array().iter().all(|i| i % 2 == 0)
                })
                .collect()
        })
        .collect()
}

/// The point (Å) of lattice index `p` of the lattice of `step` Å through `origin`.
fn lattice(origin: Vec3, step: f32, p: [i32; 3]) -> Vec3 {
    origin + step * IVec3::from_array(p).as_vec3()
}

/// The clearance `c(x)` of the module's doc (Å), from the atoms within `max r_i + probe` of
/// `x`: exact where it is negative, and at least 0 (its sign right) where it is not.
struct Clearance<'a> {
    atoms: AtomSet<'a>,
    cells: CellList,
    probe: f32,
    reach: f32,
}

impl<'a> Clearance<'a> {
    fn new(atoms: &AtomSet<'a>, probe: f32) -> Clearance<'a> {
        let max_radius = atoms.radii.iter().fold(0.0f32, |m, &r| m.max(r));
        let reach = max_radius + probe;
        let items: Vec<(u32, Vec3)> = (0..atoms.len())
            .map(|a| (a as u32, atoms.positions[a]))
            .collect();
        Clearance {
            atoms: *atoms,
            cells: CellList::covering(&items, reach, 1),
            probe,
            reach,
        }
    }

    /// `c(x)` in Å (at most `max r_i`: every atom farther than the reach counts as there).
    fn at(&self, x: Vec3) -> f32 {
        let mut nearest = self.reach;
        near_atoms(&self.atoms, &self.cells, x, |_, centre, radius| {
            nearest = nearest.min(centre.distance(x) - radius);
        });
        nearest - self.probe
    }
}

/// Step 1 of the module's doc: the seeds (point in Å, clearance), from the blocked points
/// that are not `deep`.
fn seeds(
    grid: &GridSpec,
    marks: &[u32],
    deep: &[bool],
    clearance: &Clearance<'_>,
) -> Vec<(Vec3, f32)> {
    let [nx, ny, _] = grid.dims.map(|d| d as isize);
    let steps: Vec<isize> = neighbours()
        .map(|[x, y, z]| x as isize + nx * (y as isize + ny * z as isize))
        .collect();
    // Blocked points lie inside the grid's free border, so their neighbours exist.
    let candidates: Vec<usize> = (0..marks.len())
        .into_par_iter()
        .filter(|&at| {
            marks[at] == BLOCKED
                && !deep[at]
                && steps
                    .iter()
                    .all(|&s| marks[(at as isize + s) as usize] == BLOCKED)
        })
        .collect();
    let values: HashMap<usize, f32> = candidates
        .par_iter()
        .map(|&at| (at, clearance.at(grid.point_at(at))))
        .collect();
    candidates
        .iter()
        .filter(|&&at| {
            let c = values[&at];
            steps.iter().all(|&s| {
                let next = (at as isize + s) as usize;
                values.get(&next).is_none_or(|&other| other <= c)
            })
        })
        .map(|&at| (grid.point_at(at), values[&at]))
        .collect()
}

/// A local maximum of the clearance from `start` (point, value): moves to the best of the 26
/// neighbours `step` Å away while that raises the clearance, else halves the step, until it is
/// under 0.001 Å; stays in the box `lo..=hi`.
fn climb(
    start: (Vec3, f32),
    step: f32,
    lo: Vec3,
    hi: Vec3,
    clearance: &Clearance<'_>,
) -> (Vec3, f32) {
    let directions: Vec<Vec3> = neighbours()
        .map(|[x, y, z]| Vec3::new(x as f32, y as f32, z as f32))
        .collect();
    let (mut best, mut step) = (start, step);
    while step >= 0.001 {
        let moved = directions
            .iter()
            .map(|d| best.0 + *d * step)
            .filter(|y| !(y.cmplt(lo) | y.cmpgt(hi)).any())
            .map(|y| (y, clearance.at(y)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .filter(|next| next.1 > best.1);
        match moved {
            Some(next) => best = next,
            None => step *= 0.5,
        }
    }
    best
}

/// Step 3 of the module's doc: the free points (lattice indices) of the lattice of `step` Å
/// through the free centre `top` connected to it, or `None` when they come within a lattice
/// diagonal of a free grid point.
fn flood(
    top: Vec3,
    step: f32,
    grid: &GridSpec,
    marks: &[u32],
    clearance: &Clearance<'_>,
) -> Option<Vec<[i32; 3]>> {
    let [nx, ny, nz] = grid.dims;
    // A free grid point one lattice diagonal or less from a flooded point joins them.
    let join = 3.0 * step * step;
    let next_to_free_grid_point = |x: Vec3| {
        let g = ((x - grid.origin) / grid.spacing).floor().as_ivec3();
        (0..8).any(|corner| {
            let c = g + IVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            let on_grid = c.cmpge(IVec3::ZERO).all()
                && c.cmplt(IVec3::new(nx as i32, ny as i32, nz as i32)).all();
            // Off the grid counts as free (the grid's border is free).
            !on_grid || {
                let (i, j, k) = (c.x as u32, c.y as u32, c.z as u32);
                marks[grid.index(i, j, k)] != BLOCKED
                    && grid.point(i, j, k).distance_squared(x) <= join
            }
        })
    };
    let mut seen: HashSet<[i32; 3]> = HashSet::from([[0, 0, 0]]);
    let mut stack = vec![[0, 0, 0]];
    let mut free = Vec::new();
    while let Some(p) = stack.pop() {
        let x = lattice(top, step, p);
        if next_to_free_grid_point(x) {
            return None;
        }
        free.push(p);
        if free.len() >= FLOOD_LIMIT {
            break;
        }
        for d in neighbours() {
            let q = [p[0] + d[0] as i32, p[1] + d[1] as i32, p[2] + d[2] as i32];
            if seen.insert(q) && clearance.at(lattice(top, step, q)) >= 0.0 {
                stack.push(q);
            }
        }
    }
    Some(free)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::grid_flood::{flood_outside, label_cavities};
    use crate::measure::probe_cavities::{ProbeOptions, free_centres, probe_grid};
    use crate::synthetic::sphere_points as sphere;

    #[test]
    fn a_void_smaller_than_the_grid_step_is_found_between_grid_points() {
        // Atoms of 1.5 Å on a sphere of 2.95 Å: probe centres of 1.4 Å fit only within about
        // 0.05 Å of the centre. One more atom sets the grid's corner (4.8 Å beyond it, spacing
        // 0.25 Å) so that the centre lies in the middle of a grid cell, 0.22 Å from its points.
        let centre = Vec3::new(0.11, 0.07, 0.13);
        let mut positions = sphere(400, 2.95, centre);
        positions.push(centre - Vec3::splat(8.075));
        let radii = vec![1.5; positions.len()];
        let atoms = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: None,
        };
        let options = ProbeOptions::default();
        let grid = probe_grid(&atoms, &options).unwrap();
        let mut marks = free_centres(&atoms, &grid, options.probe);
        flood_outside(&grid, &mut marks);
        assert_eq!(
            label_cavities(&grid, &mut marks),
            0,
            "the grid alone misses it"
        );
        let voids = voids_between_grid_points(&atoms, &grid, &marks, options.probe);
        assert_eq!(voids.len(), 1, "{voids:?}");
        for x in &voids[0] {
            assert!(x.distance(centre) < 0.1, "{x} is not near {centre}");
        }
        // A sphere too small for a probe holds no void.
        let mut tight = sphere(400, 2.85, centre);
        tight.push(centre - Vec3::splat(8.075));
        let atoms = AtomSet {
            positions: &tight,
            ..atoms
        };
        let grid = probe_grid(&atoms, &options).unwrap();
        let mut marks = free_centres(&atoms, &grid, options.probe);
        flood_outside(&grid, &mut marks);
        label_cavities(&grid, &mut marks);
        assert!(voids_between_grid_points(&atoms, &grid, &marks, options.probe).is_empty());
    }
}
