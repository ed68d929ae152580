//! The sparse CPU engine (density in 8³ bricks, only active bricks marched, colours per vertex)
//! against the dense path ([`CpuEngine::dense`], full volumes, every cell marched), computed
//! independently in the same test: same vertices, normals, colours and triangles in the same
//! order, and the same area and volume to the last bit. On real proteins, a frame of a
//! solvated trajectory, a hollow shell (mostly empty space) and across parameter changes.
//! Measuring without keeping the mesh gives the same area and volume to the last bit.

use glam::Vec3;
use mdsurf::io;
use mdsurf::model::ColorScheme;
use mdsurf::surface::{
    AtomSet, BrickStats, CpuEngine, MeshCounts, Quality, SurfaceEngine, SurfaceOutput,
    SurfaceParams, VertexMode,
};

use crate::data_support::data;
use crate::surface_common::Rng;

/// Positions (Å), radii (Å) and element colours of frame 0 of `top` (+ `traj`).
fn load(top: &str, traj: Option<&str>) -> (Vec<Vec3>, Vec<f32>, Vec<[f32; 3]>) {
    let (top, traj) = (data(top), traj.map(data));
    let t = io::open(&top, traj.as_deref()).unwrap_or_else(|e| panic!("{top:?}: {e}"));
    let frame = t.read_frame(0).unwrap_or_else(|e| panic!("{top:?}: {e}"));
    let topology = t.topology();
    let colours = ColorScheme::Element.atom_colours(topology);
    (frame.positions, topology.radii.clone(), colours)
}

fn bits3(v: &[Vec3]) -> Vec<[u32; 3]> {
    v.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

fn colour_bits(v: &[[f32; 3]]) -> Vec<[u32; 3]> {
    v.iter().map(|c| c.map(f32::to_bits)).collect()
}

/// Asserts `a` and `b` are bitwise the same surface.
fn assert_same(what: &str, a: &SurfaceOutput, b: &SurfaceOutput) {
    assert_eq!(a.grid, b.grid, "{what}: grid");
    assert_eq!(a.mesh.indices, b.mesh.indices, "{what}: triangles");
    assert!(
        bits3(&a.mesh.positions) == bits3(&b.mesh.positions),
        "{what}: positions"
    );
    assert!(
        bits3(&a.mesh.normals) == bits3(&b.mesh.normals),
        "{what}: normals"
    );
    assert!(
        colour_bits(&a.mesh.colours) == colour_bits(&b.mesh.colours),
        "{what}: colours"
    );
    assert_eq!(a.area.to_bits(), b.area.to_bits(), "{what}: area");
    assert_eq!(a.volume.to_bits(), b.volume.to_bits(), "{what}: volume");
}

/// Dense and sparse surfaces of the same atoms (fresh engines), plus the sparse brick counts.
/// Each engine is also run without keeping its mesh (`set_keep_mesh(false)`, as `surface
/// --stats` without `-o`), which must report the same area and volume to the last bit and the
/// mesh's counts.
fn both(atoms: &AtomSet<'_>, params: &SurfaceParams) -> (SurfaceOutput, SurfaceOutput, BrickStats) {
    let dense = CpuEngine::dense()
        .compute(atoms, params)
        .expect("dense surface");
    let mut engine = CpuEngine::bricks();
    let sparse = engine.compute(atoms, params).expect("sparse surface");
    let stats = engine.brick_stats().expect("sparse engine reports bricks");
    assert_eq!(
        dense.counts_without_mesh, None,
        "the mesh is kept by default"
    );
    for (name, mut measurer) in [
        ("dense", CpuEngine::dense()),
        ("sparse", CpuEngine::bricks()),
    ] {
        measurer.set_keep_mesh(false);
        let m = measurer.compute(atoms, params).expect("measured surface");
        assert!(
            m.mesh.positions.is_empty() && m.mesh.indices.is_empty(),
            "{name}: no mesh kept"
        );
        let counts = MeshCounts {
            vertices: dense.mesh.vertex_count(),
            triangles: dense.mesh.triangle_count(),
        };
        assert_eq!(m.counts_without_mesh, Some(counts), "{name}: counts");
        assert_eq!(m.vertex_count(), counts.vertices, "{name}: vertex_count()");
        assert_eq!(
            m.area.to_bits(),
            dense.area.to_bits(),
            "{name}: area without the mesh"
        );
        assert_eq!(
            m.volume.to_bits(),
            dense.volume.to_bits(),
            "{name}: volume without the mesh"
        );
    }
    (dense, sparse, stats)
}

/// The atoms of [`load`]'s result, with their colours.
fn coloured_atoms(loaded: &(Vec<Vec3>, Vec<f32>, Vec<[f32; 3]>)) -> AtomSet<'_> {
    let (positions, radii, colours) = loaded;
    AtomSet {
        positions,
        radii,
        colours: Some(colours),
    }
}

fn check_file(top: &str, traj: Option<&str>, params: &SurfaceParams) -> BrickStats {
    let loaded = load(top, traj);
    let atoms = coloured_atoms(&loaded);
    let (dense, sparse, stats) = both(&atoms, params);
    assert!(sparse.mesh.is_closed(), "{top}: sparse mesh not closed");
    assert!(sparse.mesh.triangle_count() > 1000, "{top}: tiny mesh");
    assert_same(top, &dense, &sparse);
    assert!(stats.occupied <= stats.bricks && stats.active <= stats.bricks);
    assert!(stats.active > 0);
    stats
}

#[test]
fn sparse_equals_dense_on_adk() {
    let params = SurfaceParams {
        quality: Quality::High,
        ..SurfaceParams::default()
    };
    check_file("adk_open.pdb", None, &params);
}

#[test]
fn sparse_equals_dense_on_1hpv() {
    check_file("1hpv.pdb", None, &SurfaceParams::default());
}

/// Refined vertices (on the exact Gaussian sum) come out the same on both paths too.
#[test]
fn sparse_equals_dense_with_refined_vertices() {
    let loaded = load("1hpv.pdb", None);
    let atoms = coloured_atoms(&loaded);
    let params = SurfaceParams {
        spacing: 1.5,
        ..SurfaceParams::default()
    };
    let refined = |engine: CpuEngine| {
        engine
            .with_vertices(VertexMode::Refined)
            .compute(&atoms, &params)
            .expect("refined surface")
    };
    let dense = refined(CpuEngine::dense());
    let sparse = refined(CpuEngine::bricks());
    assert!(sparse.mesh.triangle_count() > 1000, "tiny mesh");
    assert_same("1hpv refined", &dense, &sparse);
}

/// The default engine takes the dense path on small grids and bricks on large ones, with the
/// same results as either.
#[test]
fn the_default_engine_picks_dense_for_small_grids_only() {
    let loaded = load("1hpv.pdb", None);
    let atoms = coloured_atoms(&loaded);
    for (spacing, dense_expected) in [(1.0, true), (0.5, false)] {
        let params = SurfaceParams {
            spacing,
            ..SurfaceParams::default()
        };
        let mut engine = CpuEngine::new();
        let out = engine.compute(&atoms, &params).expect("surface");
        let samples = out.grid.voxel_count();
        assert_eq!(
            samples <= mdsurf::surface::cpu::DENSE_MAX_SAMPLES,
            dense_expected,
            "H = {spacing}: {samples} samples"
        );
        assert_eq!(
            engine.brick_stats().is_none(),
            dense_expected,
            "H = {spacing}: bricks used on {samples} samples"
        );
        let reference = CpuEngine::dense().compute(&atoms, &params).expect("dense");
        assert_same("default engine", &reference, &out);
    }
}

#[test]
fn sparse_equals_dense_on_a_solvated_trajectory_frame() {
    let params = SurfaceParams {
        quality: Quality::High,
        ..SurfaceParams::default()
    };
    check_file("adk_oplsaa.gro", Some("adk_oplsaa.xtc"), &params);
}

#[test]
fn sparse_equals_dense_across_parameters_and_without_colours() {
    let (pos, radii, colours) = load("adk_open.pdb", None);
    let cases = [
        (0.5, 1.0, 0.5, Quality::Medium),
        (2.0, 1.0, 0.5, Quality::Low),
        (1.3, 1.4, 0.3, Quality::Max),
        (0.8, 0.8, 1.0, Quality::High),
        (3.0, 1.0, 0.5, Quality::Low),
    ];
    for (spacing, radius_scale, isovalue, quality) in cases {
        let params = SurfaceParams {
            spacing,
            radius_scale,
            isovalue,
            quality,
        };
        for colour in [true, false] {
            let atoms = AtomSet {
                positions: &pos,
                radii: &radii,
                colours: colour.then_some(&colours[..]),
            };
            let (dense, sparse, _) = both(&atoms, &params);
            assert_same(&format!("{params:?} colour {colour}"), &dense, &sparse);
            assert!(sparse.mesh.is_closed(), "{params:?}");
        }
    }
}

/// `n` atoms spread evenly over a sphere of radius `r` Å around `centre` (Fibonacci lattice),
/// with radii 1.2..1.9 Å and colours varying over the sphere.
fn shell(n: usize, r: f32, centre: Vec3) -> (Vec<Vec3>, Vec<f32>, Vec<[f32; 3]>) {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let mut rng = Rng(12345);
    let mut pos = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    let mut colours = Vec::with_capacity(n);
    for i in 0..n {
        let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let ring = (1.0 - y * y).sqrt();
        let phi = golden * i as f32;
        let d = Vec3::new(ring * phi.cos(), y, ring * phi.sin());
        pos.push(centre + r * d);
        radii.push(1.2 + 0.7 * rng.next());
        colours.push([0.5 + 0.5 * d.x, 0.5 + 0.5 * d.y, rng.next()]);
    }
    (pos, radii, colours)
}

#[test]
fn sparse_equals_dense_on_a_hollow_shell_and_skips_its_inside() {
    let (pos, radii, colours) = shell(16_000, 60.0, Vec3::new(3.0, -7.0, 11.0));
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: Some(&colours),
    };
    let params = SurfaceParams {
        quality: Quality::High,
        ..SurfaceParams::default()
    };
    let (dense, sparse, stats) = both(&atoms, &params);
    assert_same("shell", &dense, &sparse);
    assert!(sparse.mesh.is_closed());
    // Two sheets (outer and inner side of the shell): Euler characteristic 2 + 2.
    assert_eq!(sparse.mesh.euler_characteristic(), 4, "{stats:?}");
    // The shell is a thin layer: most bricks are empty, far fewer still are marched.
    assert!(
        stats.occupied_fraction() < 0.6,
        "occupied fraction {}",
        stats.occupied_fraction()
    );
    eprintln!("shell bricks: {stats:?}");
    assert!(
        stats.active < stats.occupied && stats.active_fraction() < 0.4,
        "{stats:?}"
    );
}

/// Positions (Å), radii (Å) and colours of one system.
type System<'a> = (&'a [Vec3], &'a [f32], &'a [[f32; 3]]);

#[test]
fn one_engine_reused_across_systems_matches_fresh_dense_results() {
    // Kept buffers (bricks, per-thread planes, Marching Cubes slabs) must not leak values from
    // one frame into the next: a big system, a small one, an offset copy, then the big again.
    let (pos, radii, colours) = load("adk_open.pdb", None);
    let (spos, sradii, scolours) = shell(3000, 25.0, Vec3::ZERO);
    let shifted: Vec<Vec3> = pos
        .iter()
        .map(|p| *p + Vec3::new(0.37, -1.1, 2.9))
        .collect();
    let params = SurfaceParams::default();
    let mut engine = CpuEngine::bricks();
    let systems: [System<'_>; 4] = [
        (&pos, &radii, &colours),
        (&spos, &sradii, &scolours),
        (&shifted, &radii, &colours),
        (&pos, &radii, &colours),
    ];
    for (n, (p, r, c)) in systems.into_iter().enumerate() {
        let atoms = AtomSet {
            positions: p,
            radii: r,
            colours: Some(c),
        };
        let sparse = engine.compute(&atoms, &params).expect("sparse");
        let dense = CpuEngine::dense().compute(&atoms, &params).expect("dense");
        assert_same(&format!("system {n}"), &dense, &sparse);
    }
}

/// The slabs of the sparse Marching Cubes follow each thread's share of the active bricks (one
/// brick layer each at least with refined vertices, two with interpolated ones), so their ends
/// move with the thread count: the mesh must not.
#[test]
fn sparse_result_does_not_depend_on_thread_count() {
    let loaded = load("1hpv.pdb", None);
    let atoms = coloured_atoms(&loaded);
    let params = SurfaceParams::default();
    for mode in VertexMode::ALL {
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| {
                    CpuEngine::bricks()
                        .with_vertices(mode)
                        .compute(&atoms, &params)
                        .expect("sparse")
                })
        };
        let one = run(1);
        for threads in [2, 3, 7] {
            assert_same(&format!("{mode}, {threads} threads"), &one, &run(threads));
        }
    }
}

#[test]
fn a_lone_atom_in_a_corner_of_a_brick_keeps_its_sphere() {
    // Grid edges that are not multiples of the brick size, and tiny systems of one or two
    // atoms at brick boundaries.
    for (n, spacing) in [(1usize, 1.0f32), (2, 0.7), (2, 1.9)] {
        let pos: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(7.9 * i as f32, 0.0, 0.0))
            .collect();
        let radii = vec![1.5; n];
        let params = SurfaceParams {
            spacing,
            ..SurfaceParams::default()
        };
        let atoms = AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        };
        let (dense, sparse, _) = both(&atoms, &params);
        assert_same(&format!("{n} atoms, H {spacing}"), &dense, &sparse);
        assert!(sparse.mesh.is_closed());
    }
}
