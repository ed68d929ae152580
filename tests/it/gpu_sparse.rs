//! Sparse bricks on the GPU (issue 12): the engine samples and classifies only the bricks of
//! 8^3 samples that some atom reaches, and must give the dense GPU path's mesh exactly (same
//! vertices, triangles and density volume, since a reached brick runs the same arithmetic and an
//! unreached one is 0 either way) and the CPU engine's within the tolerances of
//! `mdsurf::gpu::tolerance`: on a protein (1hpv) and on a hollow shell (mostly empty space, so
//! most bricks are skipped), through slabs, after an isovalue-only change, and with no GPU object
//! created in steady state on the blocking and the non-blocking path.

use crate::gpu_support::*;
use mdsurf::gpu::engine::EngineOptions;
use mdsurf::gpu::{Changes, GpuEngine, GpuObjects, tolerance as tol};
use mdsurf::surface::{CpuEngine, Mesh, SurfaceEngine, SurfaceOutput, SurfaceParams};
use mdsurf::synthetic::SyntheticSystem;

fn params(spacing: f32) -> SurfaceParams {
    SurfaceParams {
        spacing,
        ..Default::default()
    }
}

/// The engine with sparse bricks on or off and an optional slab cap (layers).
fn set_mode(engine: &mut GpuEngine, sparse: bool, max_slab_layers: Option<u32>) {
    let opts = EngineOptions {
        sparse_bricks: sparse,
        max_slab_layers,
        ..engine.options()
    };
    engine.set_options(opts);
}

/// Hollow shell of `count` atoms (radius 1.5 Å, coloured), innermost layer 60 Å out.
fn shell(count: usize, frame: usize) -> Atoms {
    let s = SyntheticSystem::shell(
        &[1.5, 1.2],
        Some(&[[0.9, 0.3, 0.2], [0.2, 0.4, 0.9]]),
        count,
    )
    .expect("shell");
    let mut positions = Vec::new();
    s.frame_into(frame, &mut positions);
    Atoms {
        positions,
        radii: s.radii().to_vec(),
        colours: s.colours().map(<[_]>::to_vec),
    }
}

/// Asserts two GPU meshes are the same, vertex for vertex.
fn assert_same_mesh(what: &str, sparse: &Mesh, dense: &Mesh) {
    assert!(dense.triangle_count() > 0, "{what}: empty dense mesh");
    assert_eq!(
        sparse.triangle_count(),
        dense.triangle_count(),
        "{what}: triangles"
    );
    assert_eq!(
        sparse.vertex_count(),
        dense.vertex_count(),
        "{what}: vertices"
    );
    assert!(sparse.indices == dense.indices, "{what}: indices differ");
    assert!(
        sparse.positions == dense.positions,
        "{what}: positions differ"
    );
    assert!(sparse.normals == dense.normals, "{what}: normals differ");
    assert!(sparse.colours == dense.colours, "{what}: colours differ");
}

/// Area and volume of the GPU frame within the parity tolerance of the CPU engine's, and the
/// triangle counts within theirs.
fn assert_cpu_close(what: &str, gpu: &SurfaceOutput, cpu: &SurfaceOutput) {
    assert!(
        tol::triangles_close(gpu.mesh.triangle_count(), cpu.mesh.triangle_count()),
        "{what}: {} GPU triangles vs {} CPU",
        gpu.mesh.triangle_count(),
        cpu.mesh.triangle_count()
    );
    for (name, g, c) in [
        ("area", gpu.area, cpu.area),
        ("volume", gpu.volume, cpu.volume),
    ] {
        assert!(
            tol::rel_close(g, c, tol::AREA_VOLUME_REL),
            "{what}: {name} {g} vs CPU {c}"
        );
    }
}

/// What a sparse frame used: the reached fraction of bricks, and whether its class entries
/// were held per brick slot.
struct SparseUse {
    fraction: f64,
    sparse_classes: bool,
}

/// Computes `atoms` sparse (with `slabs` as the slab cap) and dense (one pass) on one engine;
/// asserts the meshes and density volumes agree exactly and both match the CPU engine. None
/// without a GPU (allowed only when the suite does not require one).
fn sparse_vs_dense(
    what: &str,
    atoms: &Atoms,
    p: &SurfaceParams,
    slabs: Option<u32>,
) -> Option<SparseUse> {
    let mut engine = engine()?;
    set_mode(&mut engine, false, None);
    let dense = engine.compute(&atoms.set(), p).expect("dense frame");
    let dense_density = engine.read_density().expect("dense density");
    let dense_classes = engine.read_classes().expect("dense classes");
    assert!(
        engine.brick_stats().is_none(),
        "{what}: dense path reports bricks"
    );

    set_mode(&mut engine, true, slabs);
    let sparse = engine.compute(&atoms.set(), p).expect("sparse frame");
    if slabs.is_none() {
        let sparse_density = engine.read_density().expect("sparse density");
        assert_eq!(sparse_density.len(), dense_density.len());
        let differ = sparse_density
            .iter()
            .zip(&dense_density)
            .filter(|(s, d)| s.to_bits() != d.to_bits())
            .count();
        assert_eq!(differ, 0, "{what}: density samples differ from dense");
        // Class words, gathered back from the brick slots' entries on sparse classes: every
        // point's word is the dense path's (0 far from every atom).
        let sparse_classes = engine.read_classes().expect("sparse classes");
        assert_eq!(
            sparse_classes.len(),
            dense_classes.len(),
            "{what}: class points"
        );
        let differ = sparse_classes
            .iter()
            .zip(&dense_classes)
            .filter(|(s, d)| s != d)
            .count();
        assert_eq!(differ, 0, "{what}: class words differ from dense");
        assert!(
            dense_classes.iter().any(|&w| w != 0),
            "{what}: no class word set"
        );
    } else {
        let slabs_run = engine.last_frame().map(|f| f.slabs).unwrap_or(0);
        assert!(slabs_run > 1, "{what}: only {slabs_run} slab");
    }
    let bricks = engine.brick_stats().expect("sparse brick stats");
    assert!(
        bricks.occupied > 0 && bricks.occupied <= bricks.bricks,
        "{what}: {bricks:?}"
    );
    assert_same_mesh(what, &sparse.mesh, &dense.mesh);
    assert!(sparse.mesh.is_closed(), "{what}: sparse mesh not closed");
    assert_eq!(sparse.area.to_bits(), dense.area.to_bits(), "{what}: area");
    assert_eq!(
        sparse.volume.to_bits(),
        dense.volume.to_bits(),
        "{what}: volume"
    );

    let cpu = CpuEngine::new().compute(&atoms.set(), p).expect("cpu");
    assert_cpu_close(what, &sparse, &cpu);
    Some(SparseUse {
        fraction: bricks.occupied_fraction(),
        sparse_classes: engine.sparse_classes(),
    })
}

#[test]
fn sparse_matches_dense_and_cpu_on_1hpv() {
    let atoms = load_pdb("1hpv.pdb");
    if let Some(used) = sparse_vs_dense("1hpv H=1", &atoms, &params(1.0), None) {
        // A compact protein still leaves bricks of its padded box unreached.
        assert!(used.fraction < 1.0, "reached fraction {}", used.fraction);
    }
}

#[test]
fn sparse_skips_the_inside_of_a_hollow_shell() {
    let atoms = shell(12_000, 0);
    if let Some(used) = sparse_vs_dense("shell 12k H=1.5", &atoms, &params(1.5), None) {
        assert!(
            (0.05..0.6).contains(&used.fraction),
            "reached fraction {}",
            used.fraction
        );
        // Mostly empty: class words, vertex bases and active cells live in the brick slots.
        assert!(used.sparse_classes, "shell classified per point");
    }
}

#[test]
fn sparse_through_slabs_matches_dense() {
    let atoms = load_pdb("1hpv.pdb");
    // 6 owned layers per slab: slabs cut through bricks of 8 layers.
    sparse_vs_dense("1hpv H=1.5 slabs", &atoms, &params(1.5), Some(6));
}

#[test]
fn sparse_classes_through_slabs_match_dense() {
    let atoms = shell(12_000, 2);
    // 48 owned layers per slab: slabs cut through bricks, and a point's class entry may sit
    // in the apron of a brick in the next brick layer.
    if let Some(used) = sparse_vs_dense("shell 12k H=1.5 slabs", &atoms, &params(1.5), Some(48)) {
        assert!(used.sparse_classes, "shell slabs classified per point");
    }
}

/// An isovalue change re-runs only Marching Cubes, on the brick flags of the last full frame;
/// a colour change re-runs the colour pass over the reached bricks only.
#[test]
fn sparse_partial_frames_match_dense() {
    let Some(mut sparse) = engine() else {
        return;
    };
    let Some(mut dense) = engine() else {
        return;
    };
    set_mode(&mut dense, false, None);
    let atoms = shell(6_000, 1);
    let p = params(1.5);
    for e in [&mut sparse, &mut dense] {
        e.compute(&atoms.set(), &p).expect("first frame");
    }
    let iso = SurfaceParams { isovalue: 0.3, ..p };
    let s = sparse.compute(&atoms.set(), &iso).expect("sparse I=0.3");
    assert_eq!(
        sparse.last_frame().map(|f| f.work),
        Some(mdsurf::gpu::Work::Mc)
    );
    let d = dense.compute(&atoms.set(), &iso).expect("dense I=0.3");
    assert_same_mesh("I = 0.3", &s.mesh, &d.mesh);

    let mut recoloured = atoms.clone();
    if let Some(c) = recoloured.colours.as_mut() {
        c.iter_mut().for_each(|c| *c = [c[2], c[0], 0.5]);
    }
    let s = sparse
        .compute(&recoloured.set(), &iso)
        .expect("sparse recolour");
    assert_eq!(
        sparse.last_frame().map(|f| f.work),
        Some(mdsurf::gpu::Work::Colour)
    );
    let d = dense
        .compute(&recoloured.set(), &iso)
        .expect("dense recolour");
    assert_same_mesh("recoloured", &s.mesh, &d.mesh);
}

/// Two cases at H = 1.5 Å: a shell of `count` atoms (frame `frame`) in one pass, and 1hpv
/// through slabs of 6 owned layers (cutting bricks of 8 layers), as (name, atoms, parameters,
/// slab cap).
fn shell_and_slabbed_1hpv(
    count: usize,
    frame: usize,
) -> [(String, Atoms, SurfaceParams, Option<u32>); 2] {
    [
        (
            format!("shell {count} H=1.5"),
            shell(count, frame),
            params(1.5),
            None,
        ),
        (
            "1hpv H=1.5 slabs".to_string(),
            load_pdb("1hpv.pdb"),
            params(1.5),
            Some(6),
        ),
    ]
}

/// A dense engine (slab cap `slabs`) and its frame of `atoms`; None without a GPU.
fn dense_frame(
    atoms: &Atoms,
    p: &SurfaceParams,
    slabs: Option<u32>,
) -> Option<(GpuEngine, SurfaceOutput)> {
    let mut dense = engine()?;
    set_mode(&mut dense, false, slabs);
    let d = dense.compute(&atoms.set(), p).expect("dense frame");
    Some((dense, d))
}

/// Density and colour live in brick slots sized from the reached bricks: an engine whose slots
/// start far too small overflows its first frame (nothing drawn), grows them from the reached
/// count and re-runs density, and then gives the dense path's mesh exactly, in one pass and
/// through slabs; a fresh sparse engine holds less GPU memory than a dense one on a shell.
#[test]
fn sparse_brick_slots_grow_after_an_overflow() {
    for (what, atoms, p, slabs) in shell_and_slabbed_1hpv(6_000, 2) {
        let Some((dense, d)) = dense_frame(&atoms, &p, slabs) else {
            return;
        };
        let Some(mut sparse) = engine() else {
            return;
        };
        sparse.set_options(EngineOptions {
            max_slab_layers: slabs,
            initial_brick_slots: Some(2),
            ..sparse.options()
        });
        let info = sparse
            .submit(&atoms.set(), &p, Changes::ALL)
            .expect("submit");
        let first = sparse.wait_stats(info.frame).expect("first counters");
        assert!(
            first.overflow && first.brick_overflow && first.reached_bricks > 2,
            "{what}: {first:?}"
        );
        let stats = sparse.finish(info.frame, &atoms.set(), &p).expect("finish");
        assert!(!stats.overflow, "{what}: {stats:?}");
        assert_eq!(
            sparse.last_frame().map(|f| f.work),
            Some(mdsurf::gpu::Work::Full),
            "{what}: the rerun did not re-run density"
        );
        let mesh = sparse.read_mesh(&stats).expect("mesh");
        assert_same_mesh(&what, &mesh, &d.mesh);
        if slabs.is_none() {
            assert!(
                sparse.gpu_bytes() < dense.gpu_bytes(),
                "{what}: sparse {} bytes, dense {}",
                sparse.gpu_bytes(),
                dense.gpu_bytes()
            );
        }
    }
}

/// A fresh engine counts its first sparse frame's reached bricks before density runs, so that
/// frame fits its brick slots at once (no overflow, density once), even when more than a
/// quarter of the bricks are reached (the shell), and through slabs.
#[test]
fn the_first_sparse_frame_fits_its_counted_brick_slots() {
    for (what, atoms, p, slabs) in shell_and_slabbed_1hpv(12_000, 0) {
        let Some((_, d)) = dense_frame(&atoms, &p, slabs) else {
            return;
        };
        let Some(mut sparse) = engine() else {
            return;
        };
        set_mode(&mut sparse, true, slabs);
        let info = sparse
            .submit(&atoms.set(), &p, Changes::ALL)
            .expect("submit");
        let first = sparse.wait_stats(info.frame).expect("first counters");
        assert!(
            !first.overflow && !first.brick_overflow,
            "{what}: first frame overflowed: {first:?}"
        );
        let bricks = sparse.brick_stats().expect("brick stats");
        if slabs.is_none() {
            // More than the quarter of the bricks an uncounted first guess would have held.
            assert!(
                bricks.occupied * 4 > bricks.bricks,
                "{what}: only {bricks:?} reached: test too weak"
            );
        }
        let mesh = sparse.read_mesh(&first).expect("mesh");
        assert_same_mesh(&what, &mesh, &d.mesh);
    }
}

/// Opening another system (a new atom count on a much larger grid) on the same engine counts
/// its reached bricks again, while a few atoms fewer (a `within` selection) do not: a shell that reaches many more bricks than the small protein before it fits its
/// brick slots on its first frame (density runs once; only a mesh overflow re-runs Marching
/// Cubes), and gives the dense mesh.
#[test]
fn a_new_system_counts_its_bricks_on_its_first_frame() {
    let Some(mut sparse) = engine() else {
        return;
    };
    let p = params(1.5);
    let small = load_pdb("1hpv.pdb");
    sparse.compute(&small.set(), &p).expect("1hpv frame");
    let before = sparse.brick_stats().expect("1hpv bricks").occupied;
    assert_eq!(sparse.brick_counts(), 1, "the engine's first frame counts");
    // A few atoms fewer (as a `within` selection changes from frame to frame): the same
    // system, no new count and no wait on the device.
    let keep = small.radii.len() - 20;
    let fewer = Atoms {
        positions: small.positions[..keep].to_vec(),
        radii: small.radii[..keep].to_vec(),
        colours: small.colours.as_ref().map(|c| c[..keep].to_vec()),
    };
    sparse
        .compute(&fewer.set(), &p)
        .expect("1hpv less 20 atoms");
    assert_eq!(sparse.brick_counts(), 1, "a changed atom count recounted");
    let big = shell(12_000, 0);
    let info = sparse.submit(&big.set(), &p, Changes::ALL).expect("submit");
    let first = sparse.wait_stats(info.frame).expect("shell counters");
    assert_eq!(sparse.brick_counts(), 2, "the shell was not counted");
    assert!(
        first.reached_bricks as u64 > 2 * before,
        "shell reached {} bricks, 1hpv {before}: test too weak",
        first.reached_bricks
    );
    assert!(
        !first.brick_overflow,
        "shell's bricks overflowed their slots: {first:?}"
    );
    // The mesh buffers, sized for 1hpv, may overflow: then only Marching Cubes runs again.
    let stats = sparse.finish(info.frame, &big.set(), &p).expect("finish");
    if first.overflow {
        assert_eq!(
            sparse.last_frame().map(|f| f.work),
            Some(mdsurf::gpu::Work::Mc),
            "the mesh rerun ran density again"
        );
    }
    let Some((_, d)) = dense_frame(&big, &p, None) else {
        return;
    };
    let mesh = sparse.read_mesh(&stats).expect("mesh");
    assert_same_mesh("shell after 1hpv", &mesh, &d.mesh);
}

/// Steady state on sparse bricks: moving atoms (new positions, the same count and grid) create
/// no GPU object once the buffers fit, blocking or submitted; submitted frames alternate
/// between the output sets. Counted from the second frame: the first frame's counters may grow
/// the mesh buffers once when the mesh came close to filling them.
#[test]
fn sparse_frames_create_no_gpu_objects() {
    let Some(mut engine) = engine() else {
        return;
    };
    assert!(
        engine.options().sparse_bricks,
        "sparse bricks are the default"
    );
    let p = params(2.0);
    let frames: Vec<Atoms> = (0..5).map(|i| shell(8_000, i)).collect();
    let mut settled = None;
    for (i, atoms) in frames.iter().enumerate() {
        let out = engine.compute(&atoms.set(), &p).expect("frame");
        assert!(out.mesh.is_closed(), "frame {i}: mesh not closed");
        if i == 1 {
            settled = Some(engine.objects_created());
        }
    }
    assert_eq!(
        engine.objects_created() - settled.expect("two frames"),
        GpuObjects::default(),
        "blocking sparse frames created GPU objects"
    );

    let before = engine.objects_created();
    let mut sets = Vec::new();
    for (i, atoms) in frames.iter().enumerate() {
        let changes = Changes {
            positions: true,
            ..Default::default()
        };
        let info = engine.submit(&atoms.set(), &p, changes).expect("submit");
        let stats = engine.finish(info.frame, &atoms.set(), &p).expect("finish");
        assert!(!stats.overflow, "frame {i} overflowed");
        assert!(stats.reached_bricks > 0, "frame {i}: no reached bricks");
        sets.push(engine.output_set());
    }
    assert_eq!(
        engine.objects_created() - before,
        GpuObjects::default(),
        "submitted sparse frames created GPU objects"
    );
    assert!(
        sets.windows(2).all(|w| w[0] != w[1]),
        "output sets do not alternate: {sets:?}"
    );
}

/// `surface --stats` without `-o`: an engine told not to keep the mesh reports the same area and
/// volume (the GPU's own reductions) and the mesh's counts, with no mesh read back.
#[test]
fn measuring_without_the_mesh_reports_the_kept_meshs_figures() {
    let Some(mut engine) = engine() else {
        return;
    };
    let atoms = load_pdb("1hpv.pdb");
    let p = params(1.0);
    let kept = engine.compute(&atoms.set(), &p).expect("kept mesh");
    engine.set_keep_mesh(false);
    let measured = engine.compute(&atoms.set(), &p).expect("measured only");
    assert!(kept.mesh.triangle_count() > 1000 && kept.counts_without_mesh.is_none());
    assert!(measured.mesh.indices.is_empty() && measured.mesh.positions.is_empty());
    assert_eq!(measured.triangle_count(), kept.mesh.triangle_count());
    assert_eq!(measured.vertex_count(), kept.mesh.vertex_count());
    assert_eq!(measured.area.to_bits(), kept.area.to_bits(), "area");
    assert_eq!(measured.volume.to_bits(), kept.volume.to_bits(), "volume");
}

/// The two sparse density gathers (each thread loading its own atoms, or a brick's threads
/// sharing their loads through workgroup memory) give every density sample the same bits and
/// so the same mesh, colours included, through slabs too.
#[test]
fn tiled_gather_matches_row_gather() {
    use mdsurf::gpu::DensityGather;
    let cases = [
        ("1hpv H=1", load_pdb("1hpv.pdb"), params(1.0), None),
        (
            "shell 6k H=1.5 slabs",
            shell(6_000, 1),
            params(1.5),
            Some(6),
        ),
    ];
    for (what, atoms, p, slabs) in cases {
        let Some(mut engine) = engine() else {
            return;
        };
        let mut run = |gather| {
            engine.set_options(EngineOptions {
                sparse_bricks: true,
                max_slab_layers: slabs,
                density_gather: gather,
                ..engine.options()
            });
            let out = engine.compute(&atoms.set(), &p).expect("frame");
            (out, engine.read_density().expect("density"))
        };
        let (rows, rows_density) = run(DensityGather::Rows);
        let (tiled, tiled_density) = run(DensityGather::Tiled);
        // The last slab's volume (the one read back) holds density somewhere.
        assert!(
            rows_density.iter().any(|&d| d > 0.0),
            "{what}: no density read back"
        );
        assert_eq!(tiled_density.len(), rows_density.len(), "{what}: samples");
        let differ = tiled_density
            .iter()
            .zip(&rows_density)
            .filter(|(t, r)| t.to_bits() != r.to_bits())
            .count();
        assert_eq!(
            differ, 0,
            "{what}: density samples differ between the gathers"
        );
        assert!(!rows.mesh.colours.is_empty(), "{what}: no colours compared");
        assert_same_mesh(what, &tiled.mesh, &rows.mesh);
    }
}
