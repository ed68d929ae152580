//! The one bond guesser: atoms closer than a fraction of the sum of their radii (at most
//! [`MAX_BOND_LENGTH`]) are bonded, found through the cell list of [`super::cells`]; with a
//! periodic box ([`guess_bonds_periodic`]) images across its faces count. Atom drawing and
//! whole molecules use it.

use glam::Vec3;
use rayon::prelude::*;

use super::cells::{CellList, sort_by_cell};
use super::pbc::PbcCell;

/// Longest bond guessed from distances, in Å.
pub const MAX_BOND_LENGTH: f32 = 2.0;
/// Two atoms are bonded when closer than this fraction of the sum of their radii.
pub const BOND_RADIUS_FRACTION: f32 = 0.6;

/// Guesses bonds from distances: atoms `i`, `j` are bonded when
/// `|p_i - p_j| < min(BOND_RADIUS_FRACTION * (r_i + r_j), MAX_BOND_LENGTH)` (radii in Å, 1.5 Å
/// for atoms past the end of `radii`). Uses the cell list, so it runs in linear time; atoms at
/// positions that are not finite have no bonds. Pairs come back sorted, with `i < j`.
pub fn guess_bonds(positions: &[Vec3], radii: &[f32]) -> Vec<[u32; 2]> {
    let items: Vec<(u32, Vec3)> = positions
        .iter()
        .enumerate()
        .map(|(i, &p)| (i as u32, p))
        .collect();
    let cells = CellList::covering(&items, MAX_BOND_LENGTH, 0);
    let mut bonds = Vec::new();
    cells.for_each_close_pair(|i, p, j, q| {
        let (i, j) = (i.min(j), i.max(j));
        let ri = radii.get(i as usize).copied().unwrap_or(1.5);
        let rj = radii.get(j as usize).copied().unwrap_or(1.5);
        let limit = (BOND_RADIUS_FRACTION * (ri + rj)).min(MAX_BOND_LENGTH);
        if p.distance_squared(q) < limit * limit {
            bonds.push([i, j]);
        }
    });
    bonds.sort_unstable();
    bonds
}

/// Bonds guessed from distances as [`guess_bonds`] does (closer than
/// `min(0.6 (r_i + r_j), 2 Å)`), counting periodic images when `cell` is given. Pairs come
/// back sorted, with `i < j`.
pub fn guess_bonds_periodic(
    positions: &[Vec3],
    radii: &[f32],
    cell: Option<PbcCell>,
) -> Vec<[u32; 2]> {
    let Some(cell) = cell else {
        return guess_bonds(positions, radii);
    };
    // A grid of cells in fractional space, each at least one bond length wide.
    let widths = cell.widths();
    let dims = [widths.x, widths.y, widths.z]
        .map(|w| ((w / MAX_BOND_LENGTH).floor() as usize).clamp(1, 256));
    let cells = dims[0] * dims[1] * dims[2];
    let wrapped: Vec<Vec3> = positions
        .par_iter()
        .map(|&p| {
            let f = cell.fractional(p);
            f - f.floor()
        })
        .collect();
    let cell_of = |f: Vec3| -> [usize; 3] {
        let c = |x: f32, d: usize| ((x * d as f32) as usize).min(d - 1);
        [c(f.x, dims[0]), c(f.y, dims[1]), c(f.z, dims[2])]
    };
    let flat = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
    // Atoms sorted by cell: the atoms of cell `k` are `sorted[start[k]..start[k + 1]]`.
    let keys: Vec<usize> = wrapped
        .par_iter()
        .map(|&f| {
            if f.is_finite() {
                flat(cell_of(f))
            } else {
                usize::MAX
            }
        })
        .collect();
    let (start, sorted) = sort_by_cell(&keys, cells);
    let cart: Vec<Vec3> = wrapped.par_iter().map(|&f| cell.cartesian(f)).collect();
    // The distinct neighbouring cell coordinates (periodic) of each coordinate along each axis:
    // three, or fewer on an axis only one or two cells wide.
    let neighbours: [Vec<Vec<usize>>; 3] = dims.map(|d| {
        (0..d)
            .map(|x| {
                let mut around: Vec<usize> = [d - 1, 0, 1].iter().map(|s| (x + s) % d).collect();
                around.sort_unstable();
                around.dedup();
                around
            })
            .collect()
    });
    // The squared minimum-image distance (Å²) of displacement `d`: a displacement whose
    // fractional coordinates are all below one half rounds to the zero lattice vector, so its
    // minimum image is `d` itself (the same bits `min_image` gives, without its rounding).
    let min_image_squared = |d: Vec3| -> f32 {
        let f = cell.fractional(d);
        if f.x.abs() < 0.5 && f.y.abs() < 0.5 && f.z.abs() < 0.5 {
            d.length_squared()
        } else {
            cell.min_image(d).length_squared()
        }
    };
    // Atoms in neighbouring cells that do not wrap around the box are less than 2 / dims ≤ 0.4
    // apart in fractional coordinates (with five or more cells along each axis): far from the
    // half that `min_image` rounds away, unless the cell is so skewed that rounding errors
    // grow (its condition number bounds them), so their minimum image is their displacement
    // itself and the test above is skipped.
    let norm = |columns: [Vec3; 3]| -> f32 {
        (0..3)
            .map(|r| columns.iter().map(|c| c[r].abs()).sum::<f32>())
            .fold(0.0, f32::max)
    };
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let condition = norm(axes.map(|a| cell.cartesian(a))) * norm(axes.map(|a| cell.fractional(a)));
    let direct_cells = dims.iter().all(|&d| d >= 5) && condition < 1000.0;
    // The bond test of atoms `i < j`; `direct` when their cells are neighbours without wrapping
    // around the box (see above).
    let bonded = |i: usize, j: usize, direct: bool| -> bool {
        let ri = radii.get(i).copied().unwrap_or(1.5);
        let rj = radii.get(j).copied().unwrap_or(1.5);
        let limit = (BOND_RADIUS_FRACTION * (ri + rj)).min(MAX_BOND_LENGTH);
        let d = cart[j] - cart[i];
        let squared = if direct {
            d.length_squared()
        } else {
            min_image_squared(d)
        };
        squared < limit * limit
    };
    const BLOCK: usize = 4096;
    if dims.iter().all(|&d| d >= 3) {
        // With three or more cells along each axis a cell's 26 neighbours are distinct cells,
        // and of two neighbouring cells exactly one is the other's neighbour at one of these
        // 13 offsets (the other 13 are their opposites): each pair of atoms in the same or
        // neighbouring cells is tested once, from the atom that comes first in cell order.
        let mut forward = Vec::with_capacity(13);
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    if (dz, dy, dx) > (0, 0, 0) {
                        forward.push([dx, dy, dz]);
                    }
                }
            }
        }
        let bonds_of_block = |first: usize| -> Vec<[u32; 2]> {
            let mut bonds = Vec::new();
            let mut test = |i: u32, j: u32, direct: bool| {
                let (a, b) = (i.min(j), i.max(j));
                if bonded(a as usize, b as usize, direct) {
                    bonds.push([a, b]);
                }
            };
            for p in first..(first + BLOCK).min(sorted.len()) {
                let i = sorted[p];
                let k = keys[i as usize];
                let c = cell_of(wrapped[i as usize]);
                for &j in &sorted[p + 1..start[k + 1] as usize] {
                    test(i, j, direct_cells);
                }
                for o in &forward {
                    let mut wraps = false;
                    let mut b = [0usize; 3];
                    for axis in 0..3 {
                        let (x, d) = (c[axis] as i64 + o[axis], dims[axis] as i64);
                        wraps |= !(0..d).contains(&x);
                        b[axis] = if x < 0 {
                            x + d
                        } else if x >= d {
                            x - d
                        } else {
                            x
                        } as usize;
                    }
                    let other = flat(b);
                    for &j in &sorted[start[other] as usize..start[other + 1] as usize] {
                        test(i, j, direct_cells && !wraps);
                    }
                }
            }
            bonds
        };
        let blocks: Vec<Vec<[u32; 2]>> = (0..sorted.len())
            .into_par_iter()
            .step_by(BLOCK)
            .map(bonds_of_block)
            .collect();
        let mut bonds = blocks.concat();
        bonds.par_sort_unstable();
        bonds.dedup();
        return bonds;
    }
    // A box under three cells wide along some axis: each atom looks for partners of higher
    // index in its (up to) 27 neighbouring cells; atoms are split into blocks searched in parallel, their bonds joined in block order (each atom's
    // bonds sorted, so the whole list comes out sorted).
    let bonds_of_block = |first: usize| -> Vec<[u32; 2]> {
        let mut bonds = Vec::new();
        for i in first..(first + BLOCK).min(keys.len()) {
            if keys[i] == usize::MAX {
                continue;
            }
            let c = cell_of(wrapped[i]);
            let own = bonds.len();
            for &z in &neighbours[2][c[2]] {
                for &y in &neighbours[1][c[1]] {
                    for &x in &neighbours[0][c[0]] {
                        let other = flat([x, y, z]);
                        let direct = direct_cells
                            && x.abs_diff(c[0]) <= 1
                            && y.abs_diff(c[1]) <= 1
                            && z.abs_diff(c[2]) <= 1;
                        for &j in &sorted[start[other] as usize..start[other + 1] as usize] {
                            let j = j as usize;
                            if j > i && bonded(i, j, direct) {
                                bonds.push([i as u32, j as u32]);
                            }
                        }
                    }
                }
            }
            bonds[own..].sort_unstable();
        }
        bonds
    };
    let blocks: Vec<Vec<[u32; 2]>> = (0..keys.len())
        .into_par_iter()
        .step_by(BLOCK)
        .map(bonds_of_block)
        .collect();
    blocks.concat()
}
