//! The contained reader (issue 29): every file chemfiles reads is read in a reader process, so a
//! file that crashes chemfiles (a LAMMPS dump with atom id 0 or an id past 2^31, a DCD whose
//! title count is huge) gives one line of error naming the file and the frame, exit code 2 from
//! `mdsurf surface`, and the stats rows of the frames before it; the reader process gives exactly
//! what chemfiles gives in-process; a reader killed mid-run (the `MDSURF_READER_CRASH_AT` hook)
//! costs only the frame it died on, and leaves no temporary file behind. A PDB file cut inside a
//! model, or with a damaged record, names the line.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use mdsurf::io;

use crate::data_support::data;

/// The result of one run of the binary.
struct Outcome {
    code: Option<i32>,
    stderr: String,
}

/// Runs `mdsurf surface FILES --stats s.csv` in `dir` with `env` added.
fn surface(dir: &Path, files: &[&Path], extra: &[&str], env: &[(&str, &str)]) -> Outcome {
    let out = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .arg("surface")
        .args(files)
        .args([
            "--backend",
            "cpu",
            "--spacing",
            "2",
            "-q",
            "--stats",
            "s.csv",
        ])
        .args(extra)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .envs(env.iter().copied())
        .output()
        .expect("cannot start mdsurf");
    Outcome {
        code: out.status.code(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The frame column of the stats CSV `dir/s.csv`.
fn stats_frames(dir: &Path) -> Vec<usize> {
    let text = std::fs::read_to_string(dir.join("s.csv")).unwrap_or_default();
    text.lines()
        .skip(1)
        .filter_map(|l| l.split(',').next()?.parse().ok())
        .collect()
}

/// Asserts exit 2 and one line of stderr that names `name` and contains every one of `words`.
fn assert_one_line(o: &Outcome, name: &str, words: &[&str]) {
    assert_eq!(o.code, Some(2), "{}", o.stderr);
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "not one line: {}", o.stderr);
    for word in std::iter::once(&name).chain(words) {
        assert!(lines[0].contains(word), "{word:?} missing: {}", lines[0]);
    }
}

/// The first `frames` frames of the LAMMPS dump in `tests/data`, as text, and where each
/// frame's first atom line starts.
fn lammps_dump(frames: usize) -> (Vec<u8>, Vec<usize>) {
    let mut dump = Vec::new();
    bzip2::read::BzDecoder::new(&std::fs::read(data("spce_all_coords.lammpstrj.bz2")).unwrap()[..])
        .read_to_end(&mut dump)
        .unwrap();
    let starts: Vec<usize> = (0..dump.len())
        .filter(|&k| dump[k..].starts_with(b"ITEM: TIMESTEP"))
        .collect();
    dump.truncate(starts.get(frames).copied().unwrap_or(dump.len()));
    let first_atoms = starts[..frames]
        .iter()
        .map(|&s| {
            let items = s + find(&dump[s..], b"ITEM: ATOMS");
            items + find(&dump[items..], b"\n") + 1
        })
        .collect();
    (dump, first_atoms)
}

fn find(hay: &[u8], needle: &[u8]) -> usize {
    hay.windows(needle.len())
        .position(|w| w == needle)
        .expect("marker")
}

/// `dump` with the id of the first atom of the frame whose atoms start at `at` set to `id`.
fn with_first_id(dump: &[u8], at: usize, id: &str) -> Vec<u8> {
    let end = at + find(&dump[at..], b" ");
    [&dump[..at], id.as_bytes(), &dump[end..]].concat()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// chemfiles for the LAMMPS dump, in its reader process (our reader takes it by default).
const CHEMFILES: [(&str, &str); 1] = [("MDSURF_NO_NATIVE_READ", "1")];

/// Atom id 0 in frame 3 of 8 makes chemfiles abort (double free) while reading that frame: the
/// run keeps frames 0-2 and names frame 3; the library reads the frames around it (a new
/// reader process after the crash) exactly as in the sound file. Our LAMMPS reader, the
/// default, reads all 8 frames: an id is a number to sort the atoms by.
#[test]
fn lammps_atom_id_zero_keeps_the_frames_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let (dump, atoms) = lammps_dump(8);
    let good = write(dir.path(), "good.lammpstrj", &dump);
    let bad = write(
        dir.path(),
        "id0.lammpstrj",
        &with_first_id(&dump, atoms[3], "0"),
    );
    let o = surface(dir.path(), &[&bad], &[], &CHEMFILES);
    assert_one_line(&o, "id0.lammpstrj", &["frame 3", "crashed"]);
    assert_eq!(stats_frames(dir.path()), vec![0, 1, 2]);
    // Our reader: every frame, frame 3 the same as in the sound file.
    let o = surface(dir.path(), &[&bad], &[], &[]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert_eq!(stats_frames(dir.path()), (0..8).collect::<Vec<_>>());
    let ours = io::open(&bad, None).expect("our reader reads id 0");
    assert_eq!(ours.len(), 8);
    let reference = io::open(&good, None).unwrap();
    for k in [0, 2, 4, 7] {
        assert_eq!(
            ours.read_frame(k).unwrap(),
            reference.read_frame(k).unwrap()
        );
    }
    // Frame 3: the renumbered atom sorts first, the atoms are those of the sound file.
    let sorted = |mut p: Vec<glam::Vec3>| {
        p.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
        p
    };
    let (a, b) = (
        ours.read_frame(3).unwrap(),
        reference.read_frame(3).unwrap(),
    );
    assert_eq!(sorted(a.positions), sorted(b.positions));
    // In this (test) process: the crash is the reader process's, not ours.
    let t = io::open_via_reader_process(&bad, None).expect("frames 0-2 are sound");
    let e = t.read_frame(3).expect_err("frame 3 crashes the reader");
    assert!(e.to_string().contains("frame 3"), "{e}");
    for k in [2, 4, 0, 7] {
        assert_eq!(
            t.read_frame(k).unwrap(),
            reference.read_frame(k).unwrap(),
            "frame {k} after the crash"
        );
    }
}

/// An atom id past 2^31 in frame 6 of 8 (SIGSEGV in chemfiles) is found when the file opens
/// (the last frames are probed): frames 0-5 are the trajectory, frame 6 its damage. Our
/// reader reads the 64-bit id and every frame.
#[test]
fn lammps_huge_atom_id_is_damage_at_its_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (dump, atoms) = lammps_dump(8);
    let bad = write(
        dir.path(),
        "big.lammpstrj",
        &with_first_id(&dump, atoms[6], "2147483648"),
    );
    assert_eq!(io::open(&bad, None).expect("our reader").len(), 8);
    let t = io::open_via_reader_process(&bad, None).expect("frames 0-5 are sound");
    assert_eq!(t.len(), 6);
    let damage = t.damage().expect("frame 6 is the damage");
    assert_eq!(damage.frame, 6);
    assert!(
        damage.error.to_string().contains("crashed"),
        "{}",
        damage.error
    );
    let o = surface(dir.path(), &[&bad], &[], &CHEMFILES);
    assert_one_line(&o, "big.lammpstrj", &["frame 6", "crashed"]);
    assert_eq!(stats_frames(dir.path()), (0..6).collect::<Vec<_>>());
    // Frame 0 broken: nothing to keep, one line, exit 2.
    let first = write(
        dir.path(),
        "f0.lammpstrj",
        &with_first_id(&dump, atoms[0], "0"),
    );
    let o = surface(dir.path(), &[&first], &[], &CHEMFILES);
    assert_one_line(&o, "f0.lammpstrj", &["crashed"]);
    assert!(io::open_via_reader_process(&first, None).is_err());
    assert_eq!(io::open(&first, None).expect("our reader").len(), 8);
}

/// A DCD whose title count is 2^31 - 1 made chemfiles read far past its buffer (SIGSEGV).
#[test]
fn dcd_huge_title_count_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut dcd = std::fs::read(data("adk_dims.dcd")).unwrap();
    dcd[96..100].copy_from_slice(&0x7fff_ffffi32.to_le_bytes());
    let bad = write(dir.path(), "title.dcd", &dcd);
    let pdb = data("adk_open.pdb");
    // Our DCD reader never reads the title lines: the frames are all there.
    let ours = io::open(&pdb, Some(&bad)).expect("the frames are sound");
    assert_eq!(ours.len(), 98);
    // chemfiles, in the reader process, crashes: one line.
    let chem = [("MDSURF_NO_NATIVE_READ", "1")];
    let o = surface(dir.path(), &[&pdb, &bad], &[], &chem);
    assert_one_line(&o, "title.dcd", &["crashed"]);
}

/// Every frame (positions, box, time), the frame count and the topology are the same through
/// the reader process as through chemfiles in this process, on every multi-frame file of
/// `tests/data` that chemfiles reads (TNG, DCD, LAMMPS dump) and on the GRO files.
#[test]
fn reader_process_gives_what_chemfiles_gives() {
    let cases: [(&str, Option<&str>); 6] = [
        ("argon_npt_compressed.tng", None),
        ("adk_open.pdb", Some("adk_dims.dcd")),
        ("spce_all_coords.lammpstrj.bz2", None),
        ("md_1u19.gro", None),
        ("adk_oplsaa.gro", None),
        ("YiiP_lipids.gro.gz", None),
    ];
    for (top, traj) in cases {
        let top = data(top);
        let traj = traj.map(data);
        let ours = io::open_via_reader_process(&top, traj.as_deref()).unwrap();
        let theirs = io::open_via_chemfiles(&top, traj.as_deref()).unwrap();
        let name = ours.path().display().to_string();
        assert_eq!(ours.len(), theirs.len(), "{name}");
        assert_eq!(ours.damage(), theirs.damage(), "{name}");
        if traj.is_none() {
            assert_eq!(ours.topology(), theirs.topology(), "{name}");
        }
        for k in 0..ours.len() {
            let (a, b) = (ours.read_frame(k).unwrap(), theirs.read_frame(k).unwrap());
            assert_eq!(a, b, "{name} frame {k}");
        }
    }
}

/// A reader process that dies at frame 5 (the test hook) costs frame 5 only: stats rows for
/// frames 0-4, one line naming frame 5 and the signal. A compressed file's temporary copy is
/// removed even so.
#[test]
fn reader_killed_mid_run_keeps_the_frames_before() {
    let dir = tempfile::tempdir().unwrap();
    let tng = data("argon_npt_compressed.tng");
    let hook = [("MDSURF_READER_CRASH_AT", "5")];
    let o = surface(dir.path(), &[&tng], &["--frames", "0:20"], &hook);
    assert_one_line(&o, "argon_npt_compressed.tng", &["frame 5", "SIGABRT"]);
    assert_eq!(stats_frames(dir.path()), (0..5).collect::<Vec<_>>());
    // The decompressed copy of a .bz2 file lives in TMPDIR while the reader process reads it.
    let temp = tempfile::tempdir().unwrap();
    let tmp = temp.path().to_str().unwrap();
    let bz2 = data("spce_all_coords.lammpstrj.bz2");
    let o = surface(
        dir.path(),
        &[&bz2],
        &[],
        &[
            ("MDSURF_READER_CRASH_AT", "2"),
            ("TMPDIR", tmp),
            CHEMFILES[0],
        ],
    );
    assert_one_line(&o, "spce_all_coords.lammpstrj.bz2", &["frame 2"]);
    assert_eq!(stats_frames(dir.path()), vec![0, 1]);
    let left: Vec<_> = std::fs::read_dir(temp.path()).unwrap().collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

/// A multi-model PDB cut inside model 5 keeps models 0-4 and names the lines of the cut (it
/// was read as 5 frames without a word); a damaged ATOM record's error names its line.
#[test]
fn cut_or_damaged_pdb_models_name_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = crate::data_support::gunzipped("1mot.pdb.gz");
    let lines: Vec<&str> = text.lines().collect();
    let models: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with("MODEL"))
        .collect();
    let cut = lines[..models[5] + 100].join("\n");
    let p = write(dir.path(), "cut.pdb", cut.as_bytes());
    let t = io::open(&p, None).expect("models 0-4 are whole");
    assert_eq!(t.len(), 5);
    let damage = t.damage().expect("the cut model is damage");
    assert_eq!(damage.frame, 5);
    let start = format!("line {}", models[5] + 1);
    assert!(
        damage.error.to_string().contains(&start),
        "{}",
        damage.error
    );
    let o = surface(dir.path(), &[&p], &[], &[]);
    assert_one_line(&o, "cut.pdb", &["frame 5", &start]);
    assert_eq!(stats_frames(dir.path()), (0..5).collect::<Vec<_>>());
    // Model 0 cut: nothing whole, one line.
    let p = write(
        dir.path(),
        "cut0.pdb",
        lines[..models[0] + 100].join("\n").as_bytes(),
    );
    let e = io::open(&p, None).expect_err("no whole model");
    assert!(e.to_string().contains("line"), "{e}");
    // A damaged coordinate in model 3, at (1-based) line `at + 1`.
    let at = models[3] + 50;
    let mut damaged: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    damaged[at].replace_range(30..38, "  xx.x!y");
    let p = write(dir.path(), "bad.pdb", damaged.join("\n").as_bytes());
    let o = surface(dir.path(), &[&p], &[], &[]);
    assert_one_line(&o, "bad.pdb", &["frame 3", &format!("line {}:", at + 1)]);
    assert_eq!(stats_frames(dir.path()), vec![0, 1, 2]);
}

/// A reader process that answers with garbage (the test hook) is stopped: one line naming the
/// frame, the frames before it kept.
#[test]
fn reader_sending_garbage_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("adk_open.pdb");
    let dcd = data("adk_dims.dcd");
    let hook = [
        ("MDSURF_READER_GARBAGE_AT", "4"),
        ("MDSURF_NO_NATIVE_READ", "1"),
    ];
    let o = surface(dir.path(), &[&pdb, &dcd], &["--frames", "0:10"], &hook);
    assert_one_line(&o, "adk_dims.dcd", &["frame 4", "invalid reply"]);
    assert_eq!(stats_frames(dir.path()), (0..4).collect::<Vec<_>>());
}
