//! GPU engine vs the CPU reference, whole surfaces: one atom (also against the analytic sphere),
//! two overlapping atoms with colours, a real protein (1hpv) at a coarse spacing. Tolerances come
//! from `mdsurf::gpu::tolerance`. Without an adapter (and without REQUIRE_GPU=1) each test
//! prints a note and returns.

use crate::gpu_support::*;
use glam::Vec3;
use mdsurf::surface::{Quality, SurfaceEngine, SurfaceParams};

#[test]
fn one_atom_matches_reference_and_sphere() {
    let Some(mut engine) = engine() else { return };
    let atoms = Atoms {
        positions: vec![Vec3::new(1.0, 2.0, 3.0)],
        radii: vec![1.6],
        colours: Some(vec![[1.0, 0.5, 0.25]]),
    };
    let p = SurfaceParams {
        spacing: 0.4,
        ..Default::default()
    };
    let out = engine.compute(&atoms.set(), &p).expect("GPU surface");
    let (grid, _, cpu) = reference(&atoms, &p);
    assert_eq!(out.grid, grid);
    assert!(assert_mesh_close(
        "one atom", &out.mesh, &cpu, out.area, out.volume
    ));
    assert!(out.mesh.is_closed(), "one-atom GPU mesh is not closed");
    // Sphere of radius alpha * sqrt(2 ln 2); linear interpolation puts vertices slightly inside.
    let r = 1.6 * (2.0f64 * 2f64.ln()).sqrt();
    let sphere_area = 4.0 * std::f64::consts::PI * r * r;
    assert!(
        (out.area / sphere_area - 1.0).abs() < 0.05,
        "area {} vs sphere {sphere_area}",
        out.area
    );
    for (v, c) in out.mesh.colours.iter().enumerate() {
        assert!(
            mdsurf::gpu::tolerance::colour_close(*c, [1.0, 0.5, 0.25]),
            "vertex {v} colour {c:?}"
        );
    }
    for (v, n) in out.mesh.normals.iter().enumerate() {
        let outward = (out.mesh.positions[v] - atoms.positions[0]).normalize();
        assert!(n.dot(outward) > 0.99, "vertex {v} normal {n} not outward");
    }
}

#[test]
fn two_overlapping_atoms_with_colours() {
    let Some(mut engine) = engine() else { return };
    let atoms = Atoms {
        positions: vec![Vec3::ZERO, Vec3::new(2.1, 0.3, -0.2)],
        radii: vec![1.5, 1.2],
        colours: Some(vec![[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    };
    for (spacing, quality) in [(0.5, Quality::Medium), (0.35, Quality::High)] {
        let p = SurfaceParams {
            spacing,
            quality,
            ..Default::default()
        };
        let out = engine.compute(&atoms.set(), &p).expect("GPU surface");
        let (_, _, cpu) = reference(&atoms, &p);
        assert!(
            out.mesh.indices == cpu.indices,
            "H={spacing}: different triangles"
        );
        assert!(assert_mesh_close(
            "two atoms",
            &out.mesh,
            &cpu,
            out.area,
            out.volume
        ));
        assert!(out.mesh.is_closed());
        // Colours blend: the red side is red, the blue side blue.
        let reddest = out
            .mesh
            .positions
            .iter()
            .zip(&out.mesh.colours)
            .min_by(|a, b| a.0.x.total_cmp(&b.0.x));
        assert!(reddest.is_some_and(|(_, c)| c[0] > 0.95 && c[2] < 0.05));
    }
}

#[test]
fn protein_1hpv_at_coarse_spacing() {
    let Some(mut engine) = engine() else { return };
    let atoms = load_pdb("1hpv.pdb");
    let p = SurfaceParams {
        spacing: 2.0,
        ..Default::default()
    };
    let out = engine.compute(&atoms.set(), &p).expect("GPU surface");
    let (_, _, cpu) = reference(&atoms, &p);
    assert!(
        cpu.triangle_count() > 1000,
        "1hpv reference too small: {}",
        cpu.triangle_count()
    );
    let same = assert_mesh_close("1hpv H=2", &out.mesh, &cpu, out.area, out.volume);
    eprintln!(
        "1hpv: {} triangles, element-wise identical: {same}",
        out.mesh.triangle_count()
    );
    assert!(out.mesh.is_closed(), "1hpv GPU mesh is not closed");
    assert!(out.volume > 0.0);
}

#[test]
fn matches_the_cpu_engine() {
    use mdsurf::gpu::tolerance as tol;
    use mdsurf::surface::{CpuEngine, density};
    let Some(mut gpu) = engine() else { return };
    let mut cpu = CpuEngine::new();
    let two = Atoms {
        positions: vec![Vec3::ZERO, Vec3::new(2.1, 0.3, -0.2)],
        radii: vec![1.5, 1.2],
        colours: Some(vec![[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    };
    let cases = [
        (
            "two atoms H=0.4",
            two,
            SurfaceParams {
                spacing: 0.4,
                ..Default::default()
            },
        ),
        (
            "1hpv H=2",
            load_pdb("1hpv.pdb"),
            SurfaceParams {
                spacing: 2.0,
                ..Default::default()
            },
        ),
    ];
    for (what, atoms, p) in cases {
        let g = gpu.compute(&atoms.set(), &p).expect("GPU surface");
        let c = cpu.compute(&atoms.set(), &p).expect("CPU surface");
        assert_eq!(g.grid, c.grid, "{what}: grids differ");
        assert!(
            tol::triangles_close(g.mesh.triangle_count(), c.mesh.triangle_count()),
            "{what}: {} GPU vs {} CPU triangles",
            g.mesh.triangle_count(),
            c.mesh.triangle_count()
        );
        for (name, a, b) in [("area", g.area, c.area), ("volume", g.volume, c.volume)] {
            assert!(
                tol::rel_close(a, b, tol::AREA_VOLUME_REL),
                "{what}: {name} GPU {a} CPU {b}"
            );
        }
        // Density against the CPU engine's own density stage.
        let d = density::compute(&atoms.set(), &p, &c.grid).expect("CPU density");
        let gd = gpu.read_density().expect("GPU density");
        assert_eq!(gd.len(), d.values.len());
        let bad = gd
            .iter()
            .zip(&d.values)
            .filter(|(a, b)| !tol::density_close(**a, **b))
            .count();
        assert_eq!(
            bad, 0,
            "{what}: {bad} density samples differ from the CPU engine"
        );
    }
}
