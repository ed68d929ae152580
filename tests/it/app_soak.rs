//! The soak test of issue 10: the real window under Xvfb plays 505 frames of the demo trajectory
//! concatenated ten times (510 frames), computing and drawing each one, and its anonymous memory
//! (`RssAnon`, logged by the hidden `--memory-log`) after frame 500 must be within 20 MiB of
//! what it was after frame 100. Before the fix it grew by about 0.25 MiB per frame (~100 MiB
//! over those 400 frames). `--spacing 2` keeps each frame quick on a software rasteriser; the
//! growth did not depend on the grid or the atom count.

use std::path::Path;
use std::process::Command;

use crate::xvfb_support::xvfb_run;

/// Allowed change of anonymous memory between frame 100 and frame 500 (KiB).
const MAX_GROWTH_KIB: i64 = 20 * 1024;

#[test]
fn window_memory_stays_flat_over_500_frames() {
    let require = std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1");
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(!require, "REQUIRE_GPU=1 but xvfb-run is not installed");
        eprintln!("note: skipping the soak test: xvfb-run is not installed");
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let one = std::fs::read(demo.join("md_1u19.xtc")).expect("demo trajectory");
    // XTC frames are self-contained: concatenated files are a longer trajectory.
    let long = dir.path().join("long.xtc");
    std::fs::write(&long, one.repeat(10)).expect("write");
    let log_path = dir.path().join("memory.csv");
    let (_one_server_at_a_time, mut xvfb) = xvfb_run();
    let out = xvfb
        .arg(env!("CARGO_BIN_EXE_mdsurf"))
        .arg(demo.join("md_1u19.gro"))
        .arg(&long)
        .args(["--spacing", "2", "--play-frames", "505", "--quit"])
        .arg("--memory-log")
        .arg(&log_path)
        .env("XDG_RUNTIME_DIR", dir.path())
        .output()
        .expect("run xvfb-run");
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "exit {}: {log}", out.status);
    assert!(log.contains("showed 505 frame(s)"), "{log}");
    let csv = std::fs::read_to_string(&log_path).expect("memory log");
    let samples: Vec<(usize, i64)> = csv
        .lines()
        .skip(1)
        .filter_map(|l| {
            let (shown, kib) = l.split_once(',')?;
            Some((shown.parse().ok()?, kib.parse().ok()?))
        })
        .collect();
    let at = |frame: usize| {
        samples
            .iter()
            .find(|(shown, _)| *shown == frame)
            .map(|(_, kib)| *kib)
            .unwrap_or_else(|| panic!("no memory sample after frame {frame}: {csv}"))
    };
    let (early, late) = (at(100), at(500));
    assert!(
        (late - early).abs() <= MAX_GROWTH_KIB,
        "anonymous memory went from {early} KiB after frame 100 to {late} KiB after frame 500"
    );
}
