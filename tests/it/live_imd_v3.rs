//! IMD version 3 through the commands, with the bytes LAMMPS 2025 sent (tests/data/imd/; no
//! engine in Debian 12 speaks version 3): an engine faster than the surface loses frames from
//! the ring before they are read, and `surface` goes on from the oldest frame held, saying so
//! (frame 0 too, which may be gone before `surface` has set up).

use std::io::{Read, Write};
use std::net::TcpListener;

use crate::cli_common::{Csv, Run, data, mdsurf_env};

/// Bytes of the capture before its first frame: handshake (8) and session record (8 + 7).
const PREAMBLE: usize = 23;
/// Bytes of one frame of the capture: time, box, coordinates, velocities, forces of 256 atoms.
const FRAME: usize = (8 + 24) + (8 + 36) + 3 * (8 + 256 * 12);

/// An engine on a local port that sends the capture's preamble and then its first frame
/// `frames` times as fast as the socket takes them (steps renumbered), then closes.
fn flooding_engine(frames: usize) -> String {
    paced_engine(frames, std::time::Duration::ZERO)
}

/// [`flooding_engine`] waiting `pace` after each frame.
fn paced_engine(frames: usize, pace: std::time::Duration) -> String {
    let capture = std::fs::read(data("imd/lammps_argon_v3.bin")).unwrap();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        socket.write_all(&capture[..PREAMBLE]).unwrap();
        let mut go = [0u8; 8];
        socket.read_exact(&mut go).unwrap();
        let mut frame = capture[PREAMBLE..PREAMBLE + FRAME].to_vec();
        for step in 1..=frames as i64 {
            // The time record's step (i64, little-endian) and time (2 fs per step).
            frame[24..32].copy_from_slice(&step.to_le_bytes());
            frame[16..24].copy_from_slice(&(2.0 * step as f64).to_le_bytes());
            if socket.write_all(&frame).is_err() {
                return;
            }
            std::thread::sleep(pace);
        }
    });
    address
}

/// Runs `mdsurf COMMAND TOP --imd ADDRESS ARGS...` in a new folder (returned with the run)
/// against an engine flooding 3000 frames; with `setup_delay_ms`, the command's set-up waits
/// that long after connecting (the test build's hook), while the frames arrive.
fn against_flood(
    command: &str,
    args: &[&str],
    setup_delay_ms: Option<&str>,
) -> (tempfile::TempDir, Run) {
    let dir = tempfile::tempdir().unwrap();
    let top = data("imd/argon.xyz");
    let address = flooding_engine(3000);
    let mut all = vec![command, top.as_str(), "--imd", address.as_str()];
    all.extend_from_slice(args);
    let env: Vec<(&str, &str)> = setup_delay_ms
        .map(|ms| ("MDSURF_TEST_LIVE_SETUP_DELAY_MS", ms))
        .into_iter()
        .collect();
    let run = mdsurf_env(dir.path(), &all, &env);
    (dir, run)
}

#[test]
fn surface_sets_up_with_the_oldest_frame_held_when_frame_0_is_already_gone() {
    // Set-up waits 2 s after connecting (the test build's hook): the engine sends its 3000
    // frames meanwhile, and frame 0 has left the 256-frame ring before `surface` reads it.
    let (dir, run) = against_flood("surface", &["--stats", "s.csv"], Some("2000"));
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stderr.contains("frames 0 to "), "{}", run.stderr);
    let stats = Csv::read(&dir.path().join("s.csv"));
    let frames = stats.col("frame");
    assert!(frames[0] > 0.0, "{frames:?}");
    assert_eq!(frames.last(), Some(&2999.0));
}

#[test]
fn surface_skips_the_frames_a_fast_engine_pushed_out_of_the_ring() {
    let (dir, run) = against_flood("surface", &["--imd-wait", "10", "--stats", "s.csv"], None);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("skipped: the simulation sends frames faster than they are measured"),
        "{}",
        run.stderr
    );
    assert!(
        run.stderr
            .contains("frames of the simulation skipped in all"),
        "{}",
        run.stderr
    );
    let stats = Csv::read(&dir.path().join("s.csv"));
    let frames: Vec<usize> = stats.col("frame").iter().map(|&f| f as usize).collect();
    // Fewer rows than frames sent, in order, ending with the last frame sent; the times are
    // the engine's (2 fs per step, LAMMPS real units: the last is 6 ps).
    assert!(frames.len() < 3000, "{} rows", frames.len());
    assert!(frames.windows(2).all(|w| w[0] < w[1]), "{frames:?}");
    assert_eq!(frames.last(), Some(&2999));
    let times = stats.col("time_ps");
    assert_eq!(times.last(), Some(&6.0));
    // Every frame is either measured or counted as skipped.
    assert_eq!(
        frames.len() + skipped_in_all(&run.stderr),
        3000,
        "{}",
        run.stderr
    );
}

/// The count of `N frames of the simulation skipped in all`, the run's last skip line.
fn skipped_in_all(stderr: &str) -> usize {
    let line = stderr
        .lines()
        .find(|l| l.ends_with("frames of the simulation skipped in all"))
        .unwrap_or_else(|| panic!("no skip total in: {stderr}"));
    line.split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn the_skip_total_counts_only_the_frames_asked_for() {
    // One frame in two: the skipped ones the engine sent in between are not the user's.
    let (dir, run) = against_flood(
        "surface",
        &["--frames", "::2", "--stats", "s.csv"],
        Some("500"),
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let stats = Csv::read(&dir.path().join("s.csv"));
    let frames = stats.col("frame");
    assert!(
        frames.iter().all(|&f| (f as usize).is_multiple_of(2)),
        "{frames:?}"
    );
    assert_eq!(
        frames.len() + skipped_in_all(&run.stderr),
        1500,
        "{}",
        run.stderr
    );
}

#[test]
fn render_sets_up_with_the_oldest_frame_held_when_frame_0_is_already_gone() {
    // As above, for a movie: its first image is the oldest frame held, and the frames before
    // it are skipped with one line.
    let render = ["--frames", ":2800", "--size", "160x120", "-o", "live.mp4"];
    let (dir, run) = against_flood("render", &render, Some("2000"));
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stderr.contains("frames 0 to "), "{}", run.stderr);
    // Frames 2744 to 2799 (56) when all 3000 arrived during the set-up: the 256 frames held,
    // up to the range's end; never more than the ring held.
    let frames = crate::cli_common::probe_video(&dir.path().join("live.mp4"), "nb_read_frames");
    let frames: usize = frames.parse().unwrap();
    assert!(
        (1..=256).contains(&frames),
        "{frames} frames: {}",
        run.stderr
    );
}

#[test]
fn the_skip_line_names_no_frame_past_the_range() {
    // Frames 0 to 999 asked for, all gone before set-up (the ring holds 2744 on once the 3000
    // have come; 1256 are enough): the line names the frames asked for, and nothing is
    // measured or written.
    let (dir, run) = against_flood(
        "surface",
        &["--frames", ":1000", "--stats", "s.csv"],
        Some("2000"),
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains("frames 0 to 999 skipped"),
        "{}",
        run.stderr
    );
    assert_eq!(skipped_in_all(&run.stderr), 1000, "{}", run.stderr);
    assert!(!dir.path().join("s.csv").exists());
}

#[test]
fn the_windows_scripted_run_takes_the_frames_of_a_running_simulation_as_they_come() {
    // The window follows the newest frame, which moves on while one is computed: the scripted
    // run counts each new frame on screen (it used to wait for the newest to be the one shown,
    // which a fast engine never allowed, and hung until the engine stopped). 30000 frames 2 ms
    // apart: a minute of frames, more than the 60 s the run is given.
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let address = paced_engine(30_000, std::time::Duration::from_millis(2));
    let (_one_server_at_a_time, mut xvfb) = crate::xvfb_support::xvfb_run();
    // A hang is a failure after 60 s, not a stuck suite.
    let out = xvfb
        .args(["timeout", "60", env!("CARGO_BIN_EXE_mdsurf")])
        .arg(data("imd/argon.xyz"))
        .args([
            "--imd",
            &address,
            "--cpu",
            "--play-frames",
            "3",
            "--screenshot",
        ])
        .arg(&shot)
        .arg("--quit")
        .env("XDG_RUNTIME_DIR", dir.path())
        .output()
        .expect("run xvfb-run");
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "exit {}: {log}", out.status);
    assert!(log.contains("scripted run: showed 3 frame(s)"), "{log}");
    let image = mdsurf::render::RgbaImage::read_png(&shot).unwrap_or_else(|e| panic!("{e}: {log}"));
    assert!(image.distinct_colours() > 500, "blank screenshot: {log}");
}
