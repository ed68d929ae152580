//! The window keeps its look and layout between runs (issue 30 section 4), through eframe's
//! persistence: a run that ends with a light background leaves it in the settings folder
//! (`MDSURF_SETTINGS_DIR`), and the next run without a state file opens with it. A scripted
//! run without that variable neither reads nor writes kept settings, so batch screenshots do not
//! depend on the last session. Runs the real binary under `xvfb-run -a`.

use std::path::Path;
use std::process::Command;

use mdsurf::render::RgbaImage;

use crate::cli_common::have_gpu;
use crate::xvfb_support::xvfb_run;

/// Runs the window on the demo for one frame, with `extra` arguments and `settings` as the
/// settings folder (none: unset), and returns the screenshot's top-left pixel (background).
fn corner_after_run(dir: &Path, extra: &[&str], settings: Option<&Path>, name: &str) -> [u8; 4] {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let shot = dir.join(name);
    let (_one_server_at_a_time, mut xvfb) = xvfb_run();
    let mut cmd: &mut Command = xvfb
        .arg(env!("CARGO_BIN_EXE_mdsurf"))
        .arg(demo.join("md_1u19.gro"))
        .args(["--cpu", "--play-frames", "1", "--screenshot"])
        .arg(&shot)
        .arg("--quit")
        .args(extra)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", dir)
        .env_remove(mdsurf::app::settings_store::SETTINGS_DIR_ENV);
    if let Some(folder) = settings {
        cmd = cmd.env(mdsurf::app::settings_store::SETTINGS_DIR_ENV, folder);
    }
    let out = cmd.output().expect("run xvfb-run");
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "mdsurf exited with {}: {log}",
        out.status
    );
    RgbaImage::read_png(&shot)
        .unwrap_or_else(|e| panic!("{e}; log: {log}"))
        .pixel(0, 0)
}

fn is_light(p: [u8; 4]) -> bool {
    p[..3].iter().all(|&c| c > 200)
}

#[test]
fn the_look_of_one_session_opens_the_next() {
    if !have_gpu() || Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(
            std::env::var("REQUIRE_GPU").as_deref() != Ok("1"),
            "REQUIRE_GPU=1 but no wgpu adapter or no xvfb-run"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("settings");
    std::fs::create_dir(&settings).unwrap();
    std::fs::write(
        dir.path().join("light.toml"),
        "version = 1\n[look]\nbackground = \"light\"\n",
    )
    .unwrap();
    // A fresh run is dark; a run with a light state file ends light and keeps that.
    let fresh = corner_after_run(dir.path(), &[], Some(&settings), "fresh.png");
    assert!(!is_light(fresh), "{fresh:?}");
    let first = corner_after_run(
        dir.path(),
        &["--state", "light.toml"],
        Some(&settings),
        "first.png",
    );
    assert!(is_light(first), "{first:?}");
    let kept = std::fs::read_to_string(settings.join("window.ron")).expect("settings written");
    assert!(kept.contains("mdsurf.look"), "{kept}");
    // The next run, with no state file, opens with the kept look.
    let second = corner_after_run(dir.path(), &[], Some(&settings), "second.png");
    assert!(is_light(second), "the look was not kept: {second:?}");
    // A scripted run without MDSURF_SETTINGS_DIR ignores kept settings.
    let batch = corner_after_run(dir.path(), &[], None, "batch.png");
    assert!(!is_light(batch), "{batch:?}");
}
