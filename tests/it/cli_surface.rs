//! `mdsurf surface` end to end on real data (the bundled demo and `tests/data`), on the CPU
//! engine: meshes in every format parse back and agree with the stats CSV, `{frame}` patterns
//! name one file per selected frame, and areas and volumes are physically sane.

use std::fs;

use crate::cli_common::{
    Csv, asset, data, mdsurf, mdsurf_env, read_ply_counts, read_stl, volume_of,
};

/// The columns issue 2 requires, in order, at the start of the CSV.
const REQUIRED: [&str; 12] = [
    "frame",
    "rep",
    "time_ps",
    "atoms",
    "nx",
    "ny",
    "nz",
    "vertices",
    "triangles",
    "area_A2",
    "volume_A3",
    "ms_total",
];

#[test]
fn demo_frames_give_ply_files_and_stats_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            &xtc,
            "--frames",
            "0:3",
            "--backend",
            "cpu",
            "-o",
            "surf_{frame}.ply",
            "--stats",
            "stats.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("stats.csv"));
    assert_eq!(&csv.columns[..REQUIRED.len()], REQUIRED);
    assert_eq!(csv.col("frame"), [0.0, 1.0, 2.0]);
    // The demo's default representation: the protein (5,419 of its 5,547 atoms; the retinal
    // ligand is drawn as ball-and-stick, not computed).
    assert!(csv.text_col("rep").iter().all(|r| r == "macromolecule"));
    assert!(csv.col("atoms").iter().all(|&a| a == 5419.0));
    let times = csv.col("time_ps");
    assert!(times[0] < times[1] && times[1] < times[2], "{times:?}");
    let (areas, volumes) = (csv.col("area_A2"), csv.col("volume_A3"));
    for (&a, &v) in areas.iter().zip(&volumes) {
        // A protein of 5,547 atoms (with H) encloses roughly 5 to 30 Å³ per atom...
        assert!((5.0 * 5547.0..30.0 * 5547.0).contains(&v), "volume {v}");
        // ...and no closed surface has less area than the sphere of the same volume.
        let sphere = (36.0 * std::f64::consts::PI * v * v).cbrt();
        assert!(
            a > sphere && a < 20.0 * sphere,
            "area {a} vs sphere {sphere}"
        );
    }
    // Consecutive frames of a short MD are similar but not identical.
    assert!(((volumes[1] - volumes[0]) / volumes[0]).abs() < 0.1);
    assert_ne!(areas[0], areas[1]);

    let (verts, tris) = (csv.col("vertices"), csv.col("triangles"));
    for f in 0..3 {
        let (v, t, _) = read_ply_counts(&dir.path().join(format!("surf_{f}.ply")));
        assert_eq!((v as f64, t as f64), (verts[f], tris[f]));
        // A closed triangle mesh of genus g has 2V - 4 + 4g = T: T is about 2V.
        assert!((t as f64 / v as f64 - 2.0).abs() < 0.05, "V {v}, T {t}");
    }
    assert!(!dir.path().join("surf_3.ply").exists());
    // stderr is a pipe here: no line per frame, the final summary line only.
    let frame_lines = |stderr: &str| stderr.lines().filter(|l| l.starts_with("frame")).count();
    assert_eq!(frame_lines(&run.stderr), 0, "{}", run.stderr);
    assert!(run.last_line().contains("3 frame(s)"), "{}", run.stderr);
    // With -v: one summary line per frame, then the final line.
    let verbose = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            &xtc,
            "--frames",
            "0:3",
            "--backend",
            "cpu",
            "-v",
        ],
    );
    assert_eq!(verbose.code, 0, "{}", verbose.stderr);
    assert_eq!(frame_lines(&verbose.stderr), 3, "{}", verbose.stderr);
    assert!(
        verbose.last_line().contains("3 frame(s)"),
        "{}",
        verbose.stderr
    );
}

#[test]
fn every_format_agrees_with_the_stats() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let mut volumes = Vec::new();
    for ext in ["ply", "obj", "stl", "glb"] {
        let out = format!("prot.{ext}");
        let stats = format!("{ext}.csv");
        let run = mdsurf(
            dir.path(),
            &[
                "surface",
                &pdb,
                "--backend",
                "cpu",
                "--spacing",
                "1.5",
                "--color",
                "chain",
                "-o",
                &out,
                "--stats",
                &stats,
            ],
        );
        assert_eq!(run.code, 0, "{ext}: {}", run.stderr);
        let csv = Csv::read(&dir.path().join(&stats));
        assert_eq!(csv.rows.len(), 1);
        let (v, t) = (
            csv.col("vertices")[0] as usize,
            csv.col("triangles")[0] as usize,
        );
        let path = dir.path().join(&out);
        match ext {
            "ply" => assert_eq!(read_ply_counts(&path), (v, t, read_ply_counts(&path).2)),
            "obj" => {
                let text = fs::read_to_string(&path).unwrap();
                let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
                assert_eq!((count("v "), count("vn "), count("f ")), (v, v, t));
            }
            "stl" => {
                let tris = read_stl(&path);
                assert_eq!(tris.len(), t);
                let vol = volume_of(&tris);
                let want = csv.col("volume_A3")[0];
                assert!(
                    ((vol - want) / want).abs() < 1e-4,
                    "STL {vol} vs CSV {want}"
                );
            }
            _ => {
                let b = fs::read(&path).unwrap();
                assert_eq!(&b[..4], b"glTF");
                let json_len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
                let root = gltf_json::Root::from_slice(&b[20..20 + json_len]).unwrap();
                assert_eq!(root.accessors[0].count.0 as usize, v);
                let idx = root.meshes[0].primitives[0].indices.unwrap();
                assert_eq!(root.accessors[idx.value()].count.0 as usize, 3 * t);
            }
        }
        volumes.push(csv.col("volume_A3")[0]);
    }
    // The same surface whatever the output format.
    assert!(volumes.windows(2).all(|w| w[0] == w[1]), "{volumes:?}");
}

#[test]
fn padded_frame_pattern_and_step_name_one_file_per_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, dcd) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &pdb,
            &dcd,
            "--frames",
            "0:6:2",
            "--backend",
            "cpu",
            "--spacing",
            "2",
            "-o",
            "adk_{frame:04}.stl",
            "--stats",
            "adk.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let mut names: Vec<String> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["adk.csv", "adk_0000.stl", "adk_0002.stl", "adk_0004.stl"]
    );
    let csv = Csv::read(&dir.path().join("adk.csv"));
    assert_eq!(csv.col("frame"), [0.0, 2.0, 4.0]);
    assert!(csv.col("atoms").iter().all(|&a| a == 3341.0));
}

#[test]
fn beads_cut_the_particle_count_and_keep_the_shape() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, dcd) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let mut volume = Vec::new();
    for beads in [false, true] {
        let mut args = vec![
            "surface",
            &pdb,
            &dcd,
            "--frames",
            "0",
            "--backend",
            "cpu",
            "--stats",
            "b.csv",
        ];
        if beads {
            args.push("--beads");
        }
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        let csv = Csv::read(&dir.path().join("b.csv"));
        let atoms = csv.col("atoms")[0];
        if beads {
            // adenylate kinase has 214 residues.
            assert!(atoms < 3341.0 / 8.0, "{atoms} beads");
        } else {
            assert_eq!(atoms, 3341.0);
        }
        volume.push(csv.col("volume_A3")[0]);
    }
    // Beads (radius = farthest atom + 1 Å) blur and inflate the surface, but it still
    // encloses the same protein: within a factor of three of the all-atom volume.
    let ratio = volume[1] / volume[0];
    assert!((0.8..3.0).contains(&ratio), "{volume:?}");
}

#[test]
fn radius_scale_and_isovalue_move_the_surface_the_right_way() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let vol = |extra: &[&str]| -> f64 {
        let mut args = vec!["surface", &pdb, "--backend", "cpu", "--spacing", "1.5"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--stats", "v.csv"]);
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        Csv::read(&dir.path().join("v.csv")).col("volume_A3")[0]
    };
    let base = vol(&[]);
    assert!(vol(&["--isovalue", "0.8"]) < base);
    assert!(vol(&["--radius-scale", "1.3"]) > base);
    assert!(
        vol(&[
            "--radius", "C=2.0", "--radius", "N=2.0", "--radius", "O=2.0"
        ]) > base
    );
}

/// `--backend auto` without any adapter (wgpu restricted to DX12, which Linux builds lack) falls
/// back to the CPU engine and says so; `--backend gpu` fails with one line instead.
#[cfg(target_os = "linux")]
#[test]
fn auto_backend_falls_back_to_the_cpu_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let no_gpu = [("WGPU_BACKEND", "dx12")];
    let auto = ["surface", &pdb, "--spacing", "2", "--backend", "auto"];
    let run = mdsurf_env(dir.path(), &auto, &no_gpu);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let line = run.stderr.lines().find(|l| l.starts_with("backend: "));
    assert!(
        line.is_some_and(|l| l.starts_with("backend: cpu (no usable GPU")),
        "{}",
        run.stderr
    );
    assert!(run.last_line().ends_with("on cpu"), "{}", run.stderr);

    let gpu = [
        "surface",
        &pdb,
        "--spacing",
        "2",
        "--backend",
        "gpu",
        "-o",
        "g.ply",
    ];
    let run = mdsurf_env(dir.path(), &gpu, &no_gpu);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(run.stderr.lines().count(), 1, "{}", run.stderr);
    assert!(
        run.stderr.starts_with("error: --backend gpu"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("g.ply").exists());
}

/// `--preset ses` places vertices as it was fitted (refined) and takes its radii unless
/// `--vertices` or `--radius` say otherwise: alone it reports the area of
/// `tests/data/ses_reference.csv`'s 1hpv row, `--vertices interpolated` changes the area but
/// not the triangles, and the element table's N radius (`--radius N=1.4`) another area.
#[test]
fn ses_preset_refines_vertices_unless_told_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let area_with = |extra: &[&str], stats: &str| {
        let mut args = vec!["--select", "protein", "--preset", "ses"];
        args.extend_from_slice(extra);
        let csv = surface_stats(dir.path(), &pdb, &args, stats);
        (csv.col("area_A2")[0], csv.col("triangles")[0])
    };
    let (preset, tris) = area_with(&[], "preset.csv");
    let (refined, tris_refined) = area_with(&["--vertices", "refined"], "refined.csv");
    let (interpolated, tris_lin) = area_with(&["--vertices", "interpolated"], "lin.csv");
    // The user's radius beats the preset's (0.922 Å for N).
    let (own_n, _) = area_with(&["--radius", "N=1.4"], "own_n.csv");
    assert!(
        (own_n - preset).abs() > 1e-3 * preset,
        "N=1.4: {own_n} vs the preset's {preset}"
    );
    assert_eq!(preset, refined, "the preset alone must refine");
    assert_eq!((tris, tris), (tris_refined, tris_lin));
    assert!(
        (preset - interpolated).abs() > 1e-3 * preset,
        "interpolated {interpolated} vs refined {preset}"
    );
    let table = fs::read_to_string(data("ses_reference.csv")).unwrap();
    let row = table
        .lines()
        .find(|l| l.starts_with("1hpv,"))
        .expect("1hpv row");
    let listed: f64 = row.split(',').nth(6).unwrap().parse().unwrap();
    assert!(
        (preset / listed - 1.0).abs() < 1e-3,
        "preset {preset} vs the table's {listed}"
    );
}

/// `--preset ses` at a spacing coarser than it holds at still computes, and says so in one
/// line on stderr; at its own spacings it says nothing.
#[test]
fn ses_preset_notes_a_too_coarse_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let run_at = |spacing: &str| {
        let stats = format!("h{spacing}.csv");
        let args = [
            "surface",
            &pdb,
            "--select",
            "protein and chain A",
            "--backend",
            "cpu",
            "--preset",
            "ses",
            "--spacing",
            spacing,
            "--stats",
            &stats,
        ];
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        assert!(dir.path().join(&stats).exists());
        run.stderr
    };
    let coarse = run_at("2");
    let notes: Vec<&str> = coarse
        .lines()
        .filter(|l| l.contains("too coarse"))
        .collect();
    assert_eq!(notes.len(), 1, "{coarse}");
    assert!(notes[0].contains("H = 2 Å"), "{coarse}");
    let fine = run_at("1");
    assert!(!fine.contains("too coarse"), "{fine}");
}

/// `--preset ses` gives a state file's representations its R, I, quality and radii as it gives
/// them to `--select` (before, they got only its vertices): the state's surface of chain A of
/// 1hpv has the area of `--select "chain A" --preset ses`, and not the one without the preset.
#[test]
fn a_preset_applies_to_the_state_files_representations() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("two.toml"),
        "version = 1\n\n[[representation]]\nname = \"a\"\nselection = \"protein and chain A\"\n\
         style = \"surface\"\n\n[[representation]]\nname = \"b\"\nselection = \"protein and chain B\"\n\
         style = \"surface\"\n",
    )
    .unwrap();
    let pdb = data("1hpv.pdb");
    let area_of = |args: &[&str], stats: &str, rep: &str| -> f64 {
        let csv = surface_stats(dir.path(), &pdb, args, stats);
        let reps = csv.text_col("rep");
        let at = reps.iter().position(|r| r == rep).expect("the row");
        csv.col("area_A2")[at]
    };
    let state_ses = area_of(
        &["--state", "two.toml", "--preset", "ses"],
        "state_ses.csv",
        "a",
    );
    let select_ses = area_of(
        &["--select", "protein and chain A", "--preset", "ses"],
        "select_ses.csv",
        "selection",
    );
    let state_plain = area_of(&["--state", "two.toml"], "state.csv", "a");
    assert!(
        (state_ses - select_ses).abs() <= 1e-9 * select_ses,
        "state {state_ses} vs select {select_ses} Å²"
    );
    assert!(
        (state_ses - state_plain).abs() > 0.01 * state_plain,
        "the preset changes the state's surface: {state_ses} vs {state_plain} Å²"
    );
}

/// `mdsurf surface INPUT --backend cpu -q --stats STATS ARGS...` run in `dir`, which must
/// succeed; its stats table.
fn surface_stats(dir: &std::path::Path, input: &str, args: &[&str], stats: &str) -> Csv {
    let mut all = vec!["surface", input, "--backend", "cpu", "-q", "--stats", stats];
    all.extend_from_slice(args);
    let run = mdsurf(dir, &all);
    assert_eq!(run.code, 0, "{all:?}: {}", run.stderr);
    Csv::read(&dir.join(stats))
}
