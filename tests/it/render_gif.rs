//! `mdsurf render -o movie.gif` end to end: the real binary writes a looping animated GIF of the
//! bundled demo with no external program; ffprobe reads back its codec, size, frame count and
//! duration (whole hundredths of a second per frame, running time kept), and a frame decoded by
//! ffmpeg matches the PNG render of the same frame (PSNR >= 35 dB; 256 colours a frame).
//! `render --chunk` writes GIF parts that `mdsurf merge movie.gif` joins into the same bytes as
//! one run. A rate a GIF cannot show is refused in one line, and nothing is written. Needs a
//! wgpu adapter and ffmpeg, as the other movie tests.

use std::path::Path;

use crate::cli_common::{Run, asset, have_gpu, mdsurf, probe_duration, probe_video};
use crate::render_movie::{assert_one_line_failure, decoded_frame_psnr, files_in};

/// Renders frames 0:6 of the demo trajectory at 30 frames/s, 160x120, with `extra` flags.
fn render(dir: &Path, extra: &[&str]) -> Run {
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    let mut args = vec![
        "render",
        gro.as_str(),
        xtc.as_str(),
        "--backend",
        "cpu",
        "--frames",
        "0:6",
        "--size",
        "160x120",
        "-q",
    ];
    args.extend_from_slice(extra);
    mdsurf(dir, &args)
}

#[test]
fn gif_has_the_frames_size_duration_and_pictures_of_the_png_renders() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let r = render(dir.path(), &["--fps", "30", "-o", "movie.gif"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(
        files_in(dir.path()),
        ["movie.gif"],
        "no temporary file left"
    );
    let movie = dir.path().join("movie.gif");
    let probe = probe_video(&movie, "codec_name,width,height,nb_read_frames");
    assert_eq!(probe, "gif,160,120,6", "ffprobe");
    // Six frames at 30 frames/s: 0.2 s, as delays of 3, 4, 3, 3, 4, 3 hundredths.
    let duration = probe_duration(&movie);
    assert!((duration - 0.2).abs() < 0.005, "duration {duration}");

    let r = render(dir.path(), &["-o", "f_{frame}.png"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let m = movie.to_str().expect("utf-8 path");
    for image in [0, 5] {
        let png = dir.path().join(format!("f_{image}.png"));
        let db = decoded_frame_psnr(m, image, &png, [160, 120]);
        eprintln!("gif frame {image}: PSNR {db:.1} dB");
        assert!(db >= 35.0, "gif frame {image}: PSNR {db:.1} dB < 35");
    }
}

#[test]
fn gif_chunks_merge_into_the_bytes_of_one_run() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let r = render(d, &["--fps", "30", "-o", "whole.gif"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for chunk in ["0/2", "1/2"] {
        let r = render(d, &["--fps", "30", "--chunk", chunk, "-o", "movie.gif"]);
        assert_eq!(r.code, 0, "chunk {chunk}: {}", r.stderr);
    }
    assert!(d.join("movie.part-0001-of-0002.gif").exists());
    assert!(
        !d.join("movie.gif").exists(),
        "a chunk writes only its part"
    );
    let r = mdsurf(d, &["merge", "movie.gif", "--remove-parts"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("6 frame(s), 0.20 s"), "{}", r.stderr);
    let merged = std::fs::read(d.join("movie.gif")).expect("merged");
    let whole = std::fs::read(d.join("whole.gif")).expect("whole");
    assert!(merged == whole, "the merged GIF differs from one run's");
    assert_eq!(files_in(d), ["movie.gif", "whole.gif"], "parts removed");

    // A part that is not a GIF is named, and nothing is written.
    for chunk in ["0/2", "1/2"] {
        let r = render(d, &["--fps", "30", "--chunk", chunk, "-o", "again.gif"]);
        assert_eq!(r.code, 0, "chunk {chunk}: {}", r.stderr);
    }
    std::fs::write(d.join("again.part-0001-of-0002.gif"), b"GIF89a broken").expect("write");
    let r = mdsurf(d, &["merge", "again.gif"]);
    assert_one_line_failure(&r, "again.part-0001-of-0002.gif");
    assert!(!d.join("again.gif").exists());

    // Parts rendered at other frame rates are named with both rates.
    for (chunk, fps) in [("0/2", "30"), ("1/2", "10")] {
        let r = render(d, &["--fps", fps, "--chunk", chunk, "-o", "mixed.gif"]);
        assert_eq!(r.code, 0, "chunk {chunk}: {}", r.stderr);
    }
    let r = mdsurf(d, &["merge", "mixed.gif"]);
    assert_one_line_failure(&r, "mixed.part-0001-of-0002.gif");
    assert!(r.stderr.contains("10.00 frames/s"), "{}", r.stderr);
    assert!(!d.join("mixed.gif").exists());
}

#[test]
fn gif_rates_above_fifty_are_refused_in_one_line() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let r = render(dir.path(), &["--fps", "60", "-o", "fast.gif"]);
    assert_one_line_failure(&r, "fast.gif");
    assert!(r.stderr.contains("50"), "{}", r.stderr);
    assert!(files_in(dir.path()).is_empty(), "nothing written");
}
