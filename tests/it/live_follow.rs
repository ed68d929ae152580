//! Following a trajectory file while it is written (`--follow`): a thread of the test appends
//! the bytes of a real XTC file in pieces that cut frames anywhere, as an engine flushing its
//! output does. Every frame must come out equal to the finished file's, the partly written
//! frame is waited for (never read half), and the run ends once the file stops growing.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use mdsurf::io::{self, FollowOptions, IoError};

use crate::cli_common::{Csv, mdsurf};
use crate::data_support::data;

/// Starts writing `source` to `dest` in `pieces` appends, `pause` apart (the first piece is
/// written before returning, so the file opens with at least one whole frame).
fn grow(source: &Path, dest: &Path, pieces: usize, pause: Duration) -> std::thread::JoinHandle<()> {
    let bytes = std::fs::read(source).unwrap();
    let piece = bytes.len().div_ceil(pieces);
    let mut file = std::fs::File::create(dest).unwrap();
    file.write_all(&bytes[..piece]).unwrap();
    file.flush().unwrap();
    std::thread::spawn(move || {
        for chunk in bytes[piece..].chunks(piece) {
            std::thread::sleep(pause);
            file.write_all(chunk).unwrap();
            file.flush().unwrap();
        }
    })
}

fn follow(path: &Path, idle_s: u64) -> FollowOptions {
    let mut options = FollowOptions::new(path);
    options.idle = Duration::from_secs(idle_s);
    options.poll = Duration::from_millis(50);
    options
}

#[test]
fn frames_appended_while_reading_equal_the_finished_file() {
    let dir = tempfile::tempdir().unwrap();
    let (top, xtc) = (data("md_1u19.gro"), data("md_1u19.xtc"));
    let growing: PathBuf = dir.path().join("growing.xtc");
    let writer = grow(&xtc, &growing, 7, Duration::from_millis(150));
    let followed = io::open_following(&top, &follow(&growing, 2)).unwrap();
    assert!(followed.is_live());
    let finished = io::open(&top, Some(&xtc)).unwrap();
    let mut index = 0;
    let end = loop {
        match followed.read_frame(index) {
            Ok(frame) => {
                let want = finished.read_frame(index).unwrap();
                assert_eq!(frame.positions, want.positions, "frame {index}");
                assert_eq!(frame.time_ps, want.time_ps, "frame {index}");
                index += 1;
            }
            Err(end) => break end,
        }
    };
    writer.join().unwrap();
    assert_eq!(index, finished.len(), "every frame of the finished file");
    match &end {
        IoError::LiveEnded { frames, reason, .. } => {
            assert_eq!(*frames, finished.len());
            assert!(reason.contains("has not grown for 2 s"), "{reason}");
        }
        other => panic!("expected the end of the file, got: {other}"),
    }
}

#[test]
fn surface_follow_measures_every_frame_of_a_growing_file() {
    let dir = tempfile::tempdir().unwrap();
    let (top, xtc) = (data("md_1u19.gro"), data("md_1u19.xtc"));
    let growing = dir.path().join("growing.xtc");
    let writer = grow(&xtc, &growing, 5, Duration::from_millis(300));
    let top = top.to_string_lossy();
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &top,
            "growing.xtc",
            "--follow",
            "--follow-idle",
            "2",
            "--backend",
            "cpu",
            "--spacing",
            "2",
            "--stats",
            "live.csv",
        ],
    );
    writer.join().unwrap();
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains("has not grown for 2 s"),
        "{}",
        run.stderr
    );
    let whole = mdsurf(
        dir.path(),
        &[
            "surface",
            &top,
            &xtc.to_string_lossy(),
            "--backend",
            "cpu",
            "--spacing",
            "2",
            "--stats",
            "whole.csv",
        ],
    );
    assert_eq!(whole.code, 0, "{}", whole.stderr);
    let (live, whole) = (
        Csv::read(&dir.path().join("live.csv")),
        Csv::read(&dir.path().join("whole.csv")),
    );
    assert_eq!(live.col("area_A2"), whole.col("area_A2"));
    assert_eq!(live.col("time_ps"), whole.col("time_ps"));
    // --follow needs the file it follows.
    let run = mdsurf(dir.path(), &["surface", &top, "--follow"]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(
        run.last_line()
            .contains("--follow: give the trajectory file"),
        "{}",
        run.stderr
    );
}
