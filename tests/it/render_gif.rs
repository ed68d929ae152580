//! `mdsurf render -o movie.gif` end to end: the real binary writes a looping animated GIF of the
//! bundled demo with no external program; ffprobe reads back its codec, size, frame count and
//! duration (whole hundredths of a second per frame, running time kept), and a frame decoded by
//! ffmpeg matches the PNG render of the same frame (PSNR >= 35 dB; 256 colours a frame).
//! `render --chunk` writes GIF parts that `mdsurf merge movie.gif` joins into the same bytes as
//! one run. A rate a GIF cannot show is refused in one line, and nothing is written. Needs a
//! wgpu adapter and ffmpeg, as the other movie tests.

use std::path::Path;

use mdsurf::render::RgbaImage;

use crate::cli_common::{Run, asset, ffmpeg_tool, have_gpu, mdsurf};
use crate::render_movie::{assert_one_line_failure, files_in, json_field, psnr};

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
    let m = movie.to_str().expect("utf-8 path");
    let probe = ffmpeg_tool(
        "ffprobe",
        &[
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            "stream=codec_name,width,height,nb_read_frames",
            "-show_entries",
            "format=duration",
            "-of",
            "json",
            m,
        ],
    );
    let json = String::from_utf8_lossy(&probe);
    assert_eq!(json_field(&json, "codec_name"), "gif", "{json}");
    assert_eq!(json_field(&json, "width"), "160", "{json}");
    assert_eq!(json_field(&json, "height"), "120", "{json}");
    assert_eq!(json_field(&json, "nb_read_frames"), "6", "{json}");
    // Six frames at 30 frames/s: 0.2 s, as delays of 3, 4, 3, 3, 4, 3 hundredths.
    let duration: f64 = json_field(&json, "duration").parse().expect("duration");
    assert!(
        (duration - 0.2).abs() < 0.005,
        "duration {duration}: {json}"
    );

    let r = render(dir.path(), &["-o", "f_{frame}.png"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for image in [0, 5] {
        let png = RgbaImage::read_png(&dir.path().join(format!("f_{image}.png"))).expect("png");
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
                m,
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
        assert_eq!(decoded.len(), 160 * 120 * 3, "decoded frame size");
        let db = psnr(&decoded, &rgb);
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
