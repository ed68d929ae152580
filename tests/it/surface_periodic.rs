//! Periodic density (issue 11 §2): surfaces of atoms in a periodic box with no walls at the
//! faces, area and volume per box invariant under shifting and wrapping the atoms, replicated
//! images, and the command line's `--periodic` / `--replicate` with their one-line errors.
//! Triclinic cells: [`triclinic`].

mod triclinic;

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::Path;

use glam::Vec3;
use mdsurf::model::Frame;
use mdsurf::scene::state_file::{StateFile, StateFileError};
use mdsurf::surface::periodic::density::PeriodicGrid;
use mdsurf::surface::periodic::measure::box_volume;
use mdsurf::surface::periodic::{PeriodicBox, PeriodicCell, PeriodicEngine, Replicate};
use mdsurf::surface::{AtomSet, CpuEngine, Mesh, SurfaceEngine, SurfaceOutput, SurfaceParams};

use crate::cli_common::{Csv, Run, mdsurf};
use crate::data_support::data;
use crate::surface_common::sphere_radius;

pub(crate) const ARGON: &str = "argon_npt_compressed.tng";
const WATER: &str = "spce_all_coords.lammpstrj.bz2";
pub(crate) const BILAYER: &str = "martini_dppc_chol_bilayer.gro";

/// Radii from the topology, the first frame and its box.
pub(crate) fn load(name: &str) -> (Vec<f32>, Frame, PeriodicBox) {
    let t = mdsurf::io::open(&data(name), None).unwrap_or_else(|e| panic!("open {name}: {e}"));
    let f = t.read_frame(0).expect("frame 0");
    let cell = f.cell.expect("the file has a box");
    let pbox = PeriodicBox::from_cell(&cell).expect("a rectangular box");
    (t.topology().radii.clone(), f, pbox)
}

pub(crate) fn params(spacing: f32, radius_scale: f32) -> SurfaceParams {
    SurfaceParams {
        spacing,
        radius_scale,
        ..SurfaceParams::default()
    }
}

fn periodic_with(
    engine: &mut PeriodicEngine,
    positions: &[Vec3],
    radii: &[f32],
    params: &SurfaceParams,
    pbox: &PeriodicBox,
    replicate: Replicate,
) -> SurfaceOutput {
    let atoms = AtomSet {
        positions,
        radii,
        colours: None,
    };
    engine
        .compute(&atoms, params, pbox, replicate)
        .expect("periodic surface")
}

fn periodic(
    positions: &[Vec3],
    radii: &[f32],
    params: &SurfaceParams,
    pbox: &PeriodicBox,
) -> SurfaceOutput {
    let mut engine = PeriodicEngine::new();
    periodic_with(
        &mut engine,
        positions,
        radii,
        params,
        pbox,
        Replicate::default(),
    )
}

/// `positions` moved by `shift` (Å) and wrapped into the box `[0, L)`.
pub(crate) fn shifted(positions: &[Vec3], shift: Vec3, l: Vec3) -> Vec<Vec3> {
    positions
        .iter()
        .map(|&p| {
            let q = p + shift;
            q - (q / l).floor() * l
        })
        .collect()
}

/// A few shifts that are not lattice vectors, including one of about half the box.
fn shifts(l: Vec3) -> [Vec3; 3] {
    [
        Vec3::new(3.71, -1.29, 11.13),
        l * Vec3::new(0.31, 0.77, 0.53),
        l * 0.5 + Vec3::new(0.123, 0.456, 0.789),
    ]
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The largest relative change of area and of volume over [`shifts`], and the unshifted
/// surface.
fn shift_spread(name: &str, p: &SurfaceParams) -> (f64, f64, SurfaceOutput) {
    let (radii, frame, pbox) = load(name);
    let base = periodic(&frame.positions, &radii, p, &pbox);
    let (mut da, mut dv) = (0.0f64, 0.0f64);
    for s in shifts(pbox.lengths) {
        let moved = shifted(&frame.positions, s, pbox.lengths);
        let out = periodic(&moved, &radii, p, &pbox);
        da = da.max(rel(out.area, base.area));
        dv = dv.max(rel(out.volume, base.volume));
    }
    (da, dv, base)
}

#[test]
fn liquids_area_and_volume_per_box_do_not_depend_on_where_the_box_is_cut() {
    // With R = 0.6 the atoms of a dense liquid are distinct blobs with a large surface; at the
    // default R = 1 the liquid fills the box and the surface is a few small cavities, whose
    // sampled area depends on the grid offset by several percent (a sampling effect, not a
    // seam), so there only the volume is compared.
    for name in [ARGON, WATER] {
        let (da, dv, base) = shift_spread(name, &params(0.5, 0.6));
        let (_, _, pbox) = load(name);
        let box_volume = pbox.lengths.x as f64 * pbox.lengths.y as f64 * pbox.lengths.z as f64;
        assert!(base.area > 5000.0, "{name}: area {}", base.area);
        assert!(base.volume > 0.05 * box_volume, "{name}: {}", base.volume);
        assert!(da < 1e-3, "{name}: area changes by {da:.2e} under a shift");
        assert!(
            dv < 1e-3,
            "{name}: volume changes by {dv:.2e} under a shift"
        );

        let (_, dv, base) = shift_spread(name, &params(1.0, 1.0));
        assert!(base.volume > 0.5 * box_volume, "{name}: {}", base.volume);
        assert!(dv < 1e-3, "{name} (R 1): volume changes by {dv:.2e}");
    }
}

#[test]
fn bilayer_area_and_volume_per_box_do_not_depend_on_where_the_box_is_cut() {
    let p = SurfaceParams::default();
    let (da, dv, base) = shift_spread(BILAYER, &p);
    assert!(da < 1e-3, "area changes by {da:.2e} under a shift");
    assert!(dv < 1e-3, "volume changes by {dv:.2e} under a shift");
    // The same shifts move the walls of the non-periodic surface, so this test can fail.
    let (radii, frame, pbox) = load(BILAYER);
    let area = |pos: &[Vec3]| {
        let atoms = AtomSet {
            positions: pos,
            radii: &radii,
            colours: None,
        };
        CpuEngine::new().compute(&atoms, &p).expect("surface").area
    };
    let a0 = area(&frame.positions);
    let worst = shifts(pbox.lengths)
        .iter()
        .map(|&s| rel(area(&shifted(&frame.positions, s, pbox.lengths)), a0))
        .fold(0.0, f64::max);
    assert!(
        worst > 0.01,
        "non-periodic area changed by only {worst:.2e}"
    );
    assert!(base.area < a0, "{} vs {a0}", base.area);
}

/// Local coordinates of `p` in the box: the face planes are 0 and `l`.
fn on_face(p: f32, l: f32, tol: f32) -> bool {
    p.abs() <= tol || (p - l).abs() <= tol
}

#[test]
fn bilayer_has_no_walls_and_is_open_only_at_the_faces() {
    let (radii, frame, pbox) = load(BILAYER);
    let p = SurfaceParams::default();
    let out = periodic(&frame.positions, &radii, &p, &pbox);
    let atoms = AtomSet {
        positions: &frame.positions,
        radii: &radii,
        colours: None,
    };
    let walled = CpuEngine::new().compute(&atoms, &p).expect("surface");
    // A 114 x 114 Å patch: the two leaflets' surfaces, far less than with the four walls.
    let l = pbox.lengths;
    let patch = 2.0 * l.x as f64 * l.y as f64;
    assert!(
        out.area > 0.8 * patch && out.area < 2.0 * patch,
        "{}",
        out.area
    );
    assert!(
        out.area < 0.75 * walled.area,
        "periodic {} vs non-periodic {}",
        out.area,
        walled.area
    );
    // No triangle lies along a box face facing across it.
    let mesh = &out.mesh;
    let mut wall = 0.0f64;
    for t in mesh.indices.chunks_exact(3) {
        let v = [0, 1, 2].map(|k| mesh.positions[t[k] as usize] - pbox.origin);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        for u in 0..3 {
            if v.iter().all(|q| on_face(q[u], l[u], 1.5)) && n[u].abs() > 0.9 * n.length() {
                wall += 0.5 * n.length() as f64;
            }
        }
    }
    // Walls on the four side faces would be about 4 x 114 x 40 Å², 40 % of the area; what is
    // left is the membrane's own roughness where it happens to face along x or y.
    assert!(wall < 0.01 * out.area, "{wall} Å² of wall");
    // Every mesh edge is used by two triangles, except edges on the box faces (used once).
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut open = 0;
    for (&(a, b), &n) in &uses {
        assert!(n <= 2, "edge used {n} times");
        if n == 1 {
            open += 1;
            let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            let face = (0..3).any(|u| on_face(pa[u], l[u], 1e-3) && on_face(pb[u], l[u], 1e-3));
            assert!(face, "open edge {pa} {pb} not on a box face");
        }
    }
    assert!(open > 0, "the bilayer crosses the box faces");
}

/// The volume of an atom's sphere and its area, for one atom placed at `at` in a cubic box.
fn one_atom(at: Vec3, side: f32, p: &SurfaceParams) -> SurfaceOutput {
    let pbox = PeriodicBox::new(Vec3::splat(side)).expect("box");
    periodic(&[at], &[1.5], p, &pbox)
}

#[test]
fn an_atom_on_a_box_corner_is_one_whole_sphere() {
    // Side 16 Å, H 0.25 Å: 64 samples per axis, so the corner and the centre are both sample
    // points and the two surfaces are sampled identically.
    let p = params(0.25, 1.0);
    let centre = one_atom(Vec3::splat(8.0), 16.0, &p);
    for at in [
        Vec3::ZERO,
        Vec3::new(16.0, 8.0, 0.0),
        Vec3::new(-16.0, 24.0, 8.0),
    ] {
        let split = one_atom(at, 16.0, &p);
        assert!(
            rel(split.area, centre.area) < 1e-5,
            "{at}: area {}",
            split.area
        );
        assert!(
            rel(split.volume, centre.volume) < 1e-5,
            "{at}: {}",
            split.volume
        );
    }
    // And that sphere is the analytic one (DESIGN §2: linear interpolation puts vertices
    // slightly inside, about -1.2 % area at H = alpha / 4).
    let r = sphere_radius(1.5, p.isovalue);
    let (area, volume) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r * r * r);
    assert!(rel(centre.area, area) < 0.02, "{} vs {area}", centre.area);
    assert!(
        rel(centre.volume, volume) < 0.03,
        "{} vs {volume}",
        centre.volume
    );
    // Off the sample points too: a corner atom matches the non-periodic engine's sphere.
    let off = one_atom(Vec3::new(0.1, 15.93, 0.07), 16.0, &p);
    assert!(rel(off.area, area) < 0.02, "{} vs {area}", off.area);
    assert!(rel(off.volume, volume) < 0.03, "{} vs {volume}", off.volume);
}

#[test]
fn the_per_box_volume_is_the_same_along_every_axis_and_matches_the_inside_samples() {
    let (radii, frame, pbox) = load(BILAYER);
    let p = SurfaceParams::default();
    let mut engine = PeriodicEngine::new();
    let out = periodic_with(
        &mut engine,
        &frame.positions,
        &radii,
        &p,
        &pbox,
        Replicate::default(),
    );
    let grid = PeriodicGrid::new(&pbox, pbox.samples(p.spacing));
    let values = &engine.last_volume().values;
    let local = Mesh {
        positions: out
            .mesh
            .positions
            .iter()
            .map(|&q| q - pbox.origin)
            .collect(),
        ..out.mesh.clone()
    };
    let v: Vec<f64> = (0..3)
        .map(|u| box_volume(&local, &grid, values, p.isovalue, u))
        .collect();
    for u in 1..3 {
        assert!(rel(v[u], v[0]) < 1e-6, "axis {u}: {} vs {}", v[u], v[0]);
    }
    assert!(rel(out.volume, v[0]) < 1e-9);
    let inside = values.iter().filter(|&&x| x >= p.isovalue).count();
    let cell = pbox.lengths.x as f64 * pbox.lengths.y as f64 * pbox.lengths.z as f64;
    let estimate = cell * inside as f64 / values.len() as f64;
    assert!(rel(v[0], estimate) < 0.02, "{} vs {estimate}", v[0]);
}

#[test]
fn replicate_gives_that_many_seamless_copies() {
    let (radii, frame, pbox) = load(ARGON);
    let p = params(1.0, 0.8);
    let mut engine = PeriodicEngine::new();
    let one = periodic_with(
        &mut engine,
        &frame.positions,
        &radii,
        &p,
        &pbox,
        Replicate::default(),
    );
    let four = periodic_with(
        &mut engine,
        &frame.positions,
        &radii,
        &p,
        &pbox,
        Replicate([2, 1, 2]),
    );
    assert!(one.mesh.triangle_count() > 1000);
    assert_eq!(four.mesh.triangle_count(), 4 * one.mesh.triangle_count());
    assert_eq!(four.mesh.vertex_count(), 4 * one.mesh.vertex_count());
    assert!(rel(four.area, 4.0 * one.area) < 1e-9);
    assert!(rel(four.mesh.area(), 4.0 * one.mesh.area()) < 1e-6);
    assert!(rel(four.volume, 4.0 * one.volume) < 1e-9);
    let (lo, hi) = four.mesh.bounds().expect("mesh");
    let l = pbox.lengths;
    let want = Vec3::new(2.0 * l.x, l.y, 2.0 * l.z);
    assert!(
        (hi - lo - want).abs().max_element() < 0.05 * l.max_element(),
        "{lo} {hi}"
    );
    // Where two copies meet (x = L), each vertex of the first has a twin in the second with
    // the same normal and colour: no seam.
    let n = one.mesh.vertex_count();
    let key = |q: Vec3| (q * 1e3).round().as_ivec3().to_array();
    let second: HashMap<[i32; 3], usize> = (n..2 * n)
        .map(|i| (key(four.mesh.positions[i]), i))
        .collect();
    let x_face = pbox.origin.x + l.x;
    let mut matched = 0;
    for i in 0..n {
        let q = four.mesh.positions[i];
        if (q.x - x_face).abs() > 1e-3 {
            continue;
        }
        let j = *second
            .get(&key(q))
            .unwrap_or_else(|| panic!("no twin for the face vertex {q}"));
        assert!((four.mesh.normals[i] - four.mesh.normals[j]).length() < 1e-5);
        matched += 1;
    }
    assert!(matched > 10, "{matched} vertices on the shared face");
}

#[test]
fn triclinic_cells_are_accepted_and_tiny_boxes_refused_with_one_line() {
    let rows = [
        Vec3::new(50.0, 0.0, 0.0),
        Vec3::new(10.0, 45.0, 0.0),
        Vec3::new(5.0, 8.0, 40.0),
    ];
    // Only the rectangular box type refuses it; --periodic takes it as a triclinic cell.
    let err = PeriodicBox::from_cell(&rows).unwrap_err().to_string();
    assert!(err.contains("triclinic") && !err.contains('\n'), "{err}");
    assert!(matches!(
        PeriodicCell::from_cell(&rows),
        Ok(PeriodicCell::Triclinic(_))
    ));
    let err = PeriodicBox::new(Vec3::new(1.0, 50.0, 50.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("1.000") && !err.contains('\n'), "{err}");
    for bad in ["0,1,1", "a,b", "2,2", "2,2,1,1", "17,1,1", "-1,1,1", ""] {
        assert!(bad.parse::<Replicate>().is_err(), "{bad}");
    }
    assert_eq!("2,3,1".parse::<Replicate>(), Ok(Replicate([2, 3, 1])));
}

#[test]
fn state_files_record_periodic_and_old_ones_still_load() {
    let old = "version = 1\n\n[trajectory]\nframe = 3\nstride = 1\nfps = 24.0\n";
    let state = StateFile::parse(old, "old.toml").expect("old state file");
    assert!(!state.trajectory.periodic);
    assert!(!state.trajectory.transforms().periodic);
    let mut state = StateFile::new(Vec::new());
    let mut options = state.trajectory.transforms();
    options.periodic = true;
    options.replicate = Replicate([2, 2, 1]);
    state.trajectory.set_transforms(&options);
    let text = state.to_toml();
    let back = StateFile::parse(&text, "new.toml").expect("round trip");
    assert_eq!(back.trajectory.transforms(), options);
    let bad = "version = 1\n\n[trajectory]\nperiodic = true\nreplicate = [0, 1, 1]\n";
    let err = StateFile::parse(bad, "bad.toml").unwrap_err();
    assert!(
        matches!(&err, StateFileError::Replicate { source, .. } if source.0 == Replicate([0, 1, 1])),
        "{err:?}"
    );
    let err = err.to_string();
    assert!(err.contains("bad.toml") && err.contains("replicate") && !err.contains('\n'));
}

/// Runs `mdsurf surface ARGS` and expects a failure with one `error:` line containing every
/// word of `must_name`.
fn fails(dir: &Path, args: &[&str], must_name: &[&str]) -> Run {
    let mut all = vec!["surface"];
    all.extend_from_slice(args);
    let run = mdsurf(dir, &all);
    assert_eq!(run.code, 2, "{args:?}: status {}\n{}", run.code, run.stderr);
    assert!(!run.stderr.contains("panicked"), "{}", run.stderr);
    let errors: Vec<&str> = run
        .stderr
        .lines()
        .filter(|l| !l.starts_with("rep ") && !l.trim().is_empty())
        .collect();
    assert_eq!(errors.len(), 1, "{args:?}: {}", run.stderr);
    assert!(errors[0].starts_with("error: "), "{}", errors[0]);
    for word in must_name {
        assert!(
            errors[0].contains(word),
            "{args:?}: '{word}' not in {}",
            errors[0]
        );
    }
    run
}

#[test]
fn cli_periodic_errors_are_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    // A PDB without CRYST1 has no box.
    let pdb = "ATOM      1  C   ALA A   1       1.000   2.000   3.000  1.00  0.00           C\n\
               ATOM      2  C   ALA A   1       2.500   2.000   3.000  1.00  0.00           C\nEND\n";
    std::fs::write(d.join("nobox.pdb"), pdb).expect("write");
    fails(
        d,
        &["nobox.pdb", "--periodic"],
        &["nobox.pdb", "--periodic", "box"],
    );
    fails(
        d,
        &["nobox.pdb", "--replicate", "2,2,1"],
        &["nobox.pdb", "--periodic"],
    );
    let flat = "CRYST1    1.000    1.000    1.000  90.00  90.00  90.00 P 1           1\n";
    std::fs::write(d.join("flat.pdb"), format!("{flat}{pdb}")).expect("write");
    fails(d, &["flat.pdb", "--periodic"], &["flat.pdb", "--periodic"]);
    let bilayer = data(BILAYER);
    let bilayer = bilayer.to_string_lossy();
    for bad in ["0,1,1", "a,b", "2,2", "1,1,99"] {
        fails(d, &[&bilayer, "--replicate", bad], &["--replicate", bad]);
    }
    fails(
        d,
        &[&bilayer, "--periodic", "--fit", "all"],
        &["--periodic", "--fit"],
    );
}

#[test]
fn cli_periodic_surface_per_box_and_replicated() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let bilayer = data(BILAYER);
    let bilayer = bilayer.to_string_lossy();
    let stats = |extra: &[&str], name: &str| {
        let mut args = vec!["surface", &*bilayer, "--stats", name, "--spacing", "2"];
        args.extend_from_slice(extra);
        let run = mdsurf(d, &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        (Csv::read(&d.join(name)), run)
    };
    let (flat, _) = stats(&["--backend", "cpu", "-q"], "flat.csv");
    let (one, run) = stats(&["--periodic", "--backend", "gpu"], "one.csv");
    // The GPU engine has no periodic path: a note says the CPU computes it (no GPU needed).
    let notes: Vec<&str> = run.stderr.lines().filter(|l| l.contains("note:")).collect();
    assert_eq!(notes.len(), 1, "{}", run.stderr);
    assert!(notes[0].contains("--periodic") && notes[0].contains("CPU"));
    let (four, run) = stats(
        &["--replicate", "2,2,1", "--backend", "gpu", "-q"],
        "four.csv",
    );
    assert!(run.stderr.trim().is_empty(), "-q: {}", run.stderr);
    let col = |c: &Csv, name: &str| c.col(name)[0];
    assert!(
        col(&one, "area_A2") < 0.75 * col(&flat, "area_A2"),
        "walls remain"
    );
    assert_eq!(
        col(&four, "triangles"),
        4.0 * col(&one, "triangles"),
        "replicated triangles"
    );
    assert!(rel(col(&four, "area_A2"), 4.0 * col(&one, "area_A2")) < 1e-6);
    assert!(rel(col(&four, "volume_A3"), 4.0 * col(&one, "volume_A3")) < 1e-6);
}

/// The area of the viewer worker's surface of every atom of `name` read with `transforms`.
fn worker_area(name: &str, transforms: &mdsurf::transform::TransformOptions) -> f64 {
    use mdsurf::app::worker::{Reply, Request, Worker};
    let source = mdsurf::app::source::open_files_with(&data(name), None, transforms)
        .unwrap_or_else(|e| panic!("{e}"));
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    worker.submit(Request::single(
        1,
        0,
        source,
        SurfaceParams::default(),
        mdsurf::model::ParticleOptions::default(),
    ));
    match worker.recv_timeout(std::time::Duration::from_secs(60)) {
        Some(Reply::Done(c)) => c.layers[0].output.area,
        Some(Reply::Failed { message, .. }) => panic!("{message}"),
        None => panic!("no reply in 60 s"),
    }
}

#[test]
fn the_viewer_worker_computes_periodic_surfaces_when_asked() {
    let mut options = mdsurf::transform::TransformOptions::default();
    let walled = worker_area(BILAYER, &options);
    options.periodic = true;
    let per_box = worker_area(BILAYER, &options);
    options.replicate = Replicate([1, 2, 1]);
    let two = worker_area(BILAYER, &options);
    let (radii, frame, pbox) = load(BILAYER);
    let direct = periodic(&frame.positions, &radii, &SurfaceParams::default(), &pbox);
    assert!(
        rel(per_box, direct.area) < 1e-6,
        "{per_box} vs {}",
        direct.area
    );
    assert!(per_box < 0.75 * walled, "{per_box} vs {walled}");
    assert!(rel(two, 2.0 * per_box) < 1e-9, "{two} vs {per_box}");
}

#[test]
fn the_trajectory_panel_toggles_periodic_surfaces() {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;
    use mdsurf::app::trajectory_panel::{TransformDraft, trajectory_ui};
    let state = (TransformDraft::new(Default::default()), false);
    let mut h = Harness::builder().with_size([500.0, 600.0]).build_ui_state(
        |ui, s: &mut (TransformDraft, bool)| {
            s.1 |= trajectory_ui(ui, &mut s.0);
        },
        state,
    );
    h.get_by_label("Trajectory").click();
    h.run();
    h.get_by_label("Periodic surface").click();
    h.run();
    assert!(!h.state().1, "no reload before Apply");
    h.get_by_label("Apply").click();
    h.run();
    let (draft, reload) = h.state();
    assert!(*reload, "Apply reloads");
    assert!(draft.applied().periodic);
    assert!(draft.applied().replicate.is_one());
}
