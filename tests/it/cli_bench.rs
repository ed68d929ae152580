//! `mdsurf bench` end to end on the CPU engine: the demo, a file given on the command line and a
//! synthetic tiled system each give one table row per engine with the right atom count, stage
//! medians that add up, and a CSV that matches the printed table. (Speed itself is reported by
//! the benchmark, never asserted here.)

use crate::cli_common::{Csv, bench_csv, data, mdsurf};

/// The data rows of the aligned text table: `(case, fields after it)`; the case is matched by
/// its known prefix since it may contain spaces.
fn table_rows<'a>(stdout: &'a str, case_prefix: &str) -> Vec<Vec<&'a str>> {
    stdout
        .lines()
        .filter(|l| l.starts_with(case_prefix))
        .map(|l| l.split_whitespace().collect())
        .collect()
}

#[test]
fn bench_on_the_demo_reports_stage_medians() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "bench",
        "--backend",
        "cpu",
        "--repeats",
        "3",
        "--warmup",
        "0",
        "--csv",
        "b.csv",
    ];
    let run = mdsurf(dir.path(), &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let header = run
        .stdout
        .lines()
        .find(|l| l.starts_with("case"))
        .expect("no table header");
    for col in ["read_ms", "bin_ms", "density_ms", "mc_ms", "frames_per_s"] {
        assert!(header.contains(col), "{header}");
    }
    let rows = table_rows(&run.stdout, "md_1u19.xtc");
    assert_eq!(rows.len(), 1, "{}", run.stdout);
    assert_eq!(rows[0][1], "cpu");
    assert_eq!(rows[0][2], "5547");

    let csv = Csv::read(&dir.path().join("b.csv"));
    assert_eq!(csv.rows.len(), 1);
    let (bin, dens, mc) = (
        csv.col("bin_ms")[0],
        csv.col("density_ms")[0],
        csv.col("mc_ms")[0],
    );
    let compute = csv.col("compute_ms")[0];
    assert!(bin >= 0.0 && dens > 0.0 && mc > 0.0, "{:?}", csv.rows[0]);
    // Medians of the parts cannot exceed much more than the median of the whole.
    assert!(bin + dens + mc <= 1.5 * compute + 1.0, "{:?}", csv.rows[0]);
    assert!(csv.col("frames_per_s")[0] > 0.0);
    assert!(csv.col("triangles")[0] > 10_000.0);
}

/// `bench` on adk (`pdb`, `dcd`) and a synthetic system of 12,000 atoms tiled from it, on the
/// CPU engine, 2 repeats at H = 2 Å.
fn adk_and_synthetic<'a>(pdb: &'a str, dcd: &'a str) -> Vec<&'a str> {
    vec![
        pdb,
        dcd,
        "--synthetic",
        "12k",
        "--backend",
        "cpu",
        "--repeats",
        "2",
        "--spacing",
        "2",
    ]
}

#[test]
fn bench_on_a_given_file_and_a_synthetic_system() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, dcd) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let csv = bench_csv(dir.path(), &adk_and_synthetic(&pdb, &dcd));
    assert_eq!(csv.rows.len(), 2, "{:?}", csv.rows);
    assert_eq!(csv.rows[0][0], "adk_dims.dcd");
    assert!(csv.rows[1][0].starts_with("synthetic 12000"));
    assert_eq!(csv.col("atoms"), [3341.0, 12000.0]);
    assert_eq!(csv.col("H_A"), [2.0, 2.0]);
    // About 3.6 tiled copies of the protein: several times the surface of one.
    let tris = csv.col("triangles");
    assert!(tris[1] > 2.5 * tris[0], "{tris:?}");
}

#[test]
fn bench_times_per_residue_areas_on_the_file_case_only() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, dcd) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let mut args = vec!["bench"];
    args.extend(adk_and_synthetic(&pdb, &dcd));
    args.extend(["--per-residue", "--csv", "b.csv"]);
    let run = mdsurf(dir.path(), &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("b.csv"));
    let k = csv
        .columns
        .iter()
        .position(|c| c == "per_residue_ms")
        .unwrap();
    let ms: f64 = csv.rows[0][k].parse().unwrap();
    assert!(ms > 0.0, "{:?}", csv.rows[0]);
    // A synthetic system has no residues: not timed.
    assert_eq!(csv.rows[1][k], "-");
    let line = run
        .stdout
        .lines()
        .find(|l| l.contains("per-residue areas cost"))
        .unwrap_or_else(|| panic!("no per-residue line: {}", run.stdout));
    assert!(line.starts_with("adk_dims.dcd on cpu"), "{line}");
    assert!(line.contains("% of the frame's compute"), "{line}");

    // Without the flag the column is there and empty; beads are refused in one line.
    let csv = bench_csv(dir.path(), &adk_and_synthetic(&pdb, &dcd));
    assert_eq!(csv.rows[0][k], "-");
    let run = mdsurf(
        dir.path(),
        &[
            "bench",
            &*pdb,
            "--backend",
            "cpu",
            "--beads",
            "--per-residue",
        ],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(run.stderr.contains("beads"), "{}", run.stderr);
    assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
    // Only synthetic systems: nothing to time, said in one line.
    let run = mdsurf(
        dir.path(),
        &[
            "bench",
            "--synthetic",
            "5k",
            "--backend",
            "cpu",
            "--per-residue",
        ],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(
        run.stderr.contains("needs a file's residues"),
        "{}",
        run.stderr
    );
    assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
}

#[test]
fn bench_rejects_bad_counts_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["0", "lots", "-5"] {
        let run = mdsurf(
            dir.path(),
            &["bench", "--backend", "cpu", "--synthetic", bad],
        );
        assert_eq!(run.code, 2, "{bad}: {}", run.stderr);
        assert_eq!(run.stderr.lines().count(), 1, "{}", run.stderr);
        assert!(run.stderr.contains(bad), "{}", run.stderr);
    }
}

#[test]
fn table1_needs_the_gpu_engine() {
    let dir = tempfile::tempdir().unwrap();
    let run = mdsurf(dir.path(), &["bench", "--table1", "--backend", "cpu"]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(run.stderr.lines().count(), 1, "{}", run.stderr);
    assert!(run.stderr.contains("--table1"), "{}", run.stderr);
}

#[test]
fn bench_times_periodic_surfaces_and_their_per_residue_areas() {
    let dir = tempfile::tempdir().unwrap();
    let bilayer = data("martini_dppc_chol_bilayer.gro");
    let args = [
        "bench",
        &*bilayer,
        "--backend",
        "cpu",
        "--periodic",
        "--per-residue",
        "--repeats",
        "1",
        "--warmup",
        "0",
        "--csv",
        "b.csv",
    ];
    let run = mdsurf(dir.path(), &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("b.csv"));
    assert_eq!(csv.rows.len(), 1, "{:?}", csv.rows);
    assert_eq!(csv.text_col("backend"), ["cpu periodic"]);
    // The cell's grid, ceil(L / H) samples per edge of the 114.03 x 114.03 x 106.91 Å box (an
    // open-space grid would hold the atoms' box and its padding instead).
    assert_eq!(csv.text_col("grid"), ["115x115x107"]);
    assert!(csv.col("triangles")[0] > 1000.0);
    assert!(csv.col("per_residue_ms")[0] > 0.0);
    // Where it cannot apply: one line each.
    for extra in [
        ["--backend", "gpu"].as_slice(),
        ["--preset", "ses"].as_slice(),
        ["--synthetic", "5k"].as_slice(),
    ] {
        let mut args = vec!["bench", &*bilayer, "--periodic"];
        args.extend_from_slice(extra);
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 2, "{extra:?}: {}", run.stderr);
        assert!(run.stderr.contains("--periodic"), "{}", run.stderr);
        assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
    }
}
