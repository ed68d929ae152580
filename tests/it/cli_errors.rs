//! Bad input to `mdsurf surface` (issue 2 section 5): each case exits with status 2 and one
//! `error: ...` line naming the file, frame or value, never panics, and leaves outputs that
//! existed before untouched. A damaged trajectory first processes and reports its good frames.

use std::fs;
use std::path::Path;

use crate::cli_common::{Csv, Run, asset, data, mdsurf};

const OLD: &[u8] = b"old content that must survive\n";

/// Runs `mdsurf surface ARGS --backend cpu -o OUT --stats stats.csv` in a directory where OUT and
/// stats.csv already exist, and checks the failure contract. Returns the run for more checks.
fn fails(dir: &Path, args: &[&str], out: &str, must_name: &[&str]) -> Run {
    fs::write(dir.join(out), OLD).unwrap();
    fs::write(dir.join("stats.csv"), OLD).unwrap();
    let mut all = vec!["surface"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--backend", "cpu", "-o", out, "--stats", "stats.csv"]);
    let run = mdsurf(dir, &all);
    assert_eq!(run.code, 2, "{args:?}: status {}\n{}", run.code, run.stderr);
    assert!(!run.stderr.contains("panicked"), "{}", run.stderr);
    let errors: Vec<&str> = run
        .stderr
        .lines()
        // Progress lines and the list of default representations are information.
        .filter(|l| !l.starts_with("frame") && !l.starts_with("rep "))
        .collect();
    assert_eq!(
        errors.len(),
        1,
        "{args:?}: expected one error line:\n{}",
        run.stderr
    );
    let line = errors[0];
    assert!(line.starts_with("error: "), "{line}");
    for word in must_name {
        let found = line.to_lowercase().contains(&word.to_lowercase());
        assert!(found, "{args:?}: '{word}' not in: {line}");
    }
    assert_eq!(fs::read(dir.join(out)).unwrap(), OLD, "{out} was changed");
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    run
}

/// Like [`fails`], and the stats file is untouched too (nothing was computed).
fn fails_cleanly(dir: &Path, args: &[&str], out: &str, must_name: &[&str]) {
    fails(dir, args, out, must_name);
    assert_eq!(
        fs::read(dir.join("stats.csv")).unwrap(),
        OLD,
        "stats.csv was changed"
    );
}

#[test]
fn missing_and_unknown_and_unreadable_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fails_cleanly(d, &["nope.gro"], "o.ply", &["nope.gro"]);
    fs::write(d.join("mol.foo"), "hello").unwrap();
    fails_cleanly(d, &["mol.foo"], "o.ply", &["mol.foo", "format"]);
    fs::write(d.join("junk.xtc"), vec![0xA5u8; 3000]).unwrap();
    fails_cleanly(
        d,
        &[&asset("md_1u19.gro"), "junk.xtc"],
        "o_{frame}.ply",
        &["junk.xtc"],
    );
    fs::write(d.join("junk.gro"), "not\na gro file at all\n").unwrap();
    fails_cleanly(d, &["junk.gro"], "o.ply", &["junk.gro"]);
}

#[test]
fn bad_parameters_name_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gro = asset("md_1u19.gro");
    for (flag, value, name) in [
        ("--spacing", "0", "H"),
        ("--spacing", "-0.5", "H"),
        ("--radius-scale", "-1", "R"),
        ("--isovalue", "0", "I"),
        ("--isovalue", "nan", "I"),
        ("--spacing", "inf", "H"),
    ] {
        fails_cleanly(d, &[&gro, flag, value], "o.ply", &[name, value]);
    }
    // Positive, finite and still absurd: refused with the range, never a panic or a hang
    // (1e-45 divided by zero in binning; 1e38 overflowed; 3e9 and up gave area 0 and exit 0).
    for (flag, value, name) in [
        ("--spacing", "1e-45", "H"),
        ("--spacing", "1e30", "H"),
        ("--radius-scale", "1e38", "R"),
        ("--isovalue", "1e30", "I"),
    ] {
        fails_cleanly(d, &[&gro, flag, value], "o.ply", &[name, value, "outside"]);
    }
    // More chunks than frames is a typo, not a part file to write.
    fails_cleanly(
        d,
        &[&gro, "--chunk", "0/4294967296"],
        "o.ply",
        &["--chunk", "4294967296"],
    );
    fails_cleanly(d, &[&gro, "--radius", "C=abc"], "o.ply", &["C=abc"]);
    fails_cleanly(
        d,
        &[&gro, "--color", "purple-ish"],
        "o.ply",
        &["purple-ish"],
    );
    fails_cleanly(d, &[&gro, "--frames", "7:x"], "o.ply", &["7:x"]);
}

#[test]
fn render_refuses_nan_and_out_of_range_look_values() {
    let dir = tempfile::tempdir().unwrap();
    let gro = asset("md_1u19.gro");
    for (flag, value) in [
        ("--opacity", "nan"),
        ("--ao", "1.5"),
        ("--depth-cue", "-inf"),
    ] {
        let arg = format!("{flag}={value}");
        let run = mdsurf(dir.path(), &["render", &gro, &arg, "-o", "x.png"]);
        assert_eq!(run.code, 2, "{flag} {value}: {}", run.stderr);
        assert!(
            run.stderr.contains(flag) && run.stderr.contains(value),
            "{}",
            run.stderr
        );
        assert!(!dir.path().join("x.png").exists());
    }
}

#[test]
fn several_frames_need_a_frame_pattern_and_outputs_a_known_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (gro, xtc) = (asset("md_1u19.gro"), asset("md_1u19.xtc"));
    fails_cleanly(
        d,
        &[&gro, &xtc, "--frames", "0:2"],
        "one.ply",
        &["one.ply", "{frame}"],
    );
    fails_cleanly(d, &[&gro], "mesh.xyz", &["mesh.xyz"]);
    let run = mdsurf(
        d,
        &["surface", &gro, "--backend", "cpu", "-o", "no/dir/m.ply"],
    );
    assert_eq!(run.code, 2);
    assert!(run.last_line().contains("no/dir"), "{}", run.stderr);
}

#[test]
fn atom_count_mismatch_names_both_files_and_counts() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, xtc) = (data("adk_open.pdb"), asset("md_1u19.xtc"));
    fails_cleanly(
        dir.path(),
        &[&pdb, &xtc],
        "o_{frame}.ply",
        &["adk_open.pdb", "md_1u19.xtc", "3341", "5547"],
    );
}

#[test]
fn empty_system_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("empty.xyz"), "0\nno atoms here\n").unwrap();
    fails_cleanly(dir.path(), &["empty.xyz"], "o.ply", &["empty.xyz"]);
}

#[test]
fn grid_too_large_says_how_much_and_suggests_a_larger_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = "2\ntwo atoms 35 um apart\nC 0 0 0\nC 20000 20000 20000\n";
    fs::write(dir.path().join("far.xyz"), xyz).unwrap();
    fails_cleanly(
        dir.path(),
        &["far.xyz"],
        "o.ply",
        &["far.xyz", "GB", "larger", "spacing"],
    );
}

/// Writes the topology `top` (a `.gro` or `.pdb` name) and `traj.dcd` with chemfiles: 3 atoms,
/// frame 0 fine, frame 1 with `bad` as one coordinate, frame 2 fine.
fn write_bad_coordinate_trajectory(dir: &Path, top: &str, bad: f64) {
    let mut frame = chemfiles::Frame::new();
    for (i, name) in ["C", "N", "O"].into_iter().enumerate() {
        frame.add_atom(
            &chemfiles::Atom::new(name),
            [i as f64 * 1.4, 0.0, 0.0],
            None,
        );
    }
    let mut writer = chemfiles::Trajectory::open(dir.join(top), 'w').unwrap();
    writer.write(&frame).unwrap();
    drop(writer);
    let mut traj = chemfiles::Trajectory::open(dir.join("traj.dcd"), 'w').unwrap();
    for f in 0..3 {
        if f == 1 {
            frame.positions_mut()[2][1] = bad;
        } else {
            frame.positions_mut()[2][1] = 0.5;
        }
        traj.write(&frame).unwrap();
    }
}

#[test]
fn nan_and_infinite_coordinates_name_the_frame_after_the_good_ones() {
    for (top, bad) in [("top.gro", f64::NAN), ("top.pdb", f64::INFINITY)] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write_bad_coordinate_trajectory(d, top, bad);
        let run = fails(
            d,
            &[top, "traj.dcd", "-v"],
            "o_{frame}.ply",
            &["traj.dcd", "frame 1"],
        );
        // Frame 0 was computed, written and reported (-v) before the error.
        assert!(
            run.stderr.lines().any(|l| l.starts_with("frame     0")),
            "{}",
            run.stderr
        );
        assert!(d.join("o_0.ply").is_file());
        assert!(!d.join("o_2.ply").exists());
        assert_eq!(Csv::read(&d.join("stats.csv")).col("frame"), [0.0]);
    }
}

/// Copies `src` cut to `keep` of its length into `dir/name`.
fn truncated_copy(src: &str, dir: &Path, name: &str, keep: f64) {
    let bytes = fs::read(src).unwrap();
    fs::write(
        dir.join(name),
        &bytes[..(bytes.len() as f64 * keep) as usize],
    )
    .unwrap();
}

/// The frame index an error line names (`frame N`).
fn frame_named(line: &str) -> usize {
    let at = line.find("frame ").expect("the error names no frame") + "frame ".len();
    line[at..]
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn truncated_xtc_processes_the_good_frames_then_fails() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    truncated_copy(&asset("md_1u19.xtc"), d, "cut.xtc", 0.45);
    let run = fails(
        d,
        &[&asset("md_1u19.gro"), "cut.xtc", "--frames", "15:"],
        "o_{frame}.ply",
        &["cut.xtc"],
    );
    let bad = frame_named(run.last_line());
    assert!((16..51).contains(&bad), "{}", run.last_line());
    let csv = Csv::read(&d.join("stats.csv"));
    let want: Vec<f64> = (15..bad).map(|f| f as f64).collect();
    assert_eq!(csv.col("frame"), want);
    assert!(d.join(format!("o_{}.ply", bad - 1)).is_file());
    assert!(!d.join(format!("o_{bad}.ply")).exists());
}

#[test]
fn truncated_dcd_processes_the_good_frames_then_fails() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    truncated_copy(&data("adk_dims.dcd"), d, "cut.dcd", 0.9);
    let args = [
        &data("adk_open.pdb") as &str,
        "cut.dcd",
        "--frames",
        "80:",
        "--spacing",
        "3",
    ];
    let run = fails(d, &args, "o_{frame}.stl", &["cut.dcd"]);
    let bad = frame_named(run.last_line());
    assert!((81..98).contains(&bad), "{}", run.last_line());
    let csv = Csv::read(&d.join("stats.csv"));
    assert_eq!(csv.rows.len(), bad - 80);
}

#[test]
fn an_address_space_limit_is_a_memory_budget_not_a_crash() {
    // Under `prlimit --as` (as `ulimit -v` or a batch system sets it) a grid past the limit is
    // refused in one line; before, MemAvailable alone was consulted and the allocation aborted.
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new("prlimit")
        .arg("--as=800000000")
        .arg(env!("CARGO_BIN_EXE_mdsurf"))
        .args(["surface", &data("1hpv.pdb"), "--spacing", "0.05"])
        .args(["--backend", "cpu", "--stats", "s.csv", "-q"])
        .current_dir(dir.path())
        .output()
        .expect("prlimit (util-linux) runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("grid") && stderr.contains("available") && stderr.contains("1hpv.pdb"),
        "{stderr}"
    );
    assert!(!dir.path().join("s.csv").exists());
}

/// A decompressed copy stops at the room of its folder (a disk's free space less a reserve, on
/// a tmpfs half the memory budget; here the `test-hooks` build's `MDSURF_TEST_COPY_ROOM`): the
/// frames that fit are processed and written, and one line names the frame it cut, the room and
/// what to do. Before, the copy grew until TMPDIR was full (or, on a tmpfs under Slurm's
/// `--mem`, until the job was killed with every frame lost).
#[test]
fn a_decompressed_copy_stops_at_the_room_of_its_folder() {
    use std::io::Read;
    let dump = data("spce_all_coords.lammpstrj.bz2");
    let mut text = Vec::new();
    bzip2::read::BzDecoder::new(fs::File::open(&dump).unwrap())
        .read_to_end(&mut text)
        .unwrap();
    let room = 2_000_000usize;
    // The frames wholly inside the room: those whose next frame starts within it.
    let marker = b"ITEM: TIMESTEP";
    let starts: Vec<usize> = (0..text.len() - marker.len())
        .filter(|&i| text[i..].starts_with(marker))
        .collect();
    let whole = starts.iter().skip(1).filter(|&&s| s <= room).count();
    assert!(
        whole >= 1 && whole + 1 < starts.len(),
        "{whole} of {}",
        starts.len()
    );
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .env("MDSURF_TEST_COPY_ROOM", room.to_string())
        .env("TMPDIR", dir.path())
        .args([
            "surface",
            &dump,
            "--backend",
            "cpu",
            "--stats",
            "s.csv",
            "-q",
        ])
        .current_dir(dir.path())
        .output()
        .expect("run mdsurf");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    for part in [
        "spce_all_coords.lammpstrj.bz2",
        &format!("frame {whole}:"),
        "room",
        "TMPDIR",
    ] {
        assert!(stderr.contains(part), "{part} missing from {stderr}");
    }
    let csv = Csv::read(&dir.path().join("s.csv"));
    assert_eq!(csv.rows.len(), whole, "{stderr}");
    let left: Vec<_> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().starts_with("mdsurf-read-"))
        .collect();
    assert!(left.is_empty(), "temporary copies left: {left:?}");
}

#[test]
fn ctrl_c_keeps_the_frames_done_and_leaves_no_temporary_file() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("stats.csv"), OLD).unwrap();
    // adk with its water at a fine grid: about a second per frame, ten frames.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(["surface", &data("adk_oplsaa.gro"), &data("adk_oplsaa.xtc")])
        .args(["--select", "all", "--spacing", "0.3", "--backend", "cpu"])
        .args(["--stats", "stats.csv", "-o", "mesh_{frame}.ply", "-v"])
        .current_dir(dir.path())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start mdsurf");
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    for line in lines.by_ref() {
        if line.unwrap().starts_with("frame") {
            break;
        }
    }
    // SAFETY: sends SIGINT to the child we started (its pid is valid until we wait on it).
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGINT);
    }
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(2), "{rest:?}");
    let last = rest.last().map(String::as_str).unwrap_or("");
    assert!(
        last.contains("interrupted") && last.contains("processed"),
        "{rest:?}"
    );
    let rows = Csv::read(&dir.path().join("stats.csv")).rows.len();
    assert!((1..10).contains(&rows), "{rows} rows");
    let names: Vec<String> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.ends_with(".tmp")), "{names:?}");
    assert_eq!(names.iter().filter(|n| n.ends_with(".ply")).count(), rows);
}
