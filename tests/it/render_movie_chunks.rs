//! `render --chunk I/N -o movie.mp4` writes the chunk's part (`movie.part-IIII-of-NNNN.mp4`) and
//! `mdsurf merge movie.mp4` joins the parts without re-encoding: the merged movie holds the
//! parts' H.264 samples byte for byte, ffprobe reads the whole run's frame count, size, rate and
//! duration, and ffmpeg decodes it cleanly. Missing, mismatched or damaged parts are refused in
//! one line naming the file, and no movie is written. Needs a wgpu adapter and ffmpeg, as the
//! other movie tests.

use std::path::Path;

use crate::cli_common::{Run, asset, ffmpeg_tool, have_gpu, mdsurf, probe_duration, probe_video};
use crate::render_movie::assert_one_line_failure;

/// Renders chunk `chunk` of frames 0:6 of the demo trajectory at 10 frames/s into `out`'s part.
fn render_chunk_to(dir: &Path, chunk: &str, size: &str, out: &str, quiet: bool) -> Run {
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    let mut args = vec![
        "render",
        &gro,
        &xtc,
        "--backend",
        "cpu",
        "--frames",
        "0:6",
        "--fps",
        "10",
        "--size",
        size,
        "--chunk",
        chunk,
        "-o",
        out,
    ];
    if quiet {
        args.push("-q");
    }
    mdsurf(dir, &args)
}

/// [`render_chunk_to`] `movie.mp4`, quietly.
fn render_chunk(dir: &Path, chunk: &str, size: &str) -> Run {
    render_chunk_to(dir, chunk, size, "movie.mp4", true)
}

/// The H.264 samples of the one video track of an MP4 file, in order.
fn samples(path: &Path) -> Vec<Vec<u8>> {
    let file = std::fs::File::open(path).expect("open");
    let len = file.metadata().expect("metadata").len();
    let mut reader =
        mp4::Mp4Reader::read_header(std::io::BufReader::new(file), len).expect("mp4 header");
    let track = *reader.tracks().keys().next().expect("a track");
    let count = reader.sample_count(track).expect("sample count");
    (1..=count)
        .map(|id| {
            let s = reader
                .read_sample(track, id)
                .expect("read")
                .expect("sample");
            s.bytes.to_vec()
        })
        .collect()
}

#[test]
fn chunks_write_parts_that_merge_joins_without_re_encoding() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    for (i, chunk) in ["0/3", "1/3", "2/3"].into_iter().enumerate() {
        let r = render_chunk(d, chunk, "160x120");
        assert_eq!(r.code, 0, "chunk {chunk}: {}", r.stderr);
        // Without -q: the summary names the part written.
        if i == 0 {
            let r = render_chunk_to(d, chunk, "160x120", "check.mp4", false);
            assert!(
                r.stderr.contains("-> check.part-0000-of-0003.mp4"),
                "{}",
                r.stderr
            );
            std::fs::remove_file(d.join("check.part-0000-of-0003.mp4")).expect("remove");
        }
    }
    let parts: Vec<_> = (0..3)
        .map(|i| d.join(format!("movie.part-000{i}-of-0003.mp4")))
        .collect();
    let part_samples: Vec<Vec<u8>> = parts.iter().flat_map(|p| samples(p)).collect();
    assert_eq!(part_samples.len(), 6, "two frames per part");
    assert!(
        !d.join("movie.mp4").exists(),
        "a chunk writes only its part"
    );

    let r = mdsurf(d, &["merge", "movie.mp4", "--remove-parts"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("6 frame(s)"), "{}", r.stderr);
    let movie = d.join("movie.mp4");
    assert_eq!(
        samples(&movie),
        part_samples,
        "samples copied, not re-encoded"
    );
    assert!(parts.iter().all(|p| !p.exists()), "--remove-parts");

    let m = movie.to_str().expect("utf-8 path");
    let probe = probe_video(
        &movie,
        "codec_name,width,height,r_frame_rate,nb_read_frames",
    );
    assert_eq!(probe, "h264,160,120,10/1,6", "ffprobe");
    let duration = probe_duration(&movie);
    assert!((duration - 0.6).abs() < 0.02, "duration {duration}");
    // Decodes without an error (each part starts with a key frame).
    let log = ffmpeg_tool("ffmpeg", &["-v", "error", "-i", m, "-f", "null", "-"]);
    assert!(log.is_empty(), "{}", String::from_utf8_lossy(&log));
}

#[test]
fn merge_refuses_missing_mismatched_and_damaged_parts_in_one_line() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let r = mdsurf(d, &["merge", "no_such_folder/movie.mp4"]);
    assert_one_line_failure(&r, "cannot read the folder of its parts");
    assert_eq!(render_chunk(d, "0/2", "160x120").code, 0);
    let r = mdsurf(d, &["merge", "movie.mp4"]);
    assert_one_line_failure(&r, "movie.part-0001-of-0002.mp4: missing");
    assert!(!d.join("movie.mp4").exists());

    // The second half at another size.
    assert_eq!(render_chunk(d, "1/2", "128x96").code, 0);
    let r = mdsurf(d, &["merge", "movie.mp4"]);
    assert_one_line_failure(&r, "128x96 pixels");
    assert!(!d.join("movie.mp4").exists());

    // A part cut short, as by a chunk killed while writing.
    assert_eq!(render_chunk(d, "1/2", "160x120").code, 0);
    let part = d.join("movie.part-0001-of-0002.mp4");
    let bytes = std::fs::read(&part).expect("part");
    std::fs::write(&part, &bytes[..bytes.len() / 2]).expect("cut");
    let r = mdsurf(d, &["merge", "movie.mp4"]);
    assert_one_line_failure(&r, "movie.part-0001-of-0002.mp4");
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    assert!(!d.join("movie.mp4").exists());
}
