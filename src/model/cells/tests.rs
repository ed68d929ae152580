//! The cell list against brute force on random points, open and periodic.

use std::collections::BTreeSet;

use glam::{IVec3, Vec3};

use super::{CellList, sort_by_cell};
use crate::model::bonds::{
    BOND_RADIUS_FRACTION, MAX_BOND_LENGTH, guess_bonds, guess_bonds_periodic,
};
use crate::model::pbc::PbcCell;

/// `n` points spread over a cube of `side` Å from `low` Å (a fixed linear congruential stream).
fn random_points(n: usize, low: f32, side: f32, seed: u64) -> Vec<Vec3> {
    let mut x = seed;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        low + side * (x >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n).map(|_| Vec3::new(next(), next(), next())).collect()
}

fn items(points: &[Vec3]) -> Vec<(u32, Vec3)> {
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| (i as u32, p))
        .collect()
}

#[test]
fn close_pairs_are_every_pair_closer_than_the_edge_once() {
    for (n, side, edge) in [
        (400, 20.0, 2.0),
        (300, 8.0, 3.5),
        (50, 100.0, 1.0),
        (1, 5.0, 2.0),
    ] {
        let points = random_points(n, -side / 2.0, side, n as u64);
        let cells = CellList::covering(&items(&points), edge, 0);
        let mut seen = Vec::new();
        cells.for_each_close_pair(|i, p, j, q| {
            assert_eq!((p, q), (points[i as usize], points[j as usize]));
            seen.push([i.min(j), i.max(j)]);
        });
        let found: BTreeSet<[u32; 2]> = seen.iter().copied().collect();
        assert_eq!(found.len(), seen.len(), "a pair came twice");
        for i in 0..n {
            for j in i + 1..n {
                if points[i].distance(points[j]) < edge {
                    assert!(found.contains(&[i as u32, j as u32]), "missed {i} {j}");
                }
            }
        }
    }
}

#[test]
fn cells_hold_the_points_inside_them() {
    let mut points = random_points(500, 3.0, 30.0, 11);
    points.push(Vec3::NAN);
    let cells = CellList::covering(&items(&points), 2.5, 1);
    let mut total = 0;
    for z in 0..cells.dims.z {
        for y in 0..cells.dims.y {
            for x in 0..cells.dims.x {
                let c = IVec3::new(x, y, z);
                let (lo, hi) = cells.cell_box(c);
                let (held, ids) = cells.cell(c);
                for (&p, &i) in held.iter().zip(ids) {
                    assert_eq!(p, points[i as usize]);
                    assert!(p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all());
                }
                total += held.len();
            }
        }
    }
    assert_eq!(total, 500, "every finite point once, the NaN left out");
    assert_eq!(cells.cell(IVec3::splat(-1)).0.len(), 0);
}

#[test]
fn counting_sort_keeps_each_cell_ascending_and_skips_left_out_items() {
    let keys = [2, usize::MAX, 0, 2, 1, 0, usize::MAX, 2];
    let (start, order) = sort_by_cell(&keys, 3);
    assert_eq!(start, vec![0, 2, 3, 6]);
    assert_eq!(order, vec![2, 5, 4, 0, 3, 7]);
}

/// Bonds by testing every pair, minimum image in `cell` when given.
fn brute_bonds(points: &[Vec3], radii: &[f32], cell: Option<&PbcCell>) -> Vec<[u32; 2]> {
    let mut bonds = Vec::new();
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            let limit = (BOND_RADIUS_FRACTION * (radii[i] + radii[j])).min(MAX_BOND_LENGTH);
            let d = match cell {
                Some(c) => {
                    let wrap = |p: Vec3| {
                        let f = c.fractional(p);
                        c.cartesian(f - f.floor())
                    };
                    c.min_image(wrap(points[j]) - wrap(points[i]))
                }
                None => points[j] - points[i],
            };
            if d.length_squared() < limit * limit {
                bonds.push([i as u32, j as u32]);
            }
        }
    }
    bonds
}

#[test]
fn guessed_bonds_match_brute_force_open_and_periodic() {
    let points = random_points(900, 0.0, 24.0, 5);
    let radii: Vec<f32> = (0..points.len()).map(|i| [1.0, 1.5, 1.9][i % 3]).collect();
    let open = guess_bonds(&points, &radii);
    assert!(!open.is_empty());
    assert_eq!(open, brute_bonds(&points, &radii, None));
    for rows in [
        [Vec3::X * 24.0, Vec3::Y * 24.0, Vec3::Z * 24.0],
        [
            Vec3::X * 24.0,
            Vec3::new(6.0, 23.0, 0.0),
            Vec3::new(-5.0, 4.0, 22.0),
        ],
        [Vec3::X * 5.0, Vec3::Y * 24.0, Vec3::Z * 24.0],
    ] {
        let cell = PbcCell::new(&rows).expect("cell");
        let periodic = guess_bonds_periodic(&points, &radii, Some(cell));
        assert!(periodic.len() >= open.len().min(1));
        assert_eq!(
            periodic,
            brute_bonds(&points, &radii, Some(&cell)),
            "{rows:?}"
        );
    }
}
