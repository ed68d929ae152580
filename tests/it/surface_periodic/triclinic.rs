//! Periodic surfaces in triclinic cells (issue 30): the rectangular box's tests again on a
//! synthetic truncated octahedron and on adenylate kinase's rhombic dodecahedron
//! (`adk_oplsaa.gro`): a corner atom is one sphere, area and volume per cell do not depend on
//! where the cell is cut, no walls and seamless copies along a, b, c, the per-cell volume
//! matches the inside samples, orthorhombic and rotated cells give the rectangular answer, and
//! `mdsurf surface --periodic` on the dodecahedron.

use std::collections::HashMap;
use std::f64::consts::PI;

use glam::{DVec3, Mat3, Vec3};
use mdsurf::surface::periodic::{
    PeriodicBox, PeriodicCell, PeriodicEngine, Replicate, TriclinicCell,
};
use mdsurf::surface::{AtomSet, CpuEngine, Mesh, SurfaceEngine, SurfaceOutput, SurfaceParams};

use super::{ARGON, load, params, rel};
use crate::cli_common::{Csv, mdsurf};
use crate::data_support::data;
use crate::surface_common::{Rng, sphere_radius};

const ADK: &str = "adk_oplsaa.gro";

/// GROMACS's truncated octahedron with image distance `d` (Å): every edge vector has length d.
fn octahedron(d: f32) -> [Vec3; 3] {
    let s2 = std::f32::consts::SQRT_2;
    let s6 = 6f32.sqrt();
    [
        Vec3::new(d, 0.0, 0.0),
        Vec3::new(d / 3.0, 2.0 * s2 * d / 3.0, 0.0),
        Vec3::new(-d / 3.0, s2 * d / 3.0, s6 * d / 3.0),
    ]
}

fn tri(
    engine: &mut PeriodicEngine,
    positions: &[Vec3],
    radii: &[f32],
    p: &SurfaceParams,
    cell: &TriclinicCell,
    replicate: Replicate,
) -> SurfaceOutput {
    let atoms = AtomSet {
        positions,
        radii,
        colours: None,
    };
    engine
        .compute_triclinic(&atoms, p, cell, replicate)
        .expect("triclinic periodic surface")
}

fn tri1(
    positions: &[Vec3],
    radii: &[f32],
    p: &SurfaceParams,
    cell: &TriclinicCell,
) -> SurfaceOutput {
    tri(
        &mut PeriodicEngine::new(),
        positions,
        radii,
        p,
        cell,
        Replicate::default(),
    )
}

/// `n` atoms spread uniformly over `cell` (radii 1.2 to 1.9 Å).
fn liquid(cell: &TriclinicCell, n: usize, seed: u64) -> (Vec<Vec3>, Vec<f32>) {
    let mut rng = Rng(seed);
    let m = Mat3::from_cols(cell.rows[0], cell.rows[1], cell.rows[2]);
    (0..n)
        .map(|_| {
            let s = Vec3::new(rng.next(), rng.next(), rng.next());
            (cell.origin + m * s, 1.2 + 0.7 * rng.next())
        })
        .unzip()
}

/// `positions` moved by `shift` (Å) and wrapped into `cell` (fractional coordinates in [0, 1)).
fn shifted_into(cell: &TriclinicCell, positions: &[Vec3], shift: Vec3) -> Vec<Vec3> {
    let m = cell.matrix();
    positions
        .iter()
        .map(|&p| {
            let s = cell.to_fractional(p + shift);
            let w = s - s.floor();
            (m * w).as_vec3() + cell.origin
        })
        .collect()
}

/// Shifts that are not lattice vectors: a few Å, and about half of each cell vector.
fn tri_shifts(cell: &TriclinicCell) -> [Vec3; 3] {
    let [a, b, c] = cell.rows;
    [
        Vec3::new(3.71, -1.29, 11.13),
        0.31 * a + 0.77 * b + 0.53 * c,
        0.5 * (a + b + c) + Vec3::new(0.123, 0.456, 0.789),
    ]
}

/// Largest relative change of area and volume under [`tri_shifts`], and the unshifted output.
fn tri_spread(
    cell: &TriclinicCell,
    positions: &[Vec3],
    radii: &[f32],
    p: &SurfaceParams,
) -> (f64, f64, SurfaceOutput) {
    let mut engine = PeriodicEngine::new();
    let base = tri(&mut engine, positions, radii, p, cell, Replicate::default());
    let (mut da, mut dv) = (0.0f64, 0.0f64);
    for s in tri_shifts(cell) {
        let moved = shifted_into(cell, positions, s);
        let out = tri(&mut engine, &moved, radii, p, cell, Replicate::default());
        da = da.max(rel(out.area, base.area));
        dv = dv.max(rel(out.volume, base.volume));
    }
    (da, dv, base)
}

/// Radii, positions and triclinic cell of frame 0 of adk_oplsaa (a rhombic dodecahedron).
fn adk() -> (Vec<f32>, Vec<Vec3>, TriclinicCell) {
    let t = mdsurf::io::open(&data(ADK), None).expect("open adk_oplsaa.gro");
    let f = t.read_frame(0).expect("frame 0");
    let rows = f.cell.expect("a box");
    let Ok(PeriodicCell::Triclinic(cell)) = PeriodicCell::from_cell(&rows) else {
        panic!("adk_oplsaa's box is triclinic: {rows:?}");
    };
    (t.topology().radii.clone(), f.positions, cell)
}

#[test]
fn a_triclinic_corner_atom_is_one_whole_sphere() {
    // d = 16 Å and H = 0.25 Å: 64 samples along each cell vector, so the corner and the
    // centre are both samples and the two spheres are sampled identically.
    let cell = TriclinicCell::new(octahedron(16.0)).expect("cell");
    let p = params(0.25, 1.0);
    let [a, b, c] = cell.rows;
    let centre = tri1(&[0.5 * (a + b + c)], &[1.5], &p, &cell);
    for at in [Vec3::ZERO, a + b, c - 2.0 * a + 0.5 * b] {
        let split = tri1(&[at], &[1.5], &p, &cell);
        assert!(rel(split.area, centre.area) < 1e-5, "{at}: {}", split.area);
        assert!(
            rel(split.volume, centre.volume) < 1e-5,
            "{at}: {}",
            split.volume
        );
    }
    let r = sphere_radius(1.5, p.isovalue);
    let (area, volume) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r * r * r);
    for at in [0.5 * (a + b + c), Vec3::new(0.1, 0.07, 15.9)] {
        let out = tri1(&[at], &[1.5], &p, &cell);
        assert!(rel(out.area, area) < 0.03, "{at}: {} vs {area}", out.area);
        assert!(
            rel(out.volume, volume) < 0.04,
            "{at}: {} vs {volume}",
            out.volume
        );
    }
}

#[test]
fn triclinic_area_and_volume_per_cell_do_not_depend_on_where_the_cell_is_cut() {
    let cell = TriclinicCell::new(octahedron(30.0)).expect("cell");
    let (pos, radii) = liquid(&cell, 600, 7);
    let (da, dv, base) = tri_spread(&cell, &pos, &radii, &params(0.5, 0.6));
    assert!(base.area > 2000.0, "area {}", base.area);
    assert!(da < 1e-3, "octahedron: area changes by {da:.2e}");
    assert!(dv < 1e-3, "octahedron: volume changes by {dv:.2e}");
    let (radii, pos, cell) = adk();
    let (da, dv, base) = tri_spread(&cell, &pos, &radii, &params(1.0, 1.0));
    assert!(
        base.volume > 0.5 * cell.signed_volume().abs(),
        "{}",
        base.volume
    );
    assert!(da < 1e-2, "adk: area changes by {da:.2e}");
    assert!(dv < 1e-3, "adk: volume changes by {dv:.2e}");
}

/// Fractional coordinate `s` is on a face plane (0 or `n`) within `tol`.
fn on_face(s: f64, n: f64, tol: f64) -> bool {
    s.abs() <= tol || (s - n).abs() <= tol
}

/// Counts edge uses of `mesh` with the vertices on the faces between the copies of a block of
/// `n` cells welded by exact position (elsewhere two vertices may coincide where an edge's
/// crossing rounds onto a sample, so those are left apart).
fn edge_uses(
    mesh: &Mesh,
    cell: &TriclinicCell,
    n: [f64; 3],
) -> (HashMap<(u32, u32), u32>, Vec<u32>) {
    let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
    let inner = |p: Vec3| {
        let f = cell.to_fractional(p);
        (0..3).any(|u| (1..n[u] as i32).any(|k| (f[u] - k as f64).abs() < 1e-4))
    };
    let id: Vec<u32> = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            if !inner(p) {
                return i as u32;
            }
            *weld
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(i as u32)
        })
        .collect();
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in mesh.indices.chunks_exact(3) {
        let t = [0, 1, 2].map(|k| id[t[k] as usize]);
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    (uses, id)
}

/// Every welded edge is used by two triangles unless both ends lie on one face of the block of
/// `n` cells (fractional coordinates 0 or n); returns the number of open edges.
fn open_only_on_faces(mesh: &Mesh, cell: &TriclinicCell, n: [f64; 3]) -> usize {
    let (uses, _) = edge_uses(mesh, cell, n);
    let frac = |i: u32| cell.to_fractional(mesh.positions[i as usize]);
    let mut open = 0;
    for (&(a, b), &k) in &uses {
        assert!(k <= 2, "edge used {k} times");
        if k == 1 {
            open += 1;
            let (fa, fb) = (frac(a), frac(b));
            let face = (0..3).any(|u| on_face(fa[u], n[u], 1e-4) && on_face(fb[u], n[u], 1e-4));
            assert!(face, "open edge {fa} {fb} not on a cell face");
        }
    }
    open
}

/// Fraction of triangles whose winding agrees with their vertex normals.
fn outward(mesh: &Mesh) -> f64 {
    let agree = mesh
        .indices
        .chunks_exact(3)
        .filter(|t| {
            let q = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let n: Vec3 = t.iter().map(|&k| mesh.normals[k as usize]).sum();
            (q[1] - q[0]).cross(q[2] - q[0]).dot(n) > 0.0
        })
        .count();
    agree as f64 / mesh.triangle_count().max(1) as f64
}

#[test]
fn a_film_in_a_triclinic_cell_has_no_walls() {
    // A film of atoms parallel to a and b (fractional c from 0.35 to 0.65) in a truncated
    // octahedron: its periodic surface is two sheets of about |a x b| each, with no walls on
    // the faces that cut a and b.
    let cell = TriclinicCell::new(octahedron(24.0)).expect("cell");
    let mut rng = Rng(5);
    let m = Mat3::from_cols(cell.rows[0], cell.rows[1], cell.rows[2]);
    let (pos, radii): (Vec<Vec3>, Vec<f32>) = (0..500)
        .map(|_| {
            let s = Vec3::new(rng.next(), rng.next(), 0.35 + 0.3 * rng.next());
            (m * s, 1.2 + 0.7 * rng.next())
        })
        .unzip();
    let out = tri1(&pos, &radii, &SurfaceParams::default(), &cell);
    let patch = 2.0 * cell.rows[0].cross(cell.rows[1]).length() as f64;
    assert!(
        out.area > 0.8 * patch && out.area < 2.0 * patch,
        "{} vs {patch}",
        out.area
    );
    // Walls on the four faces cutting a and b would be about 4 x 24 x 10 Å², a third of the
    // area.
    let mut wall = 0.0f64;
    let w = cell.widths();
    let inv = cell.matrix().inverse();
    for t in out.mesh.triangles() {
        let f = t.map(|q| cell.to_fractional(q));
        let n = (t[1] - t[0]).cross(t[2] - t[0]).as_dvec3();
        for u in 0..2 {
            let flat = f.iter().all(|s| on_face(s[u], 1.0, 1.5 / w[u]));
            if flat && n.dot(inv.row(u).normalize()).abs() > 0.9 * n.length() {
                wall += 0.5 * n.length();
            }
        }
    }
    assert!(wall < 0.01 * out.area, "{wall} Å² of wall in {}", out.area);
    assert!(open_only_on_faces(&out.mesh, &cell, [1.0; 3]) > 0);
}

#[test]
fn triclinic_cells_are_closed_across_faces_and_replicas_join_seamlessly() {
    let cell = TriclinicCell::new(octahedron(24.0)).expect("cell");
    let (pos, radii) = liquid(&cell, 250, 11);
    let p = params(0.8, 0.8);
    let mut engine = PeriodicEngine::new();
    let one = tri(&mut engine, &pos, &radii, &p, &cell, Replicate::default());
    assert!(one.mesh.triangle_count() > 1000);
    let open = open_only_on_faces(&one.mesh, &cell, [1.0; 3]);
    assert!(open > 0, "the surface crosses the cell faces");

    let eight = tri(&mut engine, &pos, &radii, &p, &cell, Replicate([2, 2, 2]));
    assert_eq!(eight.mesh.triangle_count(), 8 * one.mesh.triangle_count());
    assert!(rel(eight.area, 8.0 * one.area) < 1e-9);
    assert!(rel(eight.volume, 8.0 * one.volume) < 1e-9);
    assert!(rel(eight.mesh.area(), 8.0 * one.mesh.area()) < 1e-5);
    // Copies meet along a, b and c: welded, only the outer faces of the 2 x 2 x 2 block are
    // open, and the vertices welded together carry the same normal.
    open_only_on_faces(&eight.mesh, &cell, [2.0; 3]);
    let (_, id) = edge_uses(&eight.mesh, &cell, [2.0; 3]);
    let mut twins = 0;
    for (i, &j) in id.iter().enumerate() {
        if j as usize != i {
            let (ni, nj) = (eight.mesh.normals[i], eight.mesh.normals[j as usize]);
            assert!((ni - nj).length() < 1e-5, "{ni} vs {nj}");
            twins += 1;
        }
    }
    assert!(twins > 100, "{twins} vertices shared by two copies");
    // Triangles wind outward: their normals agree with the vertex normals.
    assert!(outward(&eight.mesh) > 0.99, "triangles wind inward");
}

#[test]
fn triclinic_per_cell_volume_matches_the_inside_samples_and_left_handed_cells() {
    let cell = TriclinicCell::new(octahedron(28.0)).expect("cell");
    let (pos, radii) = liquid(&cell, 400, 3);
    let p = params(0.7, 0.9);
    let mut engine = PeriodicEngine::new();
    let out = tri(&mut engine, &pos, &radii, &p, &cell, Replicate::default());
    let values = &engine.last_volume().values;
    let inside = values.iter().filter(|&&x| x >= p.isovalue).count();
    let estimate = cell.signed_volume() * inside as f64 / values.len() as f64;
    assert!(out.volume > 0.2 * cell.signed_volume(), "{}", out.volume);
    assert!(
        rel(out.volume, estimate) < 0.02,
        "{} vs {estimate}",
        out.volume
    );
    // b and c swapped: a left-handed cell with the same lattice and samples.
    let [a, b, c] = cell.rows;
    let left = TriclinicCell::new([a, c, b]).expect("left-handed cell");
    assert!(left.signed_volume() < 0.0);
    let mirrored = tri(&mut engine, &pos, &radii, &p, &left, Replicate::default());
    // Marching Cubes resolves ambiguous cubes by their orientation in index space, so the
    // mirrored index grid gives a slightly different piecewise-linear surface.
    assert!(
        rel(mirrored.area, out.area) < 2e-3,
        "{} vs {}",
        mirrored.area,
        out.area
    );
    assert!(
        rel(mirrored.volume, out.volume) < 2e-3,
        "{} vs {}",
        mirrored.volume,
        out.volume
    );
    assert!(outward(&mirrored.mesh) > 0.99, "triangles wind inward");
}

#[test]
fn orthorhombic_cells_give_the_rectangular_answer_even_rotated() {
    let (radii, frame, pbox) = load(ARGON);
    let p = params(1.0, 0.8);
    let atoms = AtomSet {
        positions: &frame.positions,
        radii: &radii,
        colours: None,
    };
    let mut engine = PeriodicEngine::new();
    let rect = engine
        .compute(&atoms, &p, &pbox, Replicate::default())
        .expect("rectangular");
    // A rectangular cell still takes the rectangular path: the same bits.
    let l = pbox.lengths;
    let rows = [Vec3::X * l.x, Vec3::Y * l.y, Vec3::Z * l.z];
    let via_cell = engine
        .compute_in_cell(Some(&rows), &atoms, &p, Replicate::default())
        .expect("rectangular cell");
    assert_eq!(via_cell.area.to_bits(), rect.area.to_bits());
    assert_eq!(via_cell.volume.to_bits(), rect.volume.to_bits());
    assert_eq!(via_cell.mesh, rect.mesh);
    // The same box through the triclinic path.
    let mut as_tri = TriclinicCell::new(rows).expect("cell");
    as_tri.origin = pbox.origin;
    let t = tri(
        &mut engine,
        &frame.positions,
        &radii,
        &p,
        &as_tri,
        Replicate::default(),
    );
    assert!(rel(t.area, rect.area) < 1e-5, "{} vs {}", t.area, rect.area);
    assert!(
        rel(t.volume, rect.volume) < 1e-5,
        "{} vs {}",
        t.volume,
        rect.volume
    );
    assert_eq!(t.mesh.triangle_count(), rect.mesh.triangle_count());
    // Rotated about an oblique axis, atoms and cell together: a triclinic cell to the
    // classifier, the same surface.
    let rot = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let rotated_rows = rows.map(|r| rot * r);
    let Ok(PeriodicCell::Triclinic(rcell)) = PeriodicCell::from_cell(&rotated_rows) else {
        panic!("a rotated box is not rectangular");
    };
    let moved: Vec<Vec3> = frame
        .positions
        .iter()
        .map(|&q| rot * (q - pbox.origin))
        .collect();
    let r = tri(
        &mut engine,
        &moved,
        &radii,
        &p,
        &rcell,
        Replicate::default(),
    );
    assert!(rel(r.area, rect.area) < 1e-4, "{} vs {}", r.area, rect.area);
    assert!(
        rel(r.volume, rect.volume) < 1e-4,
        "{} vs {}",
        r.volume,
        rect.volume
    );
    let cell_volume = l.x as f64 * l.y as f64 * l.z as f64;
    assert!(rel(rcell.signed_volume(), cell_volume) < 1e-5);
    assert!(PeriodicBox::from_cell(&rotated_rows).is_err());
}

#[test]
fn adk_in_its_rhombic_dodecahedron_has_a_periodic_surface() {
    let (radii, pos, cell) = adk();
    let [a, b, c] = cell.rows.map(|r| r.as_dvec3());
    // GROMACS's xy-square rhombic dodecahedron, d = 80.017 Å.
    assert!((b.length() - a.length()).abs() < 1e-3 && rel(c.length(), a.length()) < 1e-3);
    assert!(a.dot(b).abs() < 1e-6 && (c.dot(DVec3::Z) - 56.58).abs() < 0.01);
    let mut engine = PeriodicEngine::new();
    let out = tri(
        &mut engine,
        &pos,
        &radii,
        &SurfaceParams::default(),
        &cell,
        Replicate::default(),
    );
    let v = cell.signed_volume();
    eprintln!(
        "adk_oplsaa frame 0: area {:.1} Å², volume {:.1} Å³ of {v:.1}",
        out.area, out.volume
    );
    assert!(out.area.is_finite() && out.area > 0.0);
    assert!(
        out.volume > 0.5 * v && out.volume < v,
        "{} of {v}",
        out.volume
    );
    open_only_on_faces(&out.mesh, &cell, [1.0; 3]);
    // Reversing the atoms changes nothing (canonical order of the images).
    let rpos: Vec<Vec3> = pos.iter().rev().copied().collect();
    let rrad: Vec<f32> = radii.iter().rev().copied().collect();
    let back = tri(
        &mut engine,
        &rpos,
        &rrad,
        &SurfaceParams::default(),
        &cell,
        Replicate::default(),
    );
    assert_eq!(back.area.to_bits(), out.area.to_bits());
    assert_eq!(back.volume.to_bits(), out.volume.to_bits());
}

#[test]
fn cli_periodic_surface_of_a_triclinic_cell() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let adk = data(ADK);
    let adk = adk.to_string_lossy();
    let run = |extra: &[&str], name: &str| {
        let mut args = vec!["surface", &*adk, "--periodic", "--stats", name];
        args.extend_from_slice(extra);
        let run = mdsurf(d, &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        assert!(!run.stderr.contains("triclinic"), "{}", run.stderr);
        Csv::read(&d.join(name))
    };
    let one = run(&[], "s.csv");
    let col = |c: &Csv, name: &str| c.col(name)[0];
    let (area, volume) = (col(&one, "area_A2"), col(&one, "volume_A3"));
    assert!(area.is_finite() && area > 0.0, "{area}");
    assert!(volume.is_finite() && volume > 0.0, "{volume}");
    let two = run(&["--replicate", "2,1,1", "--spacing", "2"], "two.csv");
    let coarse = run(&["--spacing", "2"], "coarse.csv");
    assert_eq!(col(&two, "triangles"), 2.0 * col(&coarse, "triangles"));
    assert!(rel(col(&two, "volume_A3"), 2.0 * col(&coarse, "volume_A3")) < 1e-6);
}

#[test]
fn adks_protein_alone_has_the_non_periodic_surface() {
    // The protein (the first 3341 atoms) is split across the cell faces in the file; the
    // periodic engine does not care. Made whole (each atom the image nearest the one before)
    // it is far from its images (80 Å apart), so its periodic surface per cell is the ordinary
    // closed surface; the two differ only in where the samples fall (the sheared grid against
    // the Cartesian one).
    let (radii, pos, cell) = adk();
    let (pos, radii) = (&pos[..3341], &radii[..3341]);
    let p = params(0.5, 1.0);
    let periodic = tri1(pos, radii, &p, &cell);
    let m = cell.matrix();
    let mut whole = vec![pos[0]];
    for &q in &pos[1..] {
        let prev = *whole.last().expect("one atom");
        let d = cell.to_fractional(q) - cell.to_fractional(prev);
        whole.push(q - (m * d.round()).as_vec3());
    }
    let atoms = AtomSet {
        positions: &whole,
        radii,
        colours: None,
    };
    let flat = CpuEngine::new().compute(&atoms, &p).expect("surface");
    eprintln!(
        "adk protein H 0.5: periodic {:.1} Å² {:.1} Å³, non-periodic {:.1} Å² {:.1} Å³",
        periodic.area, periodic.volume, flat.area, flat.volume
    );
    assert!(
        rel(periodic.area, flat.area) < 0.015,
        "{} vs {}",
        periodic.area,
        flat.area
    );
    assert!(
        rel(periodic.volume, flat.volume) < 0.005,
        "{} vs {}",
        periodic.volume,
        flat.volume
    );
    // Split across the faces, so open there and only there.
    assert!(open_only_on_faces(&periodic.mesh, &cell, [1.0; 3]) > 0);
}

#[test]
fn triclinic_colours_are_normalised_and_large_grids_refused() {
    let cell = TriclinicCell::new(octahedron(20.0)).expect("cell");
    let (pos, radii) = liquid(&cell, 60, 13);
    let colour = [0.2, 0.4, 0.6];
    let colours = vec![colour; pos.len()];
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: Some(&colours),
    };
    let p = params(0.7, 1.0);
    let out = PeriodicEngine::new()
        .compute_triclinic(&atoms, &p, &cell, Replicate([1, 2, 1]))
        .expect("surface");
    assert!(out.mesh.vertex_count() > 100);
    for c in &out.mesh.colours {
        for k in 0..3 {
            assert!((c[k] - colour[k]).abs() < 1e-3, "{c:?}");
        }
    }
    let err = PeriodicEngine::with_memory_limit(10_000)
        .compute_triclinic(&atoms, &p, &cell, Replicate::default())
        .unwrap_err()
        .to_string();
    assert!(!err.contains('\n') && !err.is_empty(), "{err}");
    let bad = PeriodicEngine::new().compute_triclinic(&atoms, &p, &cell, Replicate([0, 1, 1]));
    assert!(bad.is_err());
}
