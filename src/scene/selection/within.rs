//! `within D of SEL`: which atoms lie within D Å of any source atom, with a cell grid.
//!
//! With a periodic box (orthorhombic or triclinic), every position is first wrapped into the
//! box (through fractional coordinates), and the atoms of the set that gets binned are copied
//! with each periodic image that lies within D of the box (a slab test per box axis, in
//! fractional coordinates; any box shape, and boxes narrower than D get several images). A
//! wrapped atom then finds every partner within D among those copies, so the search itself is a
//! plain Cartesian one: no minimum-image convention is needed.
//!
//! The larger of the two sets (sources, targets) is binned into Cartesian cells D/2 wide; each
//! atom of the smaller set visits the 5 × 5 × 5 cells around its own, skipping those whose
//! nearest point is farther than D, in parallel. Few sources (`within 5 of protein` in water)
//! mark the targets around them; few targets look for any source around them, and a target far
//! from every source is rejected by one look-up in a dilated occupancy map.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{IVec3, Mat3, Vec3};
use rayon::prelude::*;

/// Atoms per parallel task.
const CHUNK: usize = 1024;

/// Cells per cutoff distance along each axis (so the reach is at most this many cells).
const SPLIT: i32 = 2;

/// Atoms `i` with `targets[i]` that lie within `distance` Å (inclusive) of some atom in
/// `sources` in `positions`, counting periodic images when `cell` (box edge vectors a, b, c in
/// Å) is given. Indices past the end of `positions` are never selected.
pub(crate) fn within(
    positions: &[Vec3],
    cell: Option<&[Vec3; 3]>,
    sources: &[u32],
    targets: &[bool],
    distance: f32,
) -> Vec<bool> {
    let space = cell.and_then(Periodic::new);
    let finite = |i: usize| {
        let p = positions.get(i).filter(|p| p.is_finite())?;
        Some((i as u32, space.as_ref().map_or(*p, |s| s.wrap(*p))))
    };
    let sources: Vec<(u32, Vec3)> = sources.iter().filter_map(|&s| finite(s as usize)).collect();
    let wanted: Vec<(u32, Vec3)> = (0..targets.len().min(positions.len()))
        .filter(|&i| targets[i])
        .filter_map(finite)
        .collect();
    let mut out = vec![false; targets.len()];
    if sources.is_empty() || wanted.is_empty() || !distance.is_finite() || distance < 0.0 {
        return out;
    }
    let d2 = distance * distance;
    let max_cells = (4 * (sources.len() + wanted.len())).max(64) as f64;
    let images = |points: &[(u32, Vec3)]| match &space {
        Some(s) => s.with_images(points, distance),
        None => points.to_vec(),
    };
    let t0 = std::time::Instant::now();
    if sources.len() < wanted.len() {
        let im = images(&wanted);
        let t1 = t0.elapsed();
        let grid = Grid::new(&im, distance, max_cells, false);
        let t2 = t0.elapsed();
        let mut visits = 0usize; let mut checks = 0usize;
        for (_, p) in &sources { grid.visit(*p, d2, |pts, _| { visits += 1; checks += pts.len(); false }); }
        let t3 = t0.elapsed();
        eprintln!("images {} {:?} grid {:?} dims {:?} side {} count-visit {:?} visits {visits} checks {checks}", im.len(), t1, t2 - t1, grid.dims, grid.side, t3 - t2);
        let marks: Vec<AtomicBool> = (0..targets.len()).map(|_| AtomicBool::new(false)).collect();
        sources.par_chunks(CHUNK).for_each(|chunk| {
            for (_, p) in chunk {
                grid.visit(*p, d2, |points, ids| {
                    for (s, &i) in points.iter().zip(ids) {
                        if s.distance_squared(*p) <= d2 {
                            marks[i as usize].store(true, Ordering::Relaxed);
                        }
                    }
                    false
                });
            }
        });
        out.iter_mut()
            .zip(marks)
            .for_each(|(o, m)| *o = m.into_inner());
    } else {
        let grid = Grid::new(&images(&sources), distance, max_cells, true);
        let hits: Vec<Vec<u32>> = wanted
            .par_chunks(CHUNK)
            .map(|chunk| {
                let near = |p: Vec3| {
                    grid.is_near(p)
                        && grid.visit(p, d2, |points, _| {
                            points.iter().any(|s| s.distance_squared(p) <= d2)
                        })
                };
                chunk.iter().filter(|(_, p)| near(*p)).map(|(i, _)| *i).collect()
            })
            .collect();
        for i in hits.into_iter().flatten() {
            out[i as usize] = true;
        }
    }
    out
}

/// A periodic box: edge vectors, the map to fractional coordinates, and face-to-face widths.
struct Periodic {
    /// Box edge vectors a, b, c in Å.
    edges: [Vec3; 3],
    /// Cartesian to fractional coordinates.
    to_fraction: Mat3,
    /// Width of the box between the faces opposite each edge, in Å.
    widths: Vec3,
}

impl Periodic {
    /// The box with edges `e`, or `None` when it is degenerate.
    fn new(e: &[Vec3; 3]) -> Option<Periodic> {
        let volume = e[0].dot(e[1].cross(e[2])).abs();
        if !volume.is_finite() || volume < 1e-6 {
            return None;
        }
        let widths = Vec3::new(
            volume / e[1].cross(e[2]).length(),
            volume / e[2].cross(e[0]).length(),
            volume / e[0].cross(e[1]).length(),
        );
        Some(Periodic {
            edges: *e,
            to_fraction: Mat3::from_cols(e[0], e[1], e[2]).inverse(),
            widths,
        })
    }

    /// The box translation `t.x a + t.y b + t.z c`.
    #[inline]
    fn shift(&self, t: Vec3) -> Vec3 {
        t.x * self.edges[0] + t.y * self.edges[1] + t.z * self.edges[2]
    }

    /// `p` moved into the box (fractional coordinates in [0, 1)).
    #[inline]
    fn wrap(&self, p: Vec3) -> Vec3 {
        p - self.shift((self.to_fraction * p).floor())
    }

    /// Wrapped `points` with every periodic image that lies within `distance` Å of the box.
    fn with_images(&self, points: &[(u32, Vec3)], distance: f32) -> Vec<(u32, Vec3)> {
        let margin = Vec3::splat(distance) / self.widths;
        let reach = margin.ceil().as_ivec3();
        let mut out = Vec::with_capacity(points.len() * 3 / 2);
        for &(i, p) in points {
            let f = self.to_fraction * p;
            // Image offsets along axis k whose slab stays within the margin of the box.
            let range = |k: usize| {
                let (m, r) = (margin[k], reach[k]);
                (-r..=r).filter(move |&t| {
                    let g = f[k] + t as f32;
                    t == 0 || (g >= -m && g <= 1.0 + m)
                })
            };
            for tz in range(2) {
                for ty in range(1) {
                    for tx in range(0) {
                        let t = IVec3::new(tx, ty, tz).as_vec3();
                        out.push((i, p + self.shift(t)));
                    }
                }
            }
        }
        out
    }
}

/// Binned points: a Cartesian grid over their bounding box, padded by the reach.
struct Grid {
    /// Corner of cell (0, 0, 0) in Å.
    origin: Vec3,
    /// Cell edge in Å.
    side: f32,
    /// Cells along each axis.
    dims: IVec3,
    /// Cells searched on each side of a cell (at most [`SPLIT`]).
    reach: i32,
    /// Points of cell `c` are `points[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    /// Positions, sorted by cell.
    points: Vec<Vec3>,
    /// Atom index of each point.
    ids: Vec<u32>,
    /// True for cells within `reach` of a non-empty cell (empty when not asked for).
    near: Vec<bool>,
}

impl Grid {
    /// Bins `points` in cells about `distance / 2` wide (wider when there would be more than
    /// `max_cells`); with `near`, also marks the cells near a point.
    fn new(points: &[(u32, Vec3)], distance: f32, max_cells: f64, near: bool) -> Grid {
        let lo = points.iter().fold(Vec3::INFINITY, |a, &(_, p)| a.min(p));
        let hi = points.iter().fold(Vec3::NEG_INFINITY, |a, &(_, p)| a.max(p));
        let extent = (hi - lo).max(Vec3::splat(1e-3));
        let mut side = (distance / SPLIT as f32).max(1e-3);
        let cells = |side: f32| (extent / side).floor() + 1.0;
        let count = cells(side);
        let total = count.x as f64 * count.y as f64 * count.z as f64;
        if total > max_cells {
            side *= (total / max_cells).cbrt() as f32 * 1.01;
        }
        let reach = ((distance / side).ceil() as i32).clamp(1, SPLIT);
        let dims = cells(side).as_ivec3() + 2 * reach;
        let mut grid = Grid {
            origin: lo - reach as f32 * side,
            side,
            dims,
            reach,
            start: Vec::new(),
            points: Vec::new(),
            ids: Vec::new(),
            near: Vec::new(),
        };
        grid.fill(points, near);
        grid
    }

    /// Flat index of in-range cell `c`.
    #[inline]
    fn flat(&self, c: IVec3) -> usize {
        ((c.z * self.dims.y + c.y) * self.dims.x + c.x) as usize
    }

    /// The cell holding `p`, with `p`'s place inside it (0 to 1 per axis), when on the grid.
    #[inline]
    fn locate(&self, p: Vec3) -> Option<(IVec3, Vec3)> {
        let g = (p - self.origin) / self.side;
        let c = g.floor();
        let inside = c.cmpge(Vec3::ZERO).all() && c.cmplt(self.dims.as_vec3()).all();
        inside.then(|| (c.as_ivec3(), g - c))
    }

    /// Sorts the points into cells (counting sort); marks the cells near them when asked.
    fn fill(&mut self, points: &[(u32, Vec3)], near: bool) {
        let cells = (self.dims.x * self.dims.y * self.dims.z) as usize;
        let cell_of: Vec<usize> = points
            .iter()
            .map(|&(_, p)| self.locate(p).map_or(0, |(c, _)| self.flat(c)))
            .collect();
        let mut start = vec![0u32; cells + 1];
        for &c in &cell_of {
            start[c + 1] += 1;
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut sorted = vec![Vec3::ZERO; points.len()];
        let mut ids = vec![0u32; points.len()];
        for (&c, &(i, p)) in cell_of.iter().zip(points) {
            sorted[fill[c] as usize] = p;
            ids[fill[c] as usize] = i;
            fill[c] += 1;
        }
        if near {
            let r = self.reach;
            let mut marks = vec![false; cells];
            for z in r..self.dims.z - r {
                for y in r..self.dims.y - r {
                    for x in r..self.dims.x - r {
                        let f = self.flat(IVec3::new(x, y, z));
                        if start[f] == start[f + 1] {
                            continue;
                        }
                        for dz in -r..=r {
                            for dy in -r..=r {
                                for dx in -r..=r {
                                    marks[self.flat(IVec3::new(x + dx, y + dy, z + dz))] = true;
                                }
                            }
                        }
                    }
                }
            }
            self.near = marks;
        }
        self.start = start;
        self.points = sorted;
        self.ids = ids;
    }

    /// True when `p` lies in a cell near some point.
    #[inline]
    fn is_near(&self, p: Vec3) -> bool {
        self.locate(p).is_some_and(|(c, _)| self.near[self.flat(c)])
    }

    /// Calls `f(points, ids)` for each cell around `p` whose nearest point is within √`d2` Å
    /// of `p`, until `f` returns true; returns whether it did.
    #[inline]
    fn visit(&self, p: Vec3, d2: f32, mut f: impl FnMut(&[Vec3], &[u32]) -> bool) -> bool {
        // Points off the padded grid are farther than the cutoff from every binned point.
        let Some((c, u)) = self.locate(p) else {
            return false;
        };
        let r = self.reach;
        // Squared gap in Å² from `p` to the cells at each offset, per axis.
        let mut gaps = [[0.0f32; 2 * SPLIT as usize + 1]; 3];
        for (k, row) in gaps.iter_mut().enumerate() {
            for o in -r..=r {
                let gap = match o {
                    0 => 0.0,
                    o if o > 0 => (o as f32 - u[k]) * self.side,
                    o => (-o as f32 - 1.0 + u[k]) * self.side,
                };
                row[(o + r) as usize] = gap * gap;
            }
        }
        for z in (c.z - r).max(0)..=(c.z + r).min(self.dims.z - 1) {
            let gz = gaps[2][(z - c.z + r) as usize];
            if gz > d2 {
                continue;
            }
            for y in (c.y - r).max(0)..=(c.y + r).min(self.dims.y - 1) {
                let gy = gz + gaps[1][(y - c.y + r) as usize];
                if gy > d2 {
                    continue;
                }
                let row = ((z * self.dims.y + y) * self.dims.x) as usize;
                for x in (c.x - r).max(0)..=(c.x + r).min(self.dims.x - 1) {
                    if gy + gaps[0][(x - c.x + r) as usize] > d2 {
                        continue;
                    }
                    let cell = row + x as usize;
                    let (a, b) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                    if a < b && f(&self.points[a..b], &self.ids[a..b]) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over the 729 nearest images (enough for the points and boxes below).
    fn brute(positions: &[Vec3], cell: Option<&[Vec3; 3]>, sources: &[u32], d: f32) -> Vec<bool> {
        let shifts: Vec<Vec3> = match cell {
            Some(e) => {
                let mut v = Vec::new();
                for i in -4..=4 {
                    for j in -4..=4 {
                        for k in -4..=4 {
                            v.push(i as f32 * e[0] + j as f32 * e[1] + k as f32 * e[2]);
                        }
                    }
                }
                v
            }
            None => vec![Vec3::ZERO],
        };
        positions
            .iter()
            .map(|p| {
                sources.iter().any(|&s| {
                    shifts
                        .iter()
                        .any(|t| (positions[s as usize] + *t).distance_squared(*p) <= d * d)
                })
            })
            .collect()
    }

    fn points(n: usize, scale: f32) -> Vec<Vec3> {
        // A deterministic scatter (golden-ratio sequences), partly outside the box.
        (0..n)
            .map(|i| {
                let f = |a: f32| ((i as f32 * a).fract() * 1.4 - 0.2) * scale;
                Vec3::new(f(0.618_034), f(0.754_878), f(0.569_840))
            })
            .collect()
    }

    #[test]
    fn grid_matches_brute_force() {
        let boxes = [
            None,
            Some([Vec3::X * 20.0, Vec3::Y * 20.0, Vec3::Z * 20.0]),
            Some([
                Vec3::new(20.0, 0.0, 0.0),
                Vec3::new(8.0, 18.0, 0.0),
                Vec3::new(-6.0, 7.0, 16.0),
            ]),
            // Narrower than three cutoffs: images of the same cell are searched.
            Some([Vec3::X * 9.0, Vec3::new(3.0, 8.0, 0.0), Vec3::Z * 30.0]),
        ];
        let positions = points(600, 20.0);
        let all = vec![true; positions.len()];
        let few: Vec<bool> = (0..600).map(|i| i % 29 == 0).collect();
        let many: Vec<u32> = (0..600).filter(|i| i % 5 != 0).collect();
        let sparse: Vec<u32> = (0..600).step_by(37).collect();
        for cell in &boxes {
            for d in [0.0, 1.5, 4.0, 7.5] {
                // Few sources (targets binned), then few targets (sources binned).
                for (sources, targets) in [(&sparse, &all), (&many, &few)] {
                    let got = within(&positions, cell.as_ref(), sources, targets, d);
                    let want: Vec<bool> = brute(&positions, cell.as_ref(), sources, d)
                        .into_iter()
                        .zip(targets.iter())
                        .map(|(w, t)| w && *t)
                        .collect();
                    assert_eq!(got, want, "box {cell:?} d {d}");
                }
            }
        }
    }
}
