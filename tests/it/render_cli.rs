//! `mdsurf render` end to end on the bundled demo: one picture, a turntable sequence with
//! numbered files, stereo sizes, and the errors for a sequence without `{frame}` and for a
//! missing display when the window is asked for. Needs a wgpu adapter (lavapipe is enough);
//! without one the picture tests return early with a note unless `REQUIRE_GPU=1`.

use std::path::Path;
use std::process::{Command, Output};

use mdsurf::render::RgbaImage;

use crate::cli_common::{data, have_gpu};

fn demo(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
        .display()
        .to_string()
}

fn mdsurf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(args)
        .output()
        .expect("run mdsurf")
}

#[test]
fn renders_one_frame_to_a_non_uniform_png() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("adk.png");
    let (gro, xtc) = (demo("md_1u19.gro"), demo("md_1u19.xtc"));
    let o = out.to_str().expect("utf-8 path");
    let r = mdsurf(&[
        "render",
        &gro,
        &xtc,
        "--frame",
        "2",
        "-o",
        o,
        "--size",
        "160x120",
        "--backend",
        "cpu",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let img = RgbaImage::read_png(&out).expect("png");
    assert_eq!((img.width, img.height), (160, 120));
    assert!(
        img.distinct_colours() > 200,
        "{} colours",
        img.distinct_colours()
    );
    assert_ne!(
        img.pixel(80, 60),
        img.pixel(0, 0),
        "nothing drawn in the centre"
    );
    // No temporary files are left beside the output.
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1);
}

#[test]
fn turntable_sequence_writes_numbered_turning_images() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    // Output folders are never created (a missing one is refused, as for `surface`).
    std::fs::create_dir(dir.path().join("seq")).expect("folder");
    let pattern = dir.path().join("seq/frame_{frame:05}.png");
    let (gro, xtc) = (demo("md_1u19.gro"), demo("md_1u19.xtc"));
    let p = pattern.to_str().expect("utf-8 path");
    let args = [
        "render",
        &gro,
        &xtc,
        "--frames",
        "0:3",
        "--turntable",
        "30",
        "-o",
        p,
        "--size",
        "96x96",
        "--backend",
        "cpu",
    ];
    let r = mdsurf(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let imgs: Vec<RgbaImage> = (0..3)
        .map(|i| {
            RgbaImage::read_png(&dir.path().join(format!("seq/frame_{i:05}.png"))).expect("png")
        })
        .collect();
    assert_ne!(imgs[0].pixels, imgs[1].pixels);
    assert_ne!(imgs[1].pixels, imgs[2].pixels);
}

#[test]
fn sequence_without_frame_placeholder_is_refused() {
    let (gro, xtc) = (demo("md_1u19.gro"), demo("md_1u19.xtc"));
    let r = mdsurf(&[
        "render",
        &gro,
        &xtc,
        "--frames",
        "0:2",
        "-o",
        "/tmp/x.png",
        "--backend",
        "cpu",
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("{frame}"), "{err}");
}

#[test]
fn window_without_display_suggests_render() {
    let r = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run mdsurf");
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("mdsurf render") && err.lines().count() == 1,
        "{err}"
    );
}

/// No adapter at all (`WGPU_BACKEND` names the one backend this Linux build lacks, as a machine
/// without a Vulkan loader or libEGL has none): `render` and the window each say so in one line
/// with what each backend said and what to install, and neither sends the user to the other.
/// The window's message before: "WGPU error: Failed to create surface for any enabled backend:
/// {}; use `mdsurf render ...`", render's: "... vulkan not requested, ...".
#[test]
fn no_adapter_at_all_is_said_with_what_to_install() {
    let pdb = data("1hpv.pdb");
    let out = std::env::temp_dir().join(format!("mdsurf-no-adapter-{}.png", std::process::id()));
    let render = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .env("WGPU_BACKEND", "metal")
        .args(["render", pdb.as_str(), "-o", out.to_str().unwrap()])
        .output()
        .expect("run mdsurf render");
    let (_guard, mut xvfb) = crate::xvfb_support::xvfb_run();
    let window = xvfb
        .env("WGPU_BACKEND", "metal")
        .args([env!("CARGO_BIN_EXE_mdsurf"), pdb.as_str(), "--quit"])
        .output()
        .expect("run xvfb-run mdsurf");
    for (what, r) in [("render", &render), ("window", &window)] {
        assert_eq!(r.status.code(), Some(2), "{what}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(err.lines().count(), 1, "{what}: {err}");
        for part in [
            "no GPU adapter",
            "metal support not compiled in",
            "mesa-vulkan-drivers",
        ] {
            assert!(err.contains(part), "{what}: {part} missing from {err}");
        }
        for wrong in ["not requested", "mdsurf render", "Failed to create surface"] {
            assert!(!err.contains(wrong), "{what}: {wrong} in {err}");
        }
    }
    assert!(!out.exists(), "render wrote {}", out.display());
}

/// The extent (width, height) in pixels of what differs from the top-left (background) pixel.
fn drawn_extent(img: &RgbaImage) -> (u32, u32) {
    let bg = img.pixel(0, 0);
    let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            if img.pixel(x, y) != bg {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    (x1.saturating_sub(x0), y1.saturating_sub(y0))
}

/// A membrane is drawn from the side by default (its normal up): YiiP's lipids alone (a patch
/// about 100 x 100 x 40 Å, normal along z) are much wider than tall on screen, while `--view
/// 0,0` keeps the old direction (looking down z at the square patch).
#[test]
fn a_membrane_renders_side_on() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let data = |n: &str| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(n)
            .display()
            .to_string()
    };
    let (gro, xtc) = (data("YiiP_lipids.gro.gz"), data("YiiP_lipids.xtc"));
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let out_s = out.display().to_string();
        let mut args = vec![
            "render",
            &gro,
            &xtc,
            "--frames",
            "0:1",
            "--size",
            "240x240",
            "--spacing",
            "3",
            "--backend",
            "cpu",
            "--select",
            "lipid",
            "-o",
            &out_s,
        ];
        args.extend_from_slice(extra);
        let run = mdsurf(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        drawn_extent(&RgbaImage::read_png(&out).expect("png"))
    };
    let (w, h) = render("side.png", &[]);
    assert!(w as f32 > 1.6 * h as f32, "side view {w} x {h}");
    let (w, h) = render("top.png", &["--view", "0,0"]);
    assert!((w as f32) < 1.3 * h as f32, "--view 0,0 {w} x {h}");
}

#[test]
fn quiet_render_prints_nothing_and_still_writes() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let (gro, xtc) = (demo("md_1u19.gro"), demo("md_1u19.xtc"));
    let pattern = dir.path().join("q_{frame}.png");
    let o = pattern.to_str().expect("utf-8 path");
    let args = [
        "render",
        &gro,
        &xtc,
        "--frames",
        "0:2",
        "-o",
        o,
        "--size",
        "64x48",
        "--backend",
        "cpu",
    ];
    let loud = mdsurf(&[&args[..], &["-v"]].concat());
    assert!(loud.status.success());
    assert!(String::from_utf8_lossy(&loud.stderr).contains("frame 1"));
    // stderr is a pipe: no line per image, one summary line at the end.
    let plain = mdsurf(&args);
    assert!(plain.status.success());
    let text = String::from_utf8_lossy(&plain.stderr);
    assert!(!text.lines().any(|l| l.starts_with("frame ")), "{text}");
    assert!(
        text.lines()
            .last()
            .is_some_and(|l| l.starts_with("2 image(s) in ")),
        "{text}"
    );
    let quiet = mdsurf(&[&args[..], &["-q"]].concat());
    assert!(quiet.status.success());
    assert_eq!(String::from_utf8_lossy(&quiet.stderr), "");
    assert!(dir.path().join("q_1.png").exists());
}
