//! `mdsurf render -o movie.mp4` end to end: the real binary writes an H.264 MP4 of the bundled
//! demo; ffprobe (Debian `ffmpeg`, installed by scripts/test) reads back its codec, size, frame
//! rate, frame count and duration, and its first frame, decoded by ffmpeg, matches the PNG
//! render of the same frame (PSNR >= 35 dB). Failed movies (odd size, missing folder, a frame
//! that cannot be read half-way) leave no file and exit with one line. The movie tests need a
//! wgpu adapter (lavapipe is enough; skipped with a note unless `REQUIRE_GPU=1`) and ffmpeg
//! (its absence fails them).

use std::path::Path;
use std::process::Command;

use mdsurf::render::RgbaImage;

use crate::cli_common::{Run, asset, ffmpeg_tool, have_gpu, mdsurf, probe_duration, probe_video};

/// Peak signal-to-noise ratio in dB of two RGB images (8 bits per channel).
fn psnr(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    if mse == 0.0 {
        return f64::INFINITY;
    }
    10.0 * (255.0f64 * 255.0 / mse).log10()
}

/// PSNR in dB of image `image` of `movie`, decoded to RGB by ffmpeg, against the PNG `png` of
/// `w x h` pixels.
pub(crate) fn decoded_frame_psnr(movie: &str, image: usize, png: &Path, [w, h]: [usize; 2]) -> f64 {
    let png = RgbaImage::read_png(png).expect("png");
    let rgb: Vec<u8> = png
        .pixels
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let select = format!("select=eq(n\\,{image})");
    let decoded = ffmpeg_tool(
        "ffmpeg",
        &[
            "-v",
            "error",
            "-i",
            movie,
            "-vf",
            &select,
            "-frames:v",
            "1",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-",
        ],
    );
    assert_eq!(decoded.len(), w * h * 3, "decoded frame size");
    psnr(&decoded, &rgb)
}

fn render(dir: &Path, extra: &[&str]) -> Run {
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    let mut args = vec!["render", gro.as_str(), xtc.as_str(), "--backend", "cpu"];
    args.extend_from_slice(extra);
    mdsurf(dir, &args)
}

pub(crate) fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

pub(crate) fn assert_one_line_failure(r: &Run, needle: &str) {
    assert_ne!(r.code, 0, "should fail: {}", r.stderr);
    let err = r.stderr.trim();
    assert!(
        err.lines().count() == 1 && err.contains(needle),
        "expected one line naming {needle:?}, got:\n{err}"
    );
}

#[test]
fn movie_has_the_frames_size_rate_and_pictures_of_the_png_renders() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let size = ["--size", "320x240"];
    let r = render(
        dir.path(),
        &[
            &["--frames", "0:6", "--fps", "10", "--video-quality", "high"],
            &size[..],
            &["-o", "movie.mp4"],
        ]
        .concat(),
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("movie: 6 frames"), "{}", r.stderr);
    // Only the movie is left: no temporary files beside it.
    assert_eq!(files_in(dir.path()), ["movie.mp4"]);
    let movie = dir.path().join("movie.mp4");
    let m = movie.to_str().expect("utf-8 path");

    let probe = probe_video(
        &movie,
        "codec_name,width,height,r_frame_rate,nb_read_frames",
    );
    assert_eq!(probe, "h264,320,240,10/1,6", "ffprobe");
    let duration = probe_duration(&movie);
    assert!((duration - 0.6).abs() < 0.02, "duration {duration}");

    // The first (key) frame and the last (predicted) frame decoded to RGB against the PNG
    // sequence of the same run (same camera). 4:2:0 chroma alone limits these small pictures to
    // about 41 dB; the `high` preset gives about 40 dB.
    let r = render(
        dir.path(),
        &[&["--frames", "0:6"], &size[..], &["-o", "f_{frame}.png"]].concat(),
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    for image in [0, 5] {
        let png_name = format!("f_{image}.png");
        let db = decoded_frame_psnr(m, image, &dir.path().join(&png_name), [320, 240]);
        eprintln!("movie frame {image}: PSNR {db:.1} dB");
        assert!(
            db >= 35.0,
            "movie frame {image} vs {png_name}: PSNR {db:.1} dB < 35"
        );
    }
}

#[test]
fn odd_size_is_refused_in_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let r = render(
        dir.path(),
        &["--frames", "0:3", "--size", "161x120", "-o", "movie.mp4"],
    );
    assert_one_line_failure(&r, "161x120");
    assert!(r.stderr.contains("160x120"), "{}", r.stderr);
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}

#[test]
fn movie_into_a_missing_folder_or_an_empty_range_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let r = render(
        dir.path(),
        &[
            "--frames",
            "0:3",
            "--size",
            "160x120",
            "-o",
            "nowhere/movie.mp4",
        ],
    );
    assert_one_line_failure(&r, "nowhere");
    let r = render(
        dir.path(),
        &[
            "--frames",
            "500:600",
            "--size",
            "160x120",
            "-o",
            "movie.mp4",
        ],
    );
    assert_one_line_failure(&r, "--frames");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
    // Movie flags on a PNG output are refused rather than ignored.
    let r = render(dir.path(), &["--fps", "30", "-o", "f.png"]);
    assert_one_line_failure(&r, "--fps");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}

#[test]
fn interrupted_movie_leaves_no_file() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    // A long turntable (360 images) of small pictures, interrupted after its first image.
    let mut child = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args([
            "render",
            &gro,
            &xtc,
            "--backend",
            "cpu",
            "--turntable",
            "1",
            "--size",
            "64x48",
            "-v",
            "-o",
            "movie.mp4",
        ])
        .current_dir(dir.path())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start mdsurf");
    let mut lines = BufReader::new(child.stderr.take().expect("stderr")).lines();
    let mut seen = Vec::new();
    for line in lines.by_ref() {
        let line = line.expect("stderr line");
        let first_image = line.starts_with("frame ");
        seen.push(line);
        if first_image {
            break;
        }
    }
    assert!(
        seen.last().is_some_and(|l| l.starts_with("frame ")),
        "no image rendered: {seen:?}"
    );
    // SAFETY: sends SIGINT to the child we started (its pid is valid until we wait on it).
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGINT);
    }
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().expect("wait");
    assert_eq!(status.code(), Some(2), "{seen:?} {rest:?}");
    let last = rest.last().map(String::as_str).unwrap_or("");
    assert!(last.contains("interrupted"), "{rest:?}");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}
