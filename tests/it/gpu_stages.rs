//! GPU stages one by one against the CPU reference on 1hpv: the density volume (1e-4 relative or
//! 1e-6 absolute), the binning scan (exact), and Marching Cubes classification (exact except
//! cells with a corner within 1e-5 of I). Tolerances from `mdsurf::gpu::tolerance`.

use crate::gpu_support::*;
use mdsurf::gpu::{Changes, tolerance as tol};
use mdsurf::surface::tables::corner_offset;
use mdsurf::surface::{GridSpec, SurfaceParams};

fn params() -> SurfaceParams {
    SurfaceParams {
        spacing: 1.5,
        ..Default::default()
    }
}

#[test]
fn density_matches_reference() {
    let Some(mut engine) = engine() else { return };
    let atoms = load_pdb("1hpv.pdb");
    let p = params();
    engine
        .run_blocking(&atoms.set(), &p, Changes::ALL)
        .expect("GPU frame");
    let plan = engine.plan().expect("plan").clone();
    assert_eq!(
        plan.slabs.len(),
        1,
        "this test needs the whole grid in one slab"
    );
    let gpu = engine.read_density().expect("density readback");
    let (grid, cpu, _) = reference(&atoms, &p);
    assert_eq!(plan.grid, grid);
    assert_eq!(gpu.len(), cpu.len());
    let bad: Vec<usize> = (0..cpu.len())
        .filter(|&v| !tol::density_close(gpu[v], cpu[v]))
        .collect();
    assert!(
        bad.is_empty(),
        "{} of {} density samples off, first at {}: GPU {} CPU {}",
        bad.len(),
        cpu.len(),
        bad[0],
        gpu[bad[0]],
        cpu[bad[0]]
    );
    assert!(
        cpu.iter().any(|&d| d > 1.0),
        "density never exceeds 1: test is too weak"
    );
}

#[test]
fn binning_scan_is_exact() {
    let Some(mut engine) = engine() else { return };
    let atoms = load_pdb("1hpv.pdb");
    let p = SurfaceParams {
        spacing: 1.0,
        ..Default::default()
    };
    engine
        .run_blocking(&atoms.set(), &p, Changes::ALL)
        .expect("GPU frame");
    let plan = engine.plan().expect("plan").clone();
    let cells = plan.cell_count() as usize;
    assert!(cells > 1024, "want a multi-level scan, got {cells} cells");
    let starts = engine.read_cell_starts().expect("cell starts");
    let mut counts = vec![0u32; cells];
    let mut ambiguous = 0;
    for pos in &atoms.positions {
        let f = (*pos - plan.grid.origin) / plan.cell_size;
        if [f.x, f.y, f.z].iter().any(|v| (v - v.round()).abs() < 1e-4) {
            ambiguous += 1;
        }
        let c = [f.x, f.y, f.z]
            .map(|v| v.floor().max(0.0) as u32)
            .iter()
            .zip(plan.cell_dims)
            .map(|(&c, d)| c.min(d - 1))
            .collect::<Vec<_>>();
        counts[(c[0] + plan.cell_dims[0] * (c[1] + plan.cell_dims[1] * c[2])) as usize] += 1;
    }
    let mut expected = Vec::with_capacity(cells);
    let mut sum = 0;
    for c in &counts {
        expected.push(sum);
        sum += c;
    }
    let differing = (0..cells).filter(|&c| starts[c] != expected[c]).count();
    assert!(
        differing <= 2 * ambiguous * 27,
        "{differing} cell starts differ ({ambiguous} atoms sit on a cell boundary)"
    );
    if ambiguous == 0 {
        assert_eq!(starts, expected);
    }
}

#[test]
fn classification_is_exact_away_from_the_isovalue() {
    let Some(mut engine) = engine() else { return };
    let atoms = load_pdb("1hpv.pdb");
    let p = params();
    engine
        .run_blocking(&atoms.set(), &p, Changes::ALL)
        .expect("GPU frame");
    let classes = engine.read_classes().expect("classes");
    let (grid, d, _) = reference(&atoms, &p);
    let GridSpec {
        dims: [nx, ny, nz], ..
    } = grid;
    let iso = p.isovalue;
    let (mut checked, mut active) = (0, 0);
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let corners = (0..8u8).map(|c| {
                    let o = corner_offset(c);
                    d[grid.index(i + o[0], j + o[1], k + o[2])]
                });
                if corners
                    .clone()
                    .any(|v| (v - iso).abs() < tol::CLASSIFY_NEAR_ISO)
                {
                    continue;
                }
                let case = corners
                    .enumerate()
                    .fold(0u32, |m, (c, v)| m | (u32::from(v >= iso) << c));
                let word = classes[grid.index(i, j, k)];
                assert_eq!(word & 255, case, "cell ({i}, {j}, {k})");
                checked += 1;
                active += u32::from(case != 0 && case != 255);
            }
        }
    }
    assert!(
        active > 100,
        "only {active} surface cells: test is too weak"
    );
    assert!(checked as u64 > grid.cell_count() * 9 / 10);
}
