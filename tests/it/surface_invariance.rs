//! What must not change the CPU surface: the order of the atoms, the number of threads (slab
//! merge), and a translation (which moves only positions). Also the colour volume: a uniformly
//! coloured system gives that colour everywhere on its surface.

use crate::surface_common::{Rng, cluster, surface};
use glam::Vec3;
use mdsurf::surface::{AtomSet, GridSpec, McTables, SurfaceParams, density, marching_cubes};

#[test]
fn permuting_atoms_changes_nothing() {
    let (pos, radii) = cluster(150, 16.0, Vec3::new(1.0, 2.0, 3.0), 3);
    let mut rng = Rng(99);
    let colours: Vec<[f32; 3]> = (0..pos.len())
        .map(|_| [rng.next(), rng.next(), rng.next()])
        .collect();
    let params = SurfaceParams {
        spacing: 0.6,
        ..SurfaceParams::default()
    };
    let a = surface(&pos, &radii, Some(&colours), &params);
    // A fixed pseudo-random permutation.
    let mut order: Vec<usize> = (0..pos.len()).collect();
    for i in (1..order.len()).rev() {
        let j = (rng.next() * (i + 1) as f32) as usize % (i + 1);
        order.swap(i, j);
    }
    let p2: Vec<Vec3> = order.iter().map(|&i| pos[i]).collect();
    let r2: Vec<f32> = order.iter().map(|&i| radii[i]).collect();
    let c2: Vec<[f32; 3]> = order.iter().map(|&i| colours[i]).collect();
    let b = surface(&p2, &r2, Some(&c2), &params);
    assert!(a.mesh.triangle_count() > 1000);
    assert_eq!(a.grid, b.grid);
    assert_eq!(a.mesh, b.mesh, "meshes differ after permuting the atoms");
    assert_eq!(a.area, b.area);
    assert_eq!(a.volume, b.volume);
}

#[test]
fn thread_count_and_slabs_change_nothing() {
    let (pos, radii) = cluster(200, 20.0, Vec3::ZERO, 5);
    let params = SurfaceParams {
        spacing: 0.5,
        ..SurfaceParams::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        pool.install(|| surface(&pos, &radii, None, &params))
    };
    let one = run(1);
    let three = run(3);
    let seven = run(7);
    assert!(one.mesh.is_closed());
    assert_eq!(one.mesh, three.mesh);
    assert_eq!(one.mesh, seven.mesh);
}

#[test]
fn translating_moves_only_positions() {
    let (pos, radii) = cluster(80, 12.0, Vec3::ZERO, 21);
    let params = SurfaceParams {
        spacing: 0.5,
        ..SurfaceParams::default()
    };
    let shift = Vec3::new(10.25, -7.5, 3.75);
    let a = surface(&pos, &radii, None, &params);
    let moved: Vec<Vec3> = pos.iter().map(|p| *p + shift).collect();
    let b = surface(&moved, &radii, None, &params);
    assert_eq!(a.grid.dims, b.grid.dims);
    assert!((a.grid.origin + shift - b.grid.origin).length() < 1e-4);
    assert_eq!(a.mesh.indices, b.mesh.indices);
    for (p, q) in a.mesh.positions.iter().zip(&b.mesh.positions) {
        assert!((*p + shift - *q).length() < 1e-3, "{p} + {shift} != {q}");
    }
    for (n, m) in a.mesh.normals.iter().zip(&b.mesh.normals) {
        assert!((*n - *m).length() < 1e-3);
    }
    assert!((a.area - b.area).abs() < 1e-4 * a.area);
    assert!((a.volume - b.volume).abs() < 1e-4 * a.volume);
}

#[test]
fn uniform_colour_comes_out_unchanged_on_the_surface() {
    let (pos, radii) = cluster(100, 14.0, Vec3::ZERO, 8);
    let colour = [0.2, 0.55, 0.9];
    let colours = vec![colour; pos.len()];
    for iso in [0.3, 0.5, 1.2] {
        let params = SurfaceParams {
            spacing: 0.7,
            isovalue: iso,
            ..SurfaceParams::default()
        };
        let out = surface(&pos, &radii, Some(&colours), &params);
        assert!(out.mesh.vertex_count() > 100);
        for c in &out.mesh.colours {
            for k in 0..3 {
                assert!((c[k] - colour[k]).abs() < 1e-4, "I = {iso}: {c:?}");
            }
        }
    }
}

#[test]
fn two_coloured_atoms_blend_by_weight() {
    // Two atoms, red and blue: vertices near the red atom are red, near the blue one blue.
    let pos = [Vec3::ZERO, Vec3::new(2.5, 0.0, 0.0)];
    let radii = [1.5, 1.5];
    let colours = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let params = SurfaceParams {
        spacing: 0.3,
        ..SurfaceParams::default()
    };
    let out = surface(&pos, &radii, Some(&colours), &params);
    let weight = |p: Vec3, q: Vec3| {
        let d2 = (p - q).length_squared();
        if d2 < (2.5f32 * 1.5).powi(2) {
            (-d2 / (2.0 * 1.5 * 1.5)).exp()
        } else {
            0.0
        }
    };
    assert!(out.mesh.vertex_count() > 100);
    for (p, c) in out.mesh.positions.iter().zip(&out.mesh.colours) {
        assert!((c[0] + c[2] - 1.0).abs() < 1e-3, "weights sum to I: {c:?}");
        assert_eq!(c[1], 0.0);
        let (wr, wb) = (weight(*p, pos[0]), weight(*p, pos[1]));
        // Linear interpolation across the cutoff jump (exp(-3.125) = 0.044) blurs this a little.
        let red = wr / (wr + wb);
        assert!(
            (c[0] - red).abs() < 0.08,
            "at {p}: red {} expected {red}",
            c[0]
        );
    }
}

#[test]
fn stages_run_alone_give_the_engine_mesh() {
    let (pos, radii) = cluster(50, 10.0, Vec3::ZERO, 13);
    let params = SurfaceParams::default();
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: None,
    };
    let grid = GridSpec::for_atoms(&pos, &radii, &params).expect("grid");
    let vol = density::compute(&atoms, &params, &grid).expect("density");
    assert!(vol.colours.is_none());
    let mesh = marching_cubes::extract(&grid, &vol, params.isovalue);
    let out = surface(&pos, &radii, None, &params);
    assert_eq!(mesh, out.mesh);
    // The case bytes agree with the inside test on the density.
    let cases = marching_cubes::classify(&grid, &vol.values, params.isovalue);
    assert_eq!(cases.len() as u64, grid.cell_count());
    let [nx, ny, _] = grid.dims.map(|d| d as usize);
    let mut active = 0;
    for (c, &case) in cases.iter().enumerate() {
        let (i, j, k) = (
            c % (nx - 1),
            c / (nx - 1) % (ny - 1),
            c / ((nx - 1) * (ny - 1)),
        );
        let inside = vol.values[grid.index(i as u32, j as u32, k as u32)] >= params.isovalue;
        assert_eq!(case & 1 == 1, inside);
        active += usize::from(case != 0 && case != 255);
    }
    assert!(active > 0);
    // Triangle and vertex counts agree with a naive count over all cells and edges.
    let tables = McTables::get();
    let tris: usize = cases.iter().map(|&c| tables.case_triangles(c).len()).sum();
    assert_eq!(mesh.triangle_count(), tris);
    let inside = |i: u32, j: u32, k: u32| vol.values[grid.index(i, j, k)] >= params.isovalue;
    let [nx, ny, nz] = grid.dims;
    let mut crossed = 0;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let f = inside(i, j, k);
                crossed += usize::from(i + 1 < nx && inside(i + 1, j, k) != f);
                crossed += usize::from(j + 1 < ny && inside(i, j + 1, k) != f);
                crossed += usize::from(k + 1 < nz && inside(i, j, k + 1) != f);
            }
        }
    }
    assert_eq!(mesh.vertex_count(), crossed);
}

#[test]
fn an_engine_reused_across_frames_gives_fresh_results() {
    use mdsurf::surface::{CpuEngine, SurfaceEngine};
    let (big, big_r) = cluster(120, 18.0, Vec3::ZERO, 31);
    let (small, small_r) = cluster(30, 8.0, Vec3::new(3.0, 0.0, 0.0), 32);
    let colours = vec![[0.3, 0.6, 0.9]; big.len()];
    let params = SurfaceParams::default();
    type Frame<'a> = (&'a [Vec3], &'a [f32], Option<&'a [[f32; 3]]>);
    let frames: [Frame<'_>; 4] = [
        (&big, &big_r, None),
        (&small, &small_r, None),
        (&big, &big_r, Some(&colours)),
        (&big, &big_r, None),
    ];
    let mut engine = CpuEngine::new();
    for (positions, radii, colours) in frames {
        let atoms = AtomSet {
            positions,
            radii,
            colours,
        };
        let kept = engine.compute(&atoms, &params).expect("surface");
        let fresh = surface(positions, radii, colours, &params);
        assert_eq!(kept.mesh, fresh.mesh);
        assert_eq!(kept.area, fresh.area);
        assert_eq!(kept.volume, fresh.volume);
    }
}
