//! Per-frame transformations (issue 11 §1): make whole, centre, fit and smooth, through the
//! library and through `mdsurf surface`/`render`.

use std::path::Path;

use glam::{Quat, Vec3};
use mdsurf::model::{Frame, Topology};
use mdsurf::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceParams};
use mdsurf::transform::{TransformChain, TransformOptions, TransformedFrames};

use crate::cli_common::{Csv, mdsurf};
use crate::data_support::data;

/// adk_open.pdb: its topology and first frame.
fn adk() -> (Topology, Frame) {
    let t = mdsurf::io::open(&data("adk_open.pdb"), None).expect("open adk_open.pdb");
    let f = t.read_frame(0).expect("frame 0");
    (t.topology().clone(), f)
}

/// Area (Å²) and volume (Å³) of the surface of all atoms.
fn area_volume(positions: &[Vec3], radii: &[f32]) -> (f64, f64) {
    let atoms = AtomSet {
        positions,
        radii,
        colours: None,
    };
    let out = CpuEngine::new()
        .compute(&atoms, &SurfaceParams::default())
        .expect("surface");
    (out.area, out.volume)
}

/// `positions` put in a cubic box of side `l` so that their centre lies on the box face x = 0,
/// and the atoms wrapped into the box one by one (as an MD engine writes them). Returns the
/// unwrapped (shifted) and the wrapped positions.
fn across_a_face(positions: &[Vec3], l: f32) -> (Vec<Vec3>, Vec<Vec3>) {
    let centre = positions.iter().copied().sum::<Vec3>() / positions.len() as f32;
    let shift = Vec3::new(0.0, l / 2.0, l / 2.0) - centre;
    let unwrapped: Vec<Vec3> = positions.iter().map(|&p| p + shift).collect();
    let wrapped = unwrapped.iter().map(|&p| p - (p / l).floor() * l).collect();
    (unwrapped, wrapped)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn whole_joins_a_protein_wrapped_across_a_box_face() {
    let (topology, frame) = adk();
    let l = 90.0;
    let (unwrapped, wrapped) = across_a_face(&frame.positions, l);
    assert!(
        wrapped.iter().zip(&unwrapped).any(|(a, b)| a != b),
        "the protein must be split by the box"
    );
    let cell = Some([Vec3::X * l, Vec3::Y * l, Vec3::Z * l]);
    let mut split = Frame {
        positions: wrapped.clone(),
        cell,
        ..Frame::default()
    };
    let options = TransformOptions {
        whole: Some(true),
        ..TransformOptions::default()
    };
    let chain = TransformChain::new(&options, &topology, &split, None, "adk").expect("chain");
    chain.apply(&mut split).expect("whole");

    let (a0, v0) = area_volume(&unwrapped, &topology.radii);
    let (a1, v1) = area_volume(&split.positions, &topology.radii);
    let (a2, v2) = area_volume(&wrapped, &topology.radii);
    assert!(rel(a1, a0) < 1e-3, "whole: area {a1} vs {a0}");
    assert!(rel(v1, v0) < 1e-3, "whole: volume {v1} vs {v0}");
    assert!(
        rel(a2, a0) > 1e-2,
        "wrapped: area {a2} should differ from {a0}"
    );
    assert!(
        rel(v2, v0) > 1e-3,
        "wrapped: volume {v2} should differ from {v0}"
    );
    // Whole moves atoms by whole box vectors: the molecule is the original up to one shift.
    let d = split.positions[0] - unwrapped[0];
    for (a, b) in split.positions.iter().zip(&unwrapped) {
        assert!((*a - *b - d).length() < 1e-3, "{a} {b}");
    }
}

/// Writes `positions` of adk_open.pdb with a cubic box of side `l` to `path` (chemfiles).
fn write_adk(path: &Path, positions: &[Vec3], l: f64) {
    let mut traj = chemfiles::Trajectory::open(data("adk_open.pdb"), 'r').expect("read");
    let mut frame = chemfiles::Frame::new();
    traj.read(&mut frame).expect("frame");
    for (p, q) in frame.positions_mut().iter_mut().zip(positions) {
        *p = [q.x as f64, q.y as f64, q.z as f64];
    }
    frame.set_cell(&chemfiles::UnitCell::new([l; 3]));
    let mut out = chemfiles::Trajectory::open(path, 'w').expect("write");
    out.write(&frame).expect("write frame");
}

fn surface_stats(dir: &Path, file: &str, extra: &[&str]) -> (f64, f64) {
    let mut args = vec![
        "surface",
        file,
        "--backend",
        "cpu",
        "--stats",
        "s.csv",
        "-q",
    ];
    args.extend_from_slice(extra);
    let run = mdsurf(dir, &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.join("s.csv"));
    (csv.col("area_A2")[0], csv.col("volume_A3")[0])
}

#[test]
fn cli_whole_matches_the_unwrapped_protein_and_no_whole_does_not() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, frame) = adk();
    let l = 90.0;
    let (unwrapped, wrapped) = across_a_face(&frame.positions, l);
    // The reference: the same protein inside the box (shifted by half a box along x).
    let inside: Vec<Vec3> = unwrapped.iter().map(|&p| p + Vec3::X * l / 2.0).collect();
    write_adk(&dir.path().join("inside.pdb"), &inside, l as f64);
    write_adk(&dir.path().join("split.pdb"), &wrapped, l as f64);
    let (a0, v0) = surface_stats(dir.path(), "inside.pdb", &["--no-whole"]);
    let (a1, v1) = surface_stats(dir.path(), "split.pdb", &["--whole"]);
    let (ad, vd) = surface_stats(dir.path(), "split.pdb", &[]);
    let (a2, v2) = surface_stats(dir.path(), "split.pdb", &["--no-whole"]);
    assert!(
        rel(a1, a0) < 1e-3 && rel(v1, v0) < 1e-3,
        "--whole: {a1} {v1} vs {a0} {v0}"
    );
    assert!(
        rel(ad, a0) < 1e-3 && rel(vd, v0) < 1e-3,
        "default: {ad} {vd} vs {a0} {v0}"
    );
    assert!(
        rel(a2, a0) > 1e-2,
        "--no-whole: area {a2} should differ from {a0}"
    );
    assert!(
        rel(v2, v0) > 1e-3,
        "--no-whole: volume {v2} should differ from {v0}"
    );
}

#[test]
fn fit_undoes_a_rigid_rotation_and_translation() {
    let (topology, first) = adk();
    let frames: Vec<Frame> = (0..10)
        .map(|i| {
            let axis = Vec3::new(0.3, 1.0, -0.6 + 0.1 * i as f32).normalize();
            let rot = Quat::from_axis_angle(axis, 0.37 * i as f32);
            let shift = Vec3::new(3.0 * i as f32, -2.0 * i as f32, 1.5 * i as f32);
            Frame {
                index: i,
                positions: first.positions.iter().map(|&p| rot * p + shift).collect(),
                ..first.clone()
            }
        })
        .collect();
    let options = TransformOptions {
        whole: Some(false),
        fit: Some("protein and name CA".into()),
        ..TransformOptions::default()
    };
    let chain = TransformChain::new(&options, &topology, &frames[0], None, "adk").expect("chain");
    let mut reader = TransformedFrames::new(chain, frames.len());
    for i in 0..frames.len() {
        let f = reader
            .read(i, |j| {
                Ok::<_, mdsurf::transform::TransformError>(frames[j].clone())
            })
            .expect("fit");
        let worst = f
            .positions
            .iter()
            .zip(&first.positions)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "frame {i}: {worst} Å from the first frame");
    }
}

/// A synthetic trajectory: atom `a` of frame `f` at (f², a + f, 7).
fn quadratic_frames(n: usize, atoms: usize) -> Vec<Frame> {
    (0..n)
        .map(|f| Frame {
            index: f,
            time_ps: Some(f as f64),
            positions: (0..atoms)
                .map(|a| Vec3::new((f * f) as f32, (a + f) as f32, 7.0))
                .collect(),
            cell: None,
        })
        .collect()
}

#[test]
fn smoothing_averages_the_window_and_uses_the_frames_that_exist_at_the_ends() {
    let (n, atoms, k) = (9usize, 5usize, 2usize);
    let frames = quadratic_frames(n, atoms);
    let topology = Topology {
        names: mdsurf::model::Labels::filled("C", atoms),
        ..Topology::default()
    };
    let options = TransformOptions {
        smooth: k,
        ..TransformOptions::default()
    };
    let chain =
        TransformChain::new(&options, &topology, &frames[0], None, "synthetic").expect("chain");
    let read = |reader: &mut TransformedFrames, i: usize| {
        reader
            .read(i, |j| {
                Ok::<_, mdsurf::transform::TransformError>(frames[j].clone())
            })
            .expect("smooth")
    };
    let mut forward = TransformedFrames::new(chain.clone(), n);
    let played: Vec<Frame> = (0..n).map(|i| read(&mut forward, i)).collect();
    for (i, f) in played.iter().enumerate() {
        let lo = i.saturating_sub(k);
        let hi = (i + k).min(n - 1);
        let count = (hi - lo + 1) as f32;
        let mean_f = (lo..=hi).map(|j| j as f32).sum::<f32>() / count;
        let mean_f2 = (lo..=hi).map(|j| (j * j) as f32).sum::<f32>() / count;
        for (a, p) in f.positions.iter().enumerate() {
            let want = Vec3::new(mean_f2, a as f32 + mean_f, 7.0);
            assert!(
                (*p - want).length() < 1e-4,
                "frame {i} atom {a}: {p} vs {want}"
            );
        }
        assert_eq!(f.index, i);
        assert_eq!(f.time_ps, Some(i as f64));
    }
    // Scrubbing (any order, fresh or warm cache) gives what playing gave.
    let mut scrub = TransformedFrames::new(chain, n);
    for i in [8, 0, 4, 7, 1, 4, 3] {
        assert_eq!(read(&mut scrub, i), played[i], "frame {i}");
    }
}

#[test]
fn cli_smooth_and_center_run_on_a_gromacs_trajectory() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gro = data("adk_oplsaa.gro").display().to_string();
    let xtc = data("adk_oplsaa.xtc").display().to_string();
    let (gro, xtc) = (gro.as_str(), xtc.as_str());
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            gro,
            xtc,
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--frames",
            "0:3",
            "--center",
            "protein",
            "--fit",
            "protein and name CA",
            "--smooth",
            "1",
            "--stats",
            "s.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains("transforms: whole") && run.stderr.contains("smooth ±1"),
        "{}",
        run.stderr
    );
    let csv = Csv::read(&dir.path().join("s.csv"));
    assert_eq!(csv.rows.len(), 3);
}

#[test]
fn box_requiring_transforms_on_a_file_without_a_box_fail_in_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (_, frame) = adk();
    let mut f = chemfiles::Frame::new();
    for p in frame.positions.iter().take(50) {
        f.add_atom(
            &chemfiles::Atom::new("C"),
            [p.x as f64, p.y as f64, p.z as f64],
            None,
        );
    }
    let path = dir.path().join("nobox.xyz");
    chemfiles::Trajectory::open(&path, 'w')
        .expect("xyz")
        .write(&f)
        .expect("write");
    for flags in [&["--whole"][..], &["--center", "all"][..]] {
        let mut args = vec!["surface", "nobox.xyz", "--backend", "cpu"];
        args.extend_from_slice(flags);
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 2, "{flags:?}: {}", run.stderr);
        assert_eq!(run.stderr.lines().count(), 1, "{flags:?}: {}", run.stderr);
        assert!(
            run.stderr.contains("nobox.xyz") && run.stderr.contains("needs a periodic box"),
            "{flags:?}: {}",
            run.stderr
        );
    }
    // Without a flag the default (whole when there is a box) just stays off.
    let run = mdsurf(
        dir.path(),
        &["surface", "nobox.xyz", "--backend", "cpu", "-q"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
}

#[test]
fn fit_or_center_selections_that_match_nothing_fail_in_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gro = data("adk_oplsaa.gro").display().to_string();
    let gro = gro.as_str();
    for (flag, sel) in [("--fit", "resname XYZ"), ("--center", "name QQQ")] {
        let run = mdsurf(
            dir.path(),
            &["surface", gro, "--backend", "cpu", flag, sel, "-q"],
        );
        assert_eq!(run.code, 2, "{flag}: {}", run.stderr);
        assert_eq!(run.stderr.lines().count(), 1, "{flag}: {}", run.stderr);
        assert!(
            run.stderr.contains(flag) && run.stderr.contains("matches no atom"),
            "{flag}: {}",
            run.stderr
        );
    }
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            gro,
            "--backend",
            "cpu",
            "--fit",
            "resnam ALA",
            "-q",
        ],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(run.stderr.lines().count(), 1, "{}", run.stderr);
    assert!(run.stderr.contains("--fit 'resnam ALA'"), "{}", run.stderr);
}
