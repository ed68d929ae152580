//! Hostile inputs (issue 10): files that are damaged the way real files get damaged (text in
//! Latin-1, a cut compressed stream, chunks of a trajectory duplicated or deleted, absurd sizes
//! and coordinates) must give a correct read or one line of error, never a crash, a hang, a
//! panic or a silently wrong result. The seeded mutation test is in `io_mutants`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use mdsurf::io::{self, IoError};

use crate::data_support::data;
use crate::io_mutants_binary::{le64, tng_molecule_count_at, tng_patched};

/// The result of one run of the binary with a time limit.
struct Outcome {
    /// Exit code, `None` when killed by a signal (or by the time limit).
    code: Option<i32>,
    stderr: String,
    timed_out: bool,
}

/// Runs `mdsurf ARGS` in `dir`, killing it after `limit`.
fn run_limited(dir: &Path, args: &[&str], limit: Duration) -> Outcome {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot start mdsurf");
    let mut stderr = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        std::io::Read::read_to_end(&mut stderr, &mut text).ok();
        String::from_utf8_lossy(&text).into_owned()
    });
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > limit {
            timed_out = true;
            child.kill().ok();
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Outcome {
        code: status.code(),
        stderr: reader.join().unwrap_or_default(),
        timed_out,
    }
}

/// Asserts a clean failure: exit 2, one line of stderr naming `name`, no panic text.
fn assert_clean_error(o: &Outcome, name: &str, what: &str) {
    assert!(!o.timed_out, "{what}: timed out");
    assert_eq!(o.code, Some(2), "{what}: {}", o.stderr);
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{what}: not one line: {}", o.stderr);
    assert!(
        lines[0].contains(name),
        "{what}: must name {name}: {}",
        o.stderr
    );
    assert!(!o.stderr.contains("panicked"), "{what}: {}", o.stderr);
}

fn surface(dir: &Path, files: &[&Path], extra: &[&str]) -> Outcome {
    surface_limited(dir, files, extra, Duration::from_secs(60))
}

fn surface_limited(dir: &Path, files: &[&Path], extra: &[&str], limit: Duration) -> Outcome {
    let mut args: Vec<String> = vec!["surface".into()];
    args.extend(files.iter().map(|p| p.to_string_lossy().into_owned()));
    args.extend(
        ["--backend", "cpu", "--spacing", "2", "-q"]
            .iter()
            .map(|s| s.to_string()),
    );
    args.extend(extra.iter().map(|s| s.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    run_limited(dir, &refs, limit)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

#[test]
fn latin1_gro_title_and_residue_name_read_correctly() {
    let dir = tempfile::tempdir().unwrap();
    let gro = std::fs::read(data("md_1u19.gro")).unwrap();
    let body = &gro[gro.iter().position(|&b| b == b'\n').unwrap() + 1..];
    let mut titled = b"Prot\xe9ine\n".to_vec();
    titled.extend_from_slice(body);
    let t = write(dir.path(), "t.gro", &titled);
    let good = io::open(&data("md_1u19.gro"), None).unwrap();
    let read = io::open(&t, None).expect("a Latin-1 title reads");
    assert_eq!(read.topology().names, good.topology().names);
    assert_eq!(
        read.read_frame(0).unwrap().positions,
        good.read_frame(0).unwrap().positions
    );
    // A Latin-1 byte in a residue name (columns 6-10 of the first atom line): the columns stay.
    let mut renamed = gro.clone();
    let line2 = gro.iter().position(|&b| b == b'\n').unwrap() + 1;
    let line3 = line2 + gro[line2..].iter().position(|&b| b == b'\n').unwrap() + 1;
    renamed[line3 + 8] = 0xe9;
    let r = write(dir.path(), "r.gro", &renamed);
    let read = io::open(&r, None).expect("a Latin-1 residue name reads");
    assert_eq!(
        read.read_frame(0).unwrap().positions,
        good.read_frame(0).unwrap().positions
    );
    assert!(read.topology().residue_names[0].contains('?'));
    let o = surface(dir.path(), &[&t], &[]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

#[test]
fn latin1_pdb_title_reads() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = std::fs::read(data("adk_open.pdb")).unwrap();
    let mut text = b"TITLE     ADENYLATE KINASE \xe9\xe8\xff\n".to_vec();
    text.extend_from_slice(&pdb);
    let p = write(dir.path(), "t.pdb", &text);
    let read = io::open(&p, None).expect("a Latin-1 TITLE reads");
    let good = io::open(&data("adk_open.pdb"), None).unwrap();
    assert_eq!(read.topology().len(), good.topology().len());
    let o = surface(dir.path(), &[&p], &[]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

#[test]
fn truncated_bz2_fails_fast_or_keeps_the_good_frames() {
    let dir = tempfile::tempdir().unwrap();
    let bz2 = std::fs::read(data("spce_all_coords.lammpstrj.bz2")).unwrap();
    let t = write(dir.path(), "t.lammpstrj.bz2", &bz2[..100]);
    let o = surface(dir.path(), &[&t], &[]);
    assert_clean_error(&o, "t.lammpstrj.bz2", "100 bytes of bz2");
    // Cut in the middle: the frames before the cut are read, the cut one is the damage.
    let half = write(dir.path(), "half.lammpstrj.bz2", &bz2[..bz2.len() / 2]);
    let whole = io::open(&data("spce_all_coords.lammpstrj.bz2"), None).unwrap();
    let cut = io::open(&half, None).expect("the frames before the cut open");
    assert!(!cut.is_empty() && cut.len() < whole.len(), "{}", cut.len());
    let damage = cut.damage().expect("the cut is reported");
    assert_eq!(damage.frame, cut.len());
    assert!(damage.error.to_string().contains("half.lammpstrj.bz2"));
    for k in 0..cut.len() {
        assert_eq!(
            cut.read_frame(k).unwrap().positions,
            whole.read_frame(k).unwrap().positions
        );
    }
}

/// `md_1u19.xtc` with `x[a..b]` inserted at `at` (or deleted when `at` is `None`).
fn spliced_xtc(dir: &Path, name: &str, at: Option<usize>, a: usize, b: usize) -> PathBuf {
    let x = std::fs::read(data("md_1u19.xtc")).unwrap();
    let bytes = match at {
        Some(at) => [&x[..at], &x[a..b], &x[at..]].concat(),
        None => [&x[..a], &x[b..]].concat(),
    };
    write(dir, name, &bytes)
}

#[test]
fn spliced_xtc_keeps_the_good_frames_and_never_aborts() {
    let dir = tempfile::tempdir().unwrap();
    let gro = data("md_1u19.gro");
    let whole = io::open(&gro, Some(&data("md_1u19.xtc"))).unwrap();
    // The repro: a chunk inserted inside frame 0, so no frame is sound.
    let d = spliced_xtc(dir.path(), "d.xtc", Some(12171), 37480, 40106);
    let e = io::open(&gro, Some(&d)).expect_err("frame 0 is damaged");
    assert!(e.to_string().contains("d.xtc"), "{e}");
    let o = surface(dir.path(), &[Path::new(&gro), &d], &[]);
    assert_clean_error(&o, "d.xtc", "d.xtc");
    for (name, at, a, b) in [
        ("dup.xtc", Some(150_000), 37480, 40106),
        ("del.xtc", None, 200_000, 203_000),
        ("dup2.xtc", Some(500_000), 100, 3000),
    ] {
        let d = spliced_xtc(dir.path(), name, at, a, b);
        let t = io::open(&gro, Some(&d)).expect("the frames before the damage open");
        let damage = t.damage().expect("the damage is reported");
        assert_eq!(damage.frame, t.len());
        assert!(t.len() < whole.len());
        assert!(damage.error.to_string().contains(name), "{}", damage.error);
        for k in 0..t.len() {
            assert_eq!(
                t.read_frame(k).unwrap().positions,
                whole.read_frame(k).unwrap().positions,
                "{name} frame {k}"
            );
        }
        let o = surface(dir.path(), &[Path::new(&gro), &d], &["--frames", "0:60"]);
        assert_clean_error(&o, name, name);
    }
}

#[test]
fn absurd_atom_counts_fail_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    // DCD: the atom-count record follows the 84-byte header and the title record.
    let mut dcd = std::fs::read(data("adk_dims.dcd")).unwrap();
    let title = u32::from_le_bytes(dcd[92..96].try_into().unwrap()) as usize;
    let at = 92 + 4 + title + 4 + 4;
    dcd[at..at + 4].copy_from_slice(&0x7fff_ffffu32.to_le_bytes());
    let d = write(dir.path(), "big.dcd", &dcd);
    let e = io::open(&data("adk_open.pdb"), Some(&d)).expect_err("absurd DCD atom count");
    assert!(e.to_string().contains("2147483647"), "{e}");
    let o = surface(dir.path(), &[&data("adk_open.pdb"), &d], &[]);
    assert_clean_error(&o, "big.dcd", "DCD natoms");
    // XTC: both atom counts of the first frame header.
    let mut xtc = std::fs::read(data("md_1u19.xtc")).unwrap();
    for at in [4, 52] {
        xtc[at..at + 4].copy_from_slice(&0x7fff_ffffi32.to_be_bytes());
    }
    let x = write(dir.path(), "big.xtc", &xtc);
    let e = io::open(&data("md_1u19.gro"), Some(&x)).expect_err("absurd XTC atom count");
    assert!(e.to_string().contains("big.xtc"), "{e}");
    let o = surface(dir.path(), &[&data("md_1u19.gro"), &x], &[]);
    assert_clean_error(&o, "big.xtc", "XTC natoms");
}

#[test]
fn absurd_coordinate_names_frame_and_atom() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for frame in 0..2 {
        text.push_str("20\nframe\n");
        for i in 0..20 {
            let x = if frame == 1 && i == 7 {
                "1e30".to_string()
            } else {
                format!("{}", i as f64 * 1.5)
            };
            text.push_str(&format!("C {x} 0.0 0.0\n"));
        }
    }
    let p = write(dir.path(), "far.xyz", text.as_bytes());
    let t = io::open(&p, None).unwrap();
    let e = t.read_frame(1).expect_err("1e30 Å is damage");
    assert!(
        matches!(
            e,
            IoError::AbsurdCoordinate {
                frame: 1,
                atom: 7,
                ..
            }
        ),
        "{e}"
    );
    let o = surface(dir.path(), &[&p], &["--frames", "1:2"]);
    assert_clean_error(&o, "far.xyz", "1e30");
    assert!(
        o.stderr.contains("frame 1") && o.stderr.contains("atom 7"),
        "{}",
        o.stderr
    );
}

#[test]
fn trr_cut_mid_frame_is_damage() {
    let dir = tempfile::tempdir().unwrap();
    let (pdb, trr) = (dir.path().join("t.pdb"), dir.path().join("t.trr"));
    let make = |k: usize| {
        let mut f = chemfiles::Frame::new();
        for i in 0..12 {
            let p = [i as f64 * 1.3, k as f64 * 0.1, 0.5 * (i % 3) as f64];
            f.add_atom(&chemfiles::Atom::new("O"), p, None);
        }
        f
    };
    chemfiles::Trajectory::open(&pdb, 'w')
        .unwrap()
        .write(&make(0))
        .unwrap();
    let mut t = chemfiles::Trajectory::open(&trr, 'w').unwrap();
    (0..6).for_each(|k| t.write(&make(k)).unwrap());
    drop(t);
    let whole = std::fs::read(&trr).unwrap();
    assert_eq!(io::open(&pdb, Some(&trr)).unwrap().len(), 6);
    let cut = write(dir.path(), "cut.trr", &whole[..whole.len() - 40]);
    let t = io::open(&pdb, Some(&cut)).unwrap();
    assert_eq!(t.len(), 5);
    let damage = t.damage().expect("the cut frame is reported");
    assert_eq!(damage.frame, 5);
    assert!(
        damage.error.to_string().contains("truncated"),
        "{}",
        damage.error
    );
}

#[test]
fn render_rejects_nan_view_and_turntable() {
    let dir = tempfile::tempdir().unwrap();
    let gro = data("md_1u19.gro");
    for bad in [
        ["--view", "nan,nan"],
        ["--turntable", "nan"],
        ["--turntable", "inf"],
    ] {
        let args = [
            "render",
            gro.to_str().unwrap(),
            "-o",
            "x.png",
            bad[0],
            bad[1],
        ];
        let o = run_limited(dir.path(), &args, Duration::from_secs(30));
        assert_eq!(o.code, Some(2), "{bad:?}: {}", o.stderr);
        assert!(o.stderr.contains(bad[1]), "{bad:?}: {}", o.stderr);
        assert!(!dir.path().join("x.png").exists());
    }
}

#[test]
fn damaged_tng_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let t = std::fs::read(data("argon_npt_compressed.tng")).unwrap();
    let spliced = [&t[..401_508], &t[39_590..42_474], &t[401_508..]].concat();
    let d = write(dir.path(), "d.tng", &spliced);
    let o = surface(dir.path(), &[&d], &[]);
    assert_clean_error(&o, "d.tng", "spliced TNG");
    let mut flipped = t.clone();
    flipped[200_000] ^= 0x10;
    let f = write(dir.path(), "f.tng", &flipped);
    let e = io::open(&f, None).expect_err("a flipped byte fails the block checksum");
    assert!(e.to_string().contains("checksum"), "{e}");
    assert!(io::open(&data("argon_npt_compressed.tng"), None).is_ok());
}

/// The TNG library takes the atom count from the MOLECULES block and trusts it: a molecule count
/// of 32,768 (MD5 recomputed) in the 1,000-atom argon file read 32,768 atoms of garbage with exit
/// 0, and 999 aborted the reader. Each is one line naming the file, the count and what the
/// positions hold.
#[test]
fn tng_with_a_hostile_molecule_count_is_refused_naming_the_count() {
    let dir = tempfile::tempdir().unwrap();
    let t = std::fs::read(data("argon_npt_compressed.tng")).unwrap();
    let count = tng_molecule_count_at(&t);
    assert_eq!(le64(&t, count), 1000);
    for (value, holds) in [
        (32_768, "hold 1000"),
        (1 << 31, "hold 1000"),
        (999, "holds atoms 0 to 999"),
        (0, "holds atoms 0 to 999"),
        (-1, "-1 molecules"),
    ] {
        let name = format!("count{value}.tng");
        let path = write(dir.path(), &name, &tng_patched(&t, count, value));
        let o = surface(dir.path(), &[&path], &[]);
        assert_clean_error(&o, &name, &name);
        for part in ["MOLECULES", &value.to_string(), holds] {
            assert!(o.stderr.contains(part), "{name}: no '{part}': {}", o.stderr);
        }
    }
}

#[test]
fn render_and_surface_both_refuse_a_missing_output_folder() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let missing = dir.path().join("no_such_folder");
    let png = missing.join("a.png");
    let o = run_limited(
        dir.path(),
        &[
            "render",
            pdb.to_str().unwrap(),
            "--size",
            "32x32",
            "-o",
            png.to_str().unwrap(),
        ],
        Duration::from_secs(60),
    );
    assert_clean_error(&o, "no_such_folder", "render into a missing folder");
    let ply = missing.join("a.ply");
    let o = surface(dir.path(), &[&pdb], &["-o", ply.to_str().unwrap()]);
    assert_clean_error(&o, "no_such_folder", "surface into a missing folder");
    assert!(!missing.exists(), "a folder was created");
}

/// An `.xz` file reads like the plain one; a cut one keeps its whole frames and names the cut.
#[test]
fn xz_files_are_decompressed_in_rust() {
    let dir = tempfile::tempdir().unwrap();
    let mut dump = Vec::new();
    std::io::Read::read_to_end(
        &mut bzip2::read::BzDecoder::new(
            &std::fs::read(data("spce_all_coords.lammpstrj.bz2")).unwrap()[..],
        ),
        &mut dump,
    )
    .unwrap();
    let plain = write(dir.path(), "d.lammpstrj", &dump);
    let mut xz = Vec::new();
    let mut encoder =
        lzma_rust2::XzWriter::new(&mut xz, lzma_rust2::XzOptions::with_preset(1)).unwrap();
    std::io::Write::write_all(&mut encoder, &dump).unwrap();
    encoder.finish().unwrap();
    let whole = write(dir.path(), "d.lammpstrj.xz", &xz);
    let a = io::open(&plain, None).unwrap();
    let b = io::open(&whole, None).expect("an .xz file reads");
    assert_eq!(a.len(), b.len());
    assert_eq!(
        a.read_frame(a.len() - 1).unwrap().positions,
        b.read_frame(b.len() - 1).unwrap().positions
    );
    let cut = write(dir.path(), "c.lammpstrj.xz", &xz[..xz.len() / 2]);
    let c = io::open(&cut, None).expect("a cut .xz keeps its good frames");
    assert!(
        !c.is_empty() && c.len() < a.len(),
        "{} of {}",
        c.len(),
        a.len()
    );
    assert_eq!(
        c.read_frame(0).unwrap().positions,
        a.read_frame(0).unwrap().positions
    );
    let damage = c.damage().expect("the cut is reported");
    assert!(
        damage.error.to_string().contains("c.lammpstrj.xz"),
        "{}",
        damage.error
    );
}

/// A TNG damaged in its last frame set keeps the whole frame sets before it, frame for frame.
#[test]
fn damaged_tng_keeps_the_frame_sets_before_the_damage() {
    let dir = tempfile::tempdir().unwrap();
    let original = std::fs::read(data("argon_npt_compressed.tng")).unwrap();
    let good = io::open(&data("argon_npt_compressed.tng"), None).unwrap();
    let mut flipped = original.clone();
    // A byte inside the last frame set's data (its frame-set block starts at byte 398,576).
    flipped[400_500] ^= 0x10;
    for (name, bytes) in [
        ("flip.tng", flipped),
        ("cut.tng", original[..400_000].to_vec()),
        // Cut exactly at a block boundary: every block is whole, the index points past the end.
        ("boundary.tng", original[..398_576].to_vec()),
    ] {
        let path = write(dir.path(), name, &bytes);
        let read = io::open(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            !read.is_empty() && read.len() < good.len(),
            "{name}: {}",
            read.len()
        );
        let damage = read.damage().expect("the damage is reported");
        assert_eq!(damage.frame, read.len());
        assert!(damage.error.to_string().contains(name), "{}", damage.error);
        for k in [0, read.len() - 1] {
            assert_eq!(
                read.read_frame(k).unwrap().positions,
                good.read_frame(k).unwrap().positions,
                "{name} frame {k}"
            );
        }
    }
}
