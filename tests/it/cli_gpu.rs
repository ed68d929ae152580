//! `mdsurf surface --backend gpu` on a small real protein gives the same statistics as
//! `--backend cpu` (issue 3 section 2: same outputs and columns on every backend; tolerances of
//! section 3), and `--backend auto` says on stderr which engine it used. Without an adapter the
//! test checks that `auto` falls back to the CPU and returns with a note, except under
//! `REQUIRE_GPU=1`, where a missing adapter fails it. `bench --backend gpu` on a single-frame
//! file times whole frames.

use crate::cli_common::{Csv, bench_csv, data, mdsurf, read_ply_counts};

#[test]
fn gpu_backend_matches_the_cpu_backend_on_1hpv() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let run_on = |backend: &str| {
        let out = format!("{backend}.ply");
        let stats = format!("{backend}.csv");
        let args = [
            "surface",
            &pdb,
            "--spacing",
            "1.5",
            "--backend",
            backend,
            "-o",
            &out,
            "--stats",
            &stats,
        ];
        (mdsurf(dir.path(), &args), stats, out)
    };
    let (gpu, gpu_csv, gpu_ply) = run_on("gpu");
    if gpu.code != 0 {
        let required = std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1");
        let no_adapter = gpu.last_line().contains("no GPU adapter");
        if no_adapter && !required {
            let (auto, _, _) = run_on("auto");
            assert_eq!(auto.code, 0, "{}", auto.stderr);
            assert!(auto.stderr.contains("backend: cpu"), "{}", auto.stderr);
            eprintln!("note: no GPU adapter, skipping (set REQUIRE_GPU=1 to fail instead)");
            return;
        }
        panic!("--backend gpu failed (status {}): {}", gpu.code, gpu.stderr);
    }
    let (cpu, cpu_csv, _) = run_on("cpu");
    assert_eq!(cpu.code, 0, "{}", cpu.stderr);
    let (g, c) = (
        Csv::read(&dir.path().join(gpu_csv)),
        Csv::read(&dir.path().join(cpu_csv)),
    );
    assert_eq!(
        g.columns, c.columns,
        "the backends write different CSV columns"
    );
    for col in ["atoms", "nx", "ny", "nz"] {
        assert_eq!(g.col(col), c.col(col), "{col}");
    }
    let rel = |col: &str| (g.col(col)[0] / c.col(col)[0] - 1.0).abs();
    assert!(
        rel("triangles") <= 0.005,
        "triangles differ by {}",
        rel("triangles")
    );
    assert!(
        rel("area_A2") <= 0.001,
        "area differs by {}",
        rel("area_A2")
    );
    assert!(
        rel("volume_A3") <= 0.001,
        "volume differs by {}",
        rel("volume_A3")
    );
    let (v, t, _) = read_ply_counts(&dir.path().join(gpu_ply));
    assert_eq!(
        (v as f64, t as f64),
        (g.col("vertices")[0], g.col("triangles")[0])
    );

    // With a hardware GPU, auto picks it and says so; with only a software adapter (lavapipe,
    // slower than the CPU engine) it picks the CPU and says why. Either way the same surface.
    let (auto, auto_csv, _) = run_on("auto");
    assert_eq!(auto.code, 0, "{}", auto.stderr);
    let expected = if auto.stderr.contains("backend: gpu") {
        &g
    } else {
        assert!(
            auto.stderr.contains("backend: cpu") && auto.stderr.contains("software rasterizer"),
            "auto must name its engine and why: {}",
            auto.stderr
        );
        &c
    };
    let a = Csv::read(&dir.path().join(auto_csv));
    assert_eq!(a.col("triangles"), expected.col("triangles"));
    assert_eq!(a.col("volume_A3"), expected.col("volume_A3"));
}

/// `bench --backend gpu` on a single-frame file times full frames: each repeat uploads, bins
/// and computes density again (the engine would otherwise see the same atoms and run Marching
/// Cubes alone), so its stage columns compare with the CPU engine's.
#[test]
fn gpu_bench_of_a_single_frame_file_times_whole_frames() {
    if crate::gpu_support::context().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let args = [
        &*pdb,
        "--backend",
        "gpu",
        "--spacing",
        "1.5",
        "--repeats",
        "3",
    ];
    let csv = bench_csv(dir.path(), &args);
    assert_eq!(csv.col("atoms"), [1631.0]);
    let (upload, density) = (csv.col("upload_ms")[0], csv.col("density_ms")[0]);
    assert!(upload > 0.0 && density > 0.0, "{:?}", csv.rows[0]);
}

/// `bench --viewer` plays a (jittered) single-frame file through the viewer's own worker,
/// timeline and renderer offscreen: every timeline frame is either shown or counted as
/// dropped, at least one surface reached the picture, and the report names what it drew.
#[test]
fn viewer_bench_plays_frames_offscreen() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let args = [
        "bench",
        "--viewer",
        &pdb,
        "--frames",
        "6",
        "--play-fps",
        "3",
        "--size",
        "160x120",
    ];
    let run = mdsurf(dir.path(), &args);
    if run.code != 0 {
        let required = std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1");
        if run.stderr.contains("needs a GPU") && !required {
            eprintln!("note: no GPU adapter, skipping (set REQUIRE_GPU=1 to fail instead)");
            return;
        }
        panic!(
            "bench --viewer failed (status {}): {}",
            run.code, run.stderr
        );
    }
    let field = |name: &str| -> Vec<String> {
        let line = run
            .stdout
            .lines()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap_or_else(|| panic!("no '{name}' line in:\n{}", run.stdout));
        line[line.find(name).unwrap() + name.len()..]
            .split_whitespace()
            .map(str::to_string)
            .collect()
    };
    let shown: usize = field("shown")[0].parse().unwrap();
    let dropped: usize = field("dropped")[0].parse().unwrap();
    assert!(shown >= 1, "{}", run.stdout);
    assert_eq!(shown + dropped, 6, "{}", run.stdout);
    assert!(
        field("representations").join(" ").contains("macromolecule"),
        "{}",
        run.stdout
    );
    let triangles: usize = field("triangles")[0].parse().unwrap();
    assert!(triangles > 1_000, "{}", run.stdout);
    assert!(
        field("picture").join(" ").starts_with("160 x 120"),
        "{}",
        run.stdout
    );
    let gpu_mib: f64 = field("GPU memory")[0].parse().unwrap();
    assert!(gpu_mib > 0.0, "{}", run.stdout);
    let draw = field("draw alone");
    assert!(draw[0].parse::<f64>().unwrap() > 0.0, "{}", run.stdout);
    // The default look has no outlines or shadows to time against.
    assert_eq!(field("look's extra cost")[0], "-", "{}", run.stdout);

    // With them, each draw is paired with the same draw without them.
    let figure = mdsurf(dir.path(), &[&args[..], &["--look", "figure"]].concat());
    assert_eq!(figure.code, 0, "{}", figure.stderr);
    let line = figure
        .stdout
        .lines()
        .find(|l| l.contains("look's extra cost"))
        .unwrap_or_else(|| panic!("no look line in:\n{}", figure.stdout));
    let words: Vec<&str> = line.split_whitespace().collect();
    let percent: f64 = words[3].parse().unwrap();
    assert!(percent.is_finite() && percent > -100.0, "{line}");
    assert!(line.contains("median of 20 interleaved pairs"), "{line}");
}

/// Without a desktop session (`XDG_RUNTIME_DIR` unset, as over SSH, on clusters and in CI) the
/// GPU backend prints no driver lines: with `-q` a successful run leaves stderr empty.
#[test]
fn no_driver_noise_without_a_desktop_session() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args([
            "surface",
            &pdb,
            "--backend",
            "gpu",
            "--spacing",
            "2",
            "-q",
            "--stats",
            "s.csv",
        ])
        .current_dir(dir.path())
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .expect("cannot start the mdsurf binary");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let required = std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1");
        if stderr.contains("no GPU adapter") && !required {
            eprintln!("note: no GPU adapter, skipping (set REQUIRE_GPU=1 to fail instead)");
            return;
        }
        panic!("surface --backend gpu failed: {stderr}");
    }
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert_eq!(stderr.trim(), "", "stderr not empty under -q");
    assert!(dir.path().join("s.csv").exists());
}
