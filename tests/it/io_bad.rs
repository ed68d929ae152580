//! Every bad input gives a one-line `IoError` naming the file (and frame, and atom), never a
//! panic: missing files, unknown formats, garbage, truncated XTC/DCD (good frames kept), atom
//! count mismatches, NaN coordinates.

use crate::data_support::data;

use std::path::{Path, PathBuf};

use mdsurf::io::{self, IoError, Trajectory};

/// Opening must fail; returns the error after checking it is one line naming `names`.
fn open_err(top: &Path, traj: Option<&Path>, names: &[&str]) -> IoError {
    let e = match io::open(top, traj) {
        Ok(t) => panic!("{top:?} {traj:?} opened but must fail: {t:?}"),
        Err(e) => e,
    };
    one_line_naming(&e, names);
    e
}

fn one_line_naming(e: &IoError, names: &[&str]) {
    let text = e.to_string();
    assert!(!text.contains('\n'), "error must be one line: {text}");
    for name in names {
        assert!(text.contains(name), "error must name {name}: {text}");
    }
}

#[test]
fn missing_directory_empty_and_unknown() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("nope.pdb");
    assert!(matches!(
        open_err(&missing, None, &["nope.pdb"]),
        IoError::NotFound { .. }
    ));
    // A folder, and a pipe as `mdsurf <(zcat x.pdb.gz)` gives: said as such, not "not found".
    let folder = open_err(dir.path(), None, &[]);
    assert!(
        matches!(folder, IoError::NotAFile { what, .. } if what == "a folder"),
        "{folder}"
    );
    let pipe = dir.path().join("pipe.pdb");
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let piped = open_err(&pipe, None, &["pipe.pdb", "a pipe", "zcat"]);
    assert!(matches!(piped, IoError::NotAFile { .. }), "{piped}");
    let empty = dir.path().join("empty.gro");
    std::fs::write(&empty, "").expect("write");
    assert!(matches!(
        open_err(&empty, None, &["empty.gro"]),
        IoError::Empty { .. }
    ));
    let docx = dir.path().join("paper.docx");
    std::fs::write(&docx, "hello").expect("write");
    assert!(matches!(
        open_err(&docx, None, &["paper.docx", "docx"]),
        IoError::UnknownFormat { .. }
    ));
    let missing_traj = dir.path().join("nope.xtc");
    open_err(&data("md_1u19.gro"), Some(&missing_traj), &["nope.xtc"]);
}

#[test]
fn garbage_content() {
    let dir = tempfile::tempdir().expect("tempdir");
    let junk: Vec<u8> = (0..5000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    for name in [
        "junk.pdb",
        "junk.gro",
        "junk.xyz",
        "junk.cif",
        "junk.lammpstrj",
        "junk.tng",
        "junk.gro.gz",
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, &junk).expect("write");
        open_err(&path, None, &[name]);
    }
    for name in ["junk.xtc", "junk.dcd", "junk.trr", "junk.nc"] {
        let path = dir.path().join(name);
        std::fs::write(&path, &junk).expect("write");
        open_err(&data("md_1u19.gro"), Some(&path), &[name]);
    }
    let text = dir.path().join("text.gro");
    std::fs::write(&text, "this is\nnot a\ngro file\n").expect("write");
    open_err(&text, None, &["text.gro"]);
}

#[test]
fn coordinates_only_trajectory_needs_a_topology() {
    let e = open_err(&data("md_1u19.xtc"), None, &["md_1u19.xtc"]);
    assert!(matches!(e, IoError::NeedsTopology { .. }), "{e}");
}

#[test]
fn atom_count_mismatch_names_both_files_and_counts() {
    let e = open_err(
        &data("md_1u19.gro"),
        Some(&data("adk_oplsaa.xtc")),
        &["md_1u19.gro", "adk_oplsaa.xtc", "5547", "47681"],
    );
    assert!(matches!(e, IoError::AtomCountMismatch { .. }), "{e}");
}

/// Copies `traj` cut to `keep` of its size and opens it: the good frames must equal the
/// original's and the first missing frame must fail naming its index.
fn truncated(top: &str, traj: &str, keep: f64) {
    let dir = tempfile::tempdir().expect("tempdir");
    let bytes = std::fs::read(data(traj)).expect("read");
    let cut = dir.path().join(format!("cut-{traj}"));
    std::fs::write(&cut, &bytes[..(bytes.len() as f64 * keep) as usize]).expect("write");
    let original = io::open(&data(top), Some(&data(traj))).expect("original");
    let damaged = io::open(&data(top), Some(&cut))
        .unwrap_or_else(|e| panic!("truncated {traj} must still open: {e}"));
    let good = damaged.len();
    assert!(
        good > 0 && good < original.len(),
        "{traj} cut to {keep}: {good} good of {}",
        original.len()
    );
    let damage = damaged.damage().expect("damage is reported");
    assert_eq!(damage.frame, good);
    for k in [0, good / 2, good - 1] {
        let a = original.read_frame(k).expect("original frame");
        let b = damaged
            .read_frame(k)
            .unwrap_or_else(|e| panic!("good frame {k} must read: {e}"));
        assert_eq!(a.positions, b.positions, "frame {k}");
    }
    let e = damaged
        .read_frame(good)
        .expect_err("the cut frame must fail");
    one_line_naming(&e, &[&format!("frame {good}"), &format!("cut-{traj}")]);
    assert!(damaged.read_frame(good + 1).is_err());
}

#[test]
fn truncated_xtc_keeps_good_frames() {
    truncated("md_1u19.gro", "md_1u19.xtc", 0.7);
    truncated("md_1u19.gro", "md_1u19.xtc", 0.999);
}

#[test]
fn truncated_dcd_keeps_good_frames() {
    truncated("adk_open.pdb", "adk_dims.dcd", 0.6);
    truncated("adk_open.pdb", "adk_dims.dcd", 0.9995);
}

#[test]
fn truncated_to_nothing_fails_at_frame_zero() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bytes = std::fs::read(data("md_1u19.xtc")).expect("read");
    let cut = dir.path().join("tiny.xtc");
    std::fs::write(&cut, &bytes[..200]).expect("write");
    open_err(&data("md_1u19.gro"), Some(&cut), &["tiny.xtc"]);
}

/// Writes a 3-frame, 20-atom PDB topology and DCD trajectory with a NaN at `atom` in `frame`.
fn nan_files(dir: &Path, frame: usize, atom: usize, value: f64) -> (PathBuf, PathBuf) {
    let top = dir.join("nan.pdb");
    let traj = dir.join("nan.dcd");
    let make = |k: usize, bad: bool| {
        let mut f = chemfiles::Frame::new();
        for i in 0..20 {
            let mut p = [i as f64, 2.0 * i as f64 + k as f64, 1.0];
            if bad && k == frame && i == atom {
                p[1] = value;
            }
            f.add_atom(&chemfiles::Atom::new("C"), p, None);
        }
        f
    };
    let mut t = chemfiles::Trajectory::open(&top, 'w').expect("pdb");
    t.write(&make(0, false)).expect("write pdb");
    let mut t = chemfiles::Trajectory::open(&traj, 'w').expect("dcd");
    (0..3).for_each(|k| t.write(&make(k, true)).expect("write dcd"));
    (top, traj)
}

#[test]
fn nan_and_infinite_coordinates_name_frame_and_atom() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (top, traj) = nan_files(dir.path(), 2, 7, f64::NAN);
    let t: Trajectory = io::open(&top, Some(&traj)).expect("frames 0 and 1 are fine");
    assert_eq!(t.len(), 3);
    t.read_frame(1).expect("frame 1 is fine");
    let e = t.read_frame(2).expect_err("frame 2 has a NaN");
    assert!(
        matches!(
            e,
            IoError::NonFiniteCoordinate {
                frame: 2,
                atom: 7,
                ..
            }
        ),
        "{e}"
    );
    one_line_naming(&e, &["nan.dcd", "frame 2", "atom 7"]);
    let (top, traj) = nan_files(dir.path(), 0, 3, f64::INFINITY);
    let e = open_err(&top, Some(&traj), &["frame 0", "atom 3"]);
    assert!(
        matches!(
            e,
            IoError::NonFiniteCoordinate {
                frame: 0,
                atom: 3,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn frame_past_the_end() {
    let t = io::open(&data("1hpv.pdb"), None).expect("open");
    let e = t.read_frame(5).expect_err("one frame only");
    assert!(
        matches!(
            e,
            IoError::FrameOutOfRange {
                frame: 5,
                len: 1,
                ..
            }
        ),
        "{e}"
    );
    one_line_naming(&e, &["1hpv.pdb", "frame 5"]);
}
