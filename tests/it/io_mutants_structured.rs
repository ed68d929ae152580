//! The structured mutation test of issue 29: seeded mutants that know each format's layout, 100
//! per format (PDB, GRO, XYZ, LAMMPS dump, mmCIF, XTC, TRR, DCD, Amber NetCDF, TNG), run through
//! the real binary (`mdsurf surface ... --stats`) under the process rules of `io_mutants`
//! (exit 0 or 2, no signal, no panic, no library noise, one line of error, bounded memory and
//! time). The edits themselves are in `io_mutants_text` and `io_mutants_binary`. On top of the
//! process rules each mutant says what its run must give ([`Expect`]):
//! - a legal variant (UTF-8 BOM, CRLF or CR-only line ends, tabs for spaces, blank lines where
//!   the format allows them, no final newline, a DCD with another title count) reads exactly as
//!   the unmutated file: exit 0 and the same per-frame atoms, area and volume;
//! - a cut inside frame k keeps frames 0..k-1 (their statistics as the unmutated file's) and
//!   ends with exit 2 and one line naming `frame k`; a cut at a frame boundary keeps every
//!   whole frame with exit 0 (exit 2 naming the cut frame where the header promises more:
//!   NetCDF's record count, TNG's index); a cut in frame 0 names frame 0 too (NetCDF's
//!   header check once called a file too short for one frame a damaged header); a cut in the
//!   first frame set of a TNG run (it starts at frame 98) need only end with exit 2;
//! - a hostile header field, count, record length or value either reads every frame with every
//!   atom (exit 0: no silent loss) or ends with exit 2, and when that line names `frame K` the
//!   statistics hold frames 0..K-1.
//!
//! The inputs are the real files of `tests/data` (cut to a few frames to keep runs short) and
//! an XYZ, a TRR and an Amber NetCDF that chemfiles writes here from `md_1u19.xtc`. TNG runs
//! start at frame 98 (`--frames 98:`), so that decoding a hostile frame set stays quick; the
//! test file's frame sets hold frames 0-99 and 100.
//!
//! More mutants: `MDSURF_STRUCTURED_MUTANTS=1000 MDSURF_MUTANT_SEED=7 cargo test --release
//! --features test-hooks --test it io_mutants_structured -- --nocapture` (or `scripts/mutants`).
//! A failing mutant is kept in the temporary folder (its path is printed).

use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::data_support::data;
use crate::io_mutants::{Outcome, Rng, env_or, run, violation};
use crate::io_mutants_binary::{
    Binary, binary_frames, le64, mutate_binary, tng_molecule_count_at, tng_patched,
    tng_positions_count_at,
};
use crate::io_mutants_text::{Text, TextLayout, mutate_text};

/// Mutants per format in CI.
const DEFAULT_PER_FORMAT: usize = 100;
/// The committed seed.
const DEFAULT_SEED: u64 = 0x5eed_2929;

/// What a mutant's run must give.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Expect {
    /// A legal variant: exit 0 and the unmutated file's statistics.
    Same,
    /// Frames before `upto` kept as in the unmutated file, then `exit` (2: one line naming
    /// `frame upto`).
    Frames { upto: usize, exit: i32 },
    /// Anything clean: every frame and atom (exit 0) or one line (exit 2) after the frames it
    /// names as kept.
    Hostile,
    /// The process rules only, and on exit 2 the frames the error names as kept: an edit that
    /// makes another well-formed file (a TNG block id or contents changed, its MD5 recomputed:
    /// a frame set without positions is legal TNG).
    Clean,
}

/// One frame (TNG: frame set) of an unmutated file: its index, first byte, and the bytes where
/// a cut makes it incomplete.
#[derive(Clone, Debug)]
pub(crate) struct Frame {
    pub(crate) index: usize,
    pub(crate) start: usize,
    pub(crate) cut: Range<usize>,
}

/// One item of `items`, chosen by `rng`.
pub(crate) fn pick<T: Clone>(rng: &mut Rng, items: &[T]) -> T {
    items[rng.below(items.len())].clone()
}

#[derive(Clone, Copy)]
enum Layout {
    Text(Text),
    Binary(Binary),
}

/// One format under test.
struct Subject {
    name: &'static str,
    bytes: Vec<u8>,
    topology: Option<PathBuf>,
    extension: &'static str,
    layout: Layout,
    /// The first frame processed (`--frames FIRST:`).
    first: usize,
    text: Option<TextLayout>,
    frames: Vec<Frame>,
}

impl Subject {
    fn new(
        name: &'static str,
        bytes: Vec<u8>,
        topology: Option<PathBuf>,
        extension: &'static str,
        layout: Layout,
        frame_count: usize,
    ) -> Subject {
        let (text, frames) = match layout {
            Layout::Text(format) => {
                let t = TextLayout::new(format, &bytes);
                let frames = t.frames();
                (Some(t), frames)
            }
            Layout::Binary(format) => (None, binary_frames(format, &bytes, frame_count)),
        };
        let last = frames.last().map_or(0, |f| f.index + 1);
        assert!(
            matches!(layout, Layout::Text(Text::Cif)) || last == frame_count,
            "{name}: {last} frames found, {frame_count} expected"
        );
        let first = if matches!(layout, Layout::Binary(Binary::Tng)) {
            98
        } else {
            0
        };
        Subject {
            name,
            bytes,
            topology,
            extension,
            layout,
            first,
            text,
            frames,
        }
    }

    fn mutate(&self, rng: &mut Rng) -> (Vec<u8>, Expect, String) {
        match (self.layout, &self.text) {
            (Layout::Text(_), Some(t)) => mutate_text(t, &self.bytes, rng),
            (Layout::Binary(format), _) => mutate_binary(format, &self.bytes, &self.frames, rng),
            _ => unreachable!("a text subject has its layout"),
        }
    }
}

/// The first `frames` frames of `md_1u19.xtc` (with `md_1u19.gro`'s atoms) written by
/// chemfiles as `format` in `dir`.
fn written_by_chemfiles(dir: &Path, name: &str, format: &str, frames: usize) -> Vec<u8> {
    let path = dir.join(name);
    {
        let mut input = chemfiles::Trajectory::open(data("md_1u19.xtc"), 'r').unwrap();
        input.set_topology_file(data("md_1u19.gro")).unwrap();
        let mut output = chemfiles::Trajectory::open_with_format(&path, 'w', format).unwrap();
        let mut frame = chemfiles::Frame::new();
        for step in 0..frames {
            input.read_step(step, &mut frame).unwrap();
            output.write(&frame).unwrap();
        }
    }
    std::fs::read(path).unwrap()
}

fn subjects(dir: &Path) -> Vec<Subject> {
    let read = |name: &str| std::fs::read(data(name)).expect("test data");
    let gro = Some(data("md_1u19.gro"));
    // PDB: the first four NMR models of 1mot.
    let mot = crate::data_support::gunzipped("1mot.pdb.gz");
    let fifth = mot
        .match_indices("MODEL")
        .filter(|(i, _)| *i == 0 || mot.as_bytes()[i - 1] == b'\n')
        .nth(4)
        .map_or(mot.len(), |(i, _)| i);
    let pdb = format!("{}END\n", &mot[..fifth]).into_bytes();
    // GRO: three frames (the file three times).
    let gro_text = read("md_1u19.gro").repeat(3);
    // LAMMPS: the first four frames of the bzip2 dump.
    let mut dump = Vec::new();
    bzip2::read::BzDecoder::new(&read("spce_all_coords.lammpstrj.bz2")[..])
        .read_to_end(&mut dump)
        .expect("bunzip2");
    let fifth = dump
        .windows(15)
        .enumerate()
        .filter(|(_, w)| *w == b"\nITEM: TIMESTEP")
        .nth(3);
    dump.truncate(fifth.map_or(dump.len(), |(i, _)| i + 1));
    // XTC: the first six frames.
    let xtc = read("md_1u19.xtc");
    let xtc_frames = binary_frames(Binary::Xtc, &xtc, 51);
    let xtc = xtc[..xtc_frames[6].start].to_vec();
    // DCD: the first six frames, the header's frame count (NSET) set to 6.
    let mut dcd = read("adk_dims.dcd");
    let dcd_size = 356 + 6 * 3 * (3341 * 4 + 8);
    dcd.truncate(dcd_size);
    dcd[8..12].copy_from_slice(&6i32.to_le_bytes());
    let (text, binary) = (Layout::Text, Layout::Binary);
    vec![
        Subject::new("PDB", pdb, None, "pdb", text(Text::Pdb), 4),
        Subject::new("GRO", gro_text, None, "gro", text(Text::Gro), 3),
        Subject::new(
            "XYZ",
            written_by_chemfiles(dir, "w.xyz", "XYZ", 4),
            None,
            "xyz",
            text(Text::Xyz),
            4,
        ),
        Subject::new("LAMMPS", dump, None, "lammpstrj", text(Text::Lammps), 4),
        Subject::new(
            "mmCIF",
            crate::data_support::gunzipped("1gbt.cif.gz").into_bytes(),
            None,
            "cif",
            text(Text::Cif),
            1,
        ),
        Subject::new("XTC", xtc, gro.clone(), "xtc", binary(Binary::Xtc), 6),
        Subject::new(
            "TRR",
            written_by_chemfiles(dir, "w.trr", "TRR", 6),
            gro.clone(),
            "trr",
            binary(Binary::Trr),
            6,
        ),
        Subject::new(
            "DCD",
            dcd,
            Some(data("adk_open.pdb")),
            "dcd",
            binary(Binary::Dcd),
            6,
        ),
        Subject::new(
            "NetCDF",
            written_by_chemfiles(dir, "w.nc", "Amber NetCDF", 6),
            gro,
            "nc",
            binary(Binary::NetCdf),
            6,
        ),
        Subject::new(
            "TNG",
            read("argon_npt_compressed.tng"),
            None,
            "tng",
            binary(Binary::Tng),
            101,
        ),
    ]
}

/// One row of `--stats`: frame, atoms, area (Å²), volume (Å³).
#[derive(Clone, Debug, PartialEq)]
struct Row {
    frame: usize,
    atoms: String,
    area: f64,
    volume: f64,
}

/// The rows of a `--stats` file (none when it is missing).
fn rows(path: &Path) -> Vec<Row> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Vec::new();
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .expect("stats column")
    };
    let (f, n, a, v) = (col("frame"), col("atoms"), col("area_A2"), col("volume_A3"));
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            Row {
                frame: c[f].parse().expect("frame"),
                atoms: c[n].to_string(),
                area: c[a].parse().unwrap_or(f64::NAN),
                volume: c[v].parse().unwrap_or(f64::NAN),
            }
        })
        .collect()
}

/// Rows alike: same frame and atoms, area and volume within 1e-6 (threads sum in any order).
fn same_rows(a: &[Row], b: &[Row]) -> bool {
    let close =
        |x: f64, y: f64| (x - y).abs() <= 1e-6 * x.abs().max(1.0) || (x.is_nan() && y.is_nan());
    a.len() == b.len()
        && a.iter().zip(b).all(|(a, b)| {
            a.frame == b.frame
                && a.atoms == b.atoms
                && close(a.area, b.area)
                && close(a.volume, b.volume)
        })
}

/// Runs `mdsurf surface` on `file` (a mutant of `s`), the statistics going to `stats`.
fn run_surface(s: &Subject, file: &Path, stats: &Path) -> (Outcome, Vec<Row>) {
    let mut args = vec!["surface".to_string()];
    args.extend(s.topology.iter().map(|t| t.display().to_string()));
    args.push(file.display().to_string());
    // One surface of all atoms: its atom count is every atom read.
    for a in [
        "--backend",
        "cpu",
        "--spacing",
        "2",
        "-q",
        "--no-timings",
        "--select",
        "all",
        "--stats",
    ] {
        args.push(a.to_string());
    }
    args.push(stats.display().to_string());
    if s.first > 0 {
        args.extend(["--frames".to_string(), format!("{}:", s.first)]);
    }
    let o = run(&args);
    let r = rows(stats);
    (o, r)
}

/// The frame an error line names (`FILE: frame K: ...`), if it names one.
fn named_frame(stderr: &str) -> Option<usize> {
    let at = stderr.find(": frame ")? + 8;
    let digits: String = stderr[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    stderr[at + digits.len()..]
        .starts_with(':')
        .then(|| digits.parse().ok())?
}

/// Why a mutant's run breaks what it must give (after the process rules), if it does.
fn broken(s: &Subject, expect: Expect, base: &[Row], o: &Outcome, got: &[Row]) -> Option<String> {
    if let Some(why) = violation(o) {
        return Some(why);
    }
    let frames: Vec<usize> = {
        let mut f: Vec<usize> = got.iter().map(|r| r.frame).collect();
        f.dedup();
        f
    };
    let kept =
        |upto: usize| -> Vec<Row> { base.iter().filter(|r| r.frame < upto).cloned().collect() };
    match expect {
        Expect::Same if o.code != Some(0) => Some("a legal variant was refused".into()),
        Expect::Same if !same_rows(got, base) => {
            Some(format!("a legal variant read differently: {got:?}"))
        }
        Expect::Frames { exit, .. } if o.code != Some(exit) => {
            Some(format!("exit {:?}, not {exit}", o.code))
        }
        Expect::Frames { upto, exit }
            if exit == 2
                && named_frame(&o.stderr) != Some(upto)
                && (upto > s.first || s.first == 0) =>
        {
            Some(format!("the error does not name frame {upto}"))
        }
        Expect::Frames { upto, .. } if !same_rows(got, &kept(upto)) => Some(format!(
            "frames {frames:?} kept, not {}..{upto} as read before",
            s.first
        )),
        Expect::Hostile if o.code == Some(0) && (!same_frames(got, base)) => Some(format!(
            "exit 0 with frames or atoms lost: frames {frames:?}"
        )),
        Expect::Hostile | Expect::Clean if o.code == Some(2) => match named_frame(&o.stderr) {
            Some(k) if frames != (s.first..k).collect::<Vec<_>>() => Some(format!(
                "the error names frame {k}, frames {frames:?} were kept"
            )),
            _ => None,
        },
        _ => None,
    }
}

/// Same frames and atom counts (positions may differ: a hostile value may be a legal one).
fn same_frames(a: &[Row], b: &[Row]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(a, b)| a.frame == b.frame && a.atoms == b.atoms)
}

/// The unmutated file's run: exit 0 with every frame; its statistics.
fn baseline(s: &Subject, dir: &Path) -> Vec<Row> {
    let file = dir.join(format!("base.{}", s.extension));
    std::fs::write(&file, &s.bytes).unwrap();
    let (o, rows) = run_surface(s, &file, &dir.join(format!("base_{}.csv", s.name)));
    assert!(
        violation(&o).is_none() && o.code == Some(0),
        "{}: {}",
        s.name,
        o.stderr
    );
    assert!(!rows.is_empty(), "{}: no statistics", s.name);
    rows
}

/// The mutants that found reader bugs, kept as small fixed cases.
#[test]
fn mutants_that_found_bugs_stay_fixed() {
    let dir = tempfile::tempdir().unwrap();
    let xyz_bytes = written_by_chemfiles(dir.path(), "w.xyz", "XYZ", 3);
    let xyz = Subject::new("XYZ", xyz_bytes, None, "xyz", Layout::Text(Text::Xyz), 3);
    let tng_bytes = std::fs::read(data("argon_npt_compressed.tng")).unwrap();
    let tng = Subject::new(
        "TNG",
        tng_bytes,
        None,
        "tng",
        Layout::Binary(Binary::Tng),
        101,
    );
    let mut cases: Vec<(&Subject, &str, Vec<u8>, Expect)> = Vec::new();
    // XYZ (read by chemfiles): a cut in frame 2 lost frames 0 and 1 too; a BOM made the first
    // atom count unreadable.
    let cut = xyz.frames[2].cut.start + 100;
    let frames_0_1 = Expect::Frames { upto: 2, exit: 2 };
    cases.push((
        &xyz,
        "XYZ cut in frame 2",
        xyz.bytes[..cut].to_vec(),
        frames_0_1,
    ));
    let bom = [b"\xef\xbb\xbf".as_slice(), &xyz.bytes].concat();
    cases.push((&xyz, "XYZ with a BOM", bom, Expect::Same));
    // TNG: a first block with another id read without the last frame set (exit 0, frame 100
    // lost); a frame set's id -1 gave the TNG library's words ("... in the TNG library").
    let mut first_id = tng.bytes.clone();
    first_id[16..24].copy_from_slice(&i64::MIN.to_le_bytes());
    cases.push((&tng, "TNG block 0 id", first_id, Expect::Hostile));
    let set = tng.frames[0].start + 16;
    let mut set_id = tng.bytes.clone();
    set_id[set..set + 8].copy_from_slice(&(-1i64).to_le_bytes());
    cases.push((&tng, "TNG frame set id", set_id, Expect::Hostile));
    // TNG cut inside the block that starts frame set 1: frame set 0 was lost too.
    let cut = tng.bytes[..tng.frames[1].start + 103].to_vec();
    let upto_100 = Expect::Frames { upto: 100, exit: 2 };
    cases.push((&tng, "TNG cut in a frame-set block", cut, upto_100));
    // TNG atom counts with their MD5 recomputed: a molecule count of 32,768 (the file holds
    // 1,000 atoms) read 32,768 atoms with exit 0; a positions block of frame set 1 holding 500
    // atoms is damage in frame 100 (frame set 0 kept).
    let count = tng_molecule_count_at(&tng.bytes);
    assert_eq!(le64(&tng.bytes, count), 1000);
    let molecules = tng_patched(&tng.bytes, count, 32_768);
    cases.push((&tng, "TNG molecule count", molecules, Expect::Hostile));
    let held = tng_positions_count_at(&tng.bytes, 1);
    assert_eq!(le64(&tng.bytes, held), 1000);
    let positions = tng_patched(&tng.bytes, held, 500);
    cases.push((&tng, "TNG frame set 1 atom count", positions, upto_100));
    let bases = [baseline(&xyz, dir.path()), baseline(&tng, dir.path())];
    for (n, (s, what, bytes, expect)) in cases.into_iter().enumerate() {
        let path = dir.path().join(format!("fixed{n}.{}", s.extension));
        std::fs::write(&path, bytes).unwrap();
        let (o, got) = run_surface(s, &path, &path.with_extension("csv"));
        let base = &bases[usize::from(s.name == "TNG")];
        let why = broken(s, expect, base, &o, &got);
        assert!(why.is_none(), "{what}: {why:?}: {}", o.stderr);
    }
}

#[test]
fn structured_mutants_of_every_format_end_as_they_must() {
    let per_format: usize = env_or("MDSURF_STRUCTURED_MUTANTS", DEFAULT_PER_FORMAT);
    let seed: u64 = env_or("MDSURF_MUTANT_SEED", DEFAULT_SEED);
    let dir = tempfile::tempdir().unwrap();
    let subjects = subjects(dir.path());
    let base: Vec<Vec<Row>> = subjects.iter().map(|s| baseline(s, dir.path())).collect();
    let mut jobs = Vec::new();
    for (c, s) in subjects.iter().enumerate() {
        let mut rng = Rng(seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(c as u64 + 1)));
        for k in 0..per_format {
            let (bytes, expect, label) = s.mutate(&mut rng);
            let path = dir.path().join(format!("m{c}_{k}.{}", s.extension));
            std::fs::write(&path, bytes).expect("write mutant");
            jobs.push((c, k, path, expect, label));
        }
    }
    let pooled = crate::io_mutants::run_pool(&jobs, subjects.len(), |job| {
        let (c, k, path, expect, label) = job;
        let s = &subjects[*c];
        let stats = path.with_extension("csv");
        let (o, got) = run_surface(s, path, &stats);
        let failure = broken(s, *expect, &base[*c], &o, &got).map(|why| {
            let kept = std::env::temp_dir().join(format!(
                "mdsurf_structured_{seed:x}_{c}_{k}.{}",
                s.extension
            ));
            std::fs::copy(path, &kept).ok();
            format!(
                "{} mutant {k} ({label}; {expect:?}; kept as {}): {why}: {}",
                s.name,
                kept.display(),
                o.stderr.trim()
            )
        });
        (*c, o, failure)
    });
    let (counts, failures) = pooled;
    crate::io_mutants::report(
        subjects.iter().map(|s| s.name),
        counts,
        failures,
        jobs.len(),
        "structured mutants",
    );
}
