//! The density and colour volumes against the direct formula of DESIGN section 2, evaluated
//! here by brute force over every (sample, atom) pair in f64 with the same f32 cutoff test.

use crate::surface_common::{Rng, cluster};
use glam::Vec3;
use mdsurf::surface::{AtomSet, GridSpec, Quality, SurfaceParams, density};

/// Direct `rho` and `sum w colour / I` at sample `(i, j, k)`.
fn direct(
    grid: &GridSpec,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    ijk: [u32; 3],
) -> (f64, [f64; 3]) {
    let x = grid.point(ijk[0], ijk[1], ijk[2]);
    let (mut rho, mut col) = (0.0f64, [0.0f64; 3]);
    for (n, (p, r)) in atoms.positions.iter().zip(atoms.radii).enumerate() {
        let alpha = r * params.radius_scale;
        let cut = params.cutoff() * alpha;
        let d = x - *p;
        let d2 = (d.x * d.x + d.y * d.y) + d.z * d.z;
        if d2 >= cut * cut {
            continue;
        }
        let a = alpha as f64;
        let w = (-(d2 as f64) / (2.0 * a * a)).exp();
        rho += w;
        if let Some(c) = atoms.colours {
            for k in 0..3 {
                col[k] += w * c[n][k] as f64 / params.isovalue as f64;
            }
        }
    }
    (rho, col)
}

fn check(quality: Quality, spacing: f32, radius_scale: f32, seed: u64) {
    let (pos, radii) = cluster(40, 9.0, Vec3::new(2.0, -1.0, 0.5), seed);
    let mut rng = Rng(seed + 1);
    let colours: Vec<[f32; 3]> = (0..pos.len())
        .map(|_| [rng.next(), rng.next(), rng.next()])
        .collect();
    let params = SurfaceParams {
        spacing,
        radius_scale,
        isovalue: 0.7,
        quality,
    };
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: Some(&colours),
    };
    let grid = GridSpec::for_atoms(&pos, &radii, &params).expect("grid");
    let vol = density::compute(&atoms, &params, &grid).expect("density");
    let cols = vol.colours.as_ref().expect("colour volume");
    // Without colours the density takes another code path; it must give the same numbers.
    let plain = AtomSet {
        colours: None,
        ..atoms
    };
    let alone = density::compute(&plain, &params, &grid).expect("density");
    assert!(alone.colours.is_none());
    assert_eq!(alone.values, vol.values);
    assert_eq!(vol.values.len() as u64, grid.voxel_count());
    let [nx, ny, nz] = grid.dims;
    let (mut nonzero, mut worst) = (0, 0.0f64);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let (rho, col) = direct(&grid, &atoms, &params, [i, j, k]);
                let idx = grid.index(i, j, k);
                let got = vol.values[idx] as f64;
                let err = (got - rho).abs() / rho.max(1e-3);
                worst = worst.max(err);
                assert!(err < 2e-6, "{quality} at {i},{j},{k}: {got} vs {rho}");
                for c in 0..3 {
                    let e = (cols[idx][c] as f64 - col[c]).abs() / col[c].max(1e-3);
                    assert!(
                        e < 4e-6,
                        "colour at {i},{j},{k}: {:?} vs {col:?}",
                        cols[idx]
                    );
                }
                nonzero += usize::from(rho > 0.0);
            }
        }
    }
    assert!(nonzero > 1000, "too few samples covered: {nonzero}");
    eprintln!("{quality} H={spacing} R={radius_scale}: worst relative error {worst:.2e}");
}

#[test]
fn density_matches_the_direct_formula_at_every_quality() {
    // Wide (more than 16 samples per row) and narrow atoms.
    check(Quality::Max, 0.2, 1.0, 5);
    check(Quality::Low, 0.9, 1.0, 1);
    check(Quality::Medium, 0.7, 1.3, 2);
    check(Quality::High, 1.0, 0.8, 3);
    check(Quality::Max, 0.6, 1.0, 4);
}

#[test]
fn grid_boundary_stays_below_the_isovalue() {
    let (pos, radii) = cluster(60, 12.0, Vec3::ZERO, 9);
    let params = SurfaceParams {
        isovalue: 0.05,
        quality: Quality::Max,
        ..SurfaceParams::default()
    };
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: None,
    };
    let grid = GridSpec::for_atoms(&pos, &radii, &params).expect("grid");
    let vol = density::compute(&atoms, &params, &grid).expect("density");
    let [nx, ny, nz] = grid.dims;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let edge = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
                if edge {
                    assert_eq!(vol.values[grid.index(i, j, k)], 0.0);
                }
            }
        }
    }
}
