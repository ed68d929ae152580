//! Connected sets of free points on a grid (26 neighbours), for the probe measurements: the
//! free probe centres reached from the grid's border are the probe's outside, and each other
//! connected set is one cavity. Each grid point holds a mark (one `u32`): [`BLOCKED`],
//! [`UNSEEN`], [`OUTSIDE`] or a cavity's number from 1.

use crate::surface::GridSpec;

/// A point where a probe overlaps an atom.
pub(super) const BLOCKED: u32 = u32::MAX;
/// A free point reached from the grid's border.
pub(super) const OUTSIDE: u32 = u32::MAX - 1;
/// A free point not yet reached.
pub(super) const UNSEEN: u32 = 0;

/// The 26 neighbours' offsets.
pub(super) fn neighbours() -> impl Iterator<Item = [i64; 3]> {
    (-1..=1i64)
        .flat_map(|z| (-1..=1i64).flat_map(move |y| (-1..=1i64).map(move |x| [x, y, z])))
        .filter(|d| *d != [0, 0, 0])
}

/// Gives every [`UNSEEN`] point reached from the points of `seeds` (26-connected; already
/// marked) the mark `label`. Every point on the grid's border must already be marked, so that
/// the points reached are inside the border and all their neighbours lie on the grid.
///
/// A scanline fill: runs of points along x are marked whole, and each run looks for new runs
/// in the eight rows next to it (y and z one step away), over its own extent and one more
/// point each side (the diagonal neighbours).
fn fill(grid: &GridSpec, marks: &mut [u32], seeds: Vec<usize>, label: u32) {
    let [nx, ny, _] = grid.dims.map(|d| d as isize);
    let rows: Vec<isize> = (-1..=1isize)
        .flat_map(|dz| (-1..=1isize).map(move |dy| nx * (dy + ny * dz)))
        .filter(|&step| step != 0)
        .collect();
    // Marks the run of unseen points through `at` (marked, or unseen and then marked) and
    // returns its first and last points.
    let run = |marks: &mut [u32], at: usize| -> (usize, usize) {
        let (mut first, mut last) = (at, at);
        while marks[first - 1] == UNSEEN {
            first -= 1;
        }
        while marks[last + 1] == UNSEEN {
            last += 1;
        }
        marks[first..=last].fill(label);
        (first, last)
    };
    let mut runs: Vec<(usize, usize)> = seeds.into_iter().map(|at| run(marks, at)).collect();
    while let Some((first, last)) = runs.pop() {
        for &step in &rows {
            let end = (last as isize + 1 + step) as usize;
            let mut at = (first as isize - 1 + step) as usize;
            while at <= end {
                if marks[at] == UNSEEN {
                    let found = run(marks, at);
                    runs.push(found);
                    // The point after a run is marked.
                    at = found.1 + 2;
                } else {
                    at += 1;
                }
            }
        }
    }
}

/// Marks the free points connected to the grid's border [`OUTSIDE`] (the border is free: the
/// grid's padding is larger than any atom's reach). The border is marked first and the fill
/// starts from the free points next to it.
pub(super) fn flood_outside(grid: &GridSpec, marks: &mut [u32]) {
    let [nx, ny, nz] = grid.dims;
    let on_border = |i: u32, j: u32, k: u32| {
        i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1
    };
    let next_to_border = |i: u32, j: u32, k: u32| {
        !on_border(i, j, k)
            && (i == 1 || j == 1 || k == 1 || i == nx - 2 || j == ny - 2 || k == nz - 2)
    };
    let mut stack = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            // Whole rows inside the shell hold only two border points and two next to it.
            let inner = k > 1 && j > 1 && k < nz - 2 && j < ny - 2;
            let columns: Vec<u32> = if inner {
                vec![0, 1, nx - 2, nx - 1]
            } else {
                (0..nx).collect()
            };
            for i in columns {
                let at = grid.index(i, j, k);
                if on_border(i, j, k) {
                    if marks[at] == UNSEEN {
                        marks[at] = OUTSIDE;
                    }
                } else if next_to_border(i, j, k) && marks[at] == UNSEEN {
                    marks[at] = OUTSIDE;
                    stack.push(at);
                }
            }
        }
    }
    fill(grid, marks, stack, OUTSIDE);
}

/// Numbers the remaining free sets 1, 2, ...; returns how many there are.
pub(super) fn label_cavities(grid: &GridSpec, marks: &mut [u32]) -> u32 {
    let mut count = 0;
    for at in 0..marks.len() {
        if marks[at] == UNSEEN {
            count += 1;
            marks[at] = count;
            fill(grid, marks, vec![at], count);
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// The free points connected to the border, the naive way: a search over the 26
    /// neighbours of every point.
    fn outside_by_search(dims: [u32; 3], marks: &[u32]) -> Vec<bool> {
        let [nx, ny, nz] = dims.map(|d| d as i64);
        let index = |i: i64, j: i64, k: i64| (i + nx * (j + ny * k)) as usize;
        let mut outside = vec![false; marks.len()];
        let mut stack = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let border = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1;
                    if (border || k == nz - 1) && marks[index(i, j, k)] == UNSEEN {
                        outside[index(i, j, k)] = true;
                        stack.push([i, j, k]);
                    }
                }
            }
        }
        while let Some([i, j, k]) = stack.pop() {
            for [dx, dy, dz] in neighbours() {
                let (a, b, c) = (i + dx, j + dy, k + dz);
                if a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz {
                    continue;
                }
                let at = index(a, b, c);
                if marks[at] == UNSEEN && !outside[at] {
                    outside[at] = true;
                    stack.push([a, b, c]);
                }
            }
        }
        outside
    }

    /// On grids of random blocked points (a fifth to two thirds of those inside a free
    /// border), the scanline fill
    /// marks exactly the points a plain neighbour search reaches from the border, and the
    /// cavities it numbers are the rest of the free points, each connected set one number.
    #[test]
    fn the_scanline_fill_reaches_what_a_neighbour_search_reaches() {
        let grid = GridSpec {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims: [23, 17, 19],
        };
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut random = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for density in [0.2, 0.45, 0.55, 0.67] {
            // The border stays free, as the probe grid's padding keeps it.
            let [nx, ny, nz] = grid.dims;
            let mut marks: Vec<u32> = (0..grid.voxel_count() as u32)
                .map(|at| {
                    let (i, j, k) = (at % nx, at / nx % ny, at / (nx * ny));
                    let border = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1;
                    if border || k == nz - 1 || random() >= density {
                        UNSEEN
                    } else {
                        BLOCKED
                    }
                })
                .collect();
            let expected = outside_by_search(grid.dims, &marks);
            flood_outside(&grid, &mut marks);
            let outside: Vec<bool> = marks.iter().map(|&m| m == OUTSIDE).collect();
            assert_eq!(outside, expected, "blocked share {density}");
            let free_left = marks.iter().filter(|&&m| m == UNSEEN).count();
            let count = label_cavities(&grid, &mut marks);
            assert!(marks.iter().all(|&m| m != UNSEEN));
            let labelled = marks.iter().filter(|&&m| (1..=count).contains(&m)).count();
            assert_eq!(labelled, free_left);
            // Neighbouring free points of cavities carry the same number.
            for k in 1..nz - 1 {
                for j in 1..ny - 1 {
                    for i in 1..nx - 1 {
                        let here = marks[grid.index(i, j, k)];
                        if !(1..=count).contains(&here) {
                            continue;
                        }
                        for [dx, dy, dz] in neighbours() {
                            let at = grid.index(
                                (i as i64 + dx) as u32,
                                (j as i64 + dy) as u32,
                                (k as i64 + dz) as u32,
                            );
                            assert!(marks[at] == here || marks[at] == BLOCKED);
                        }
                    }
                }
            }
        }
    }
}
