//! The inputs fuzzing found (issue #29), run through the real binary: every file kept in
//! `tests/fuzz/<target>/` (one folder per fuzz target of `fuzz/`, see `docs/fuzzing.md`; the
//! findings of `scripts/fuzz`, copied there by `scripts/fuzz keep` once fixed) goes to
//! `mdsurf surface FILE --stats out.csv` as a user's file would, with its target's extension.
//! Each run holds to the process rules of the mutation tests (`io_mutants::violation`: exit 0 or
//! 2, no signal, no panic text or library noise, one error line, within the time and memory
//! bounds), and an error line names the file. A coordinate-only format (XTC, TRR, DCD, Amber
//! NetCDF) needs a topology: the run is made with a one-atom GRO, and when that gives the
//! atom-count mismatch naming the file's count, again with a GRO of that many atoms, so that
//! the reader reads every frame.

use std::path::{Path, PathBuf};

use crate::io_mutants::{Outcome, run, violation};

/// The fuzz targets (folder names under `tests/fuzz/`), the extension each writes its input
/// with, and whether the format carries atom names (else a topology is needed).
const TARGETS: [(&str, &str, bool); 10] = [
    ("pdb", "pdb", true),
    ("mmcif", "cif", true),
    ("gro", "gro", true),
    ("xyz", "xyz", true),
    ("lammps", "lammpstrj", true),
    ("dcd", "dcd", false),
    ("netcdf", "nc", false),
    ("xtc", "xtc", false),
    ("trr", "trr", false),
    ("tng", "tng", true),
];

/// A generated topology has at most this many atoms (a hostile count is not built).
const MAX_TOPOLOGY_ATOMS: usize = 100_000;

/// The regression inputs: (target, file), in a stable order.
fn inputs() -> Vec<(&'static str, PathBuf)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz");
    let mut out = Vec::new();
    for entry in std::fs::read_dir(&root).expect("tests/fuzz") {
        let path = entry.unwrap().path();
        if !path.is_dir() {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let (target, ..) = TARGETS
            .iter()
            .find(|(t, ..)| *t == name)
            .unwrap_or_else(|| panic!("tests/fuzz/{name}: not a fuzz target folder"));
        for file in std::fs::read_dir(&path).unwrap() {
            out.push((*target, file.unwrap().path()));
        }
    }
    out.sort();
    out
}

/// A GRO file of `atoms` atoms (on a 3 Å grid) in `dir`.
fn topology(dir: &Path, atoms: usize) -> PathBuf {
    let mut text = format!("generated\n{atoms}\n");
    for i in 0..atoms {
        let (x, y, z) = (i % 40, i / 40 % 40, i / 1600);
        text += &format!(
            "{:>5}{:<5}{:>5}{:>5}{:8.3}{:8.3}{:8.3}\n",
            i / 10 % 100_000 + 1,
            "ALA",
            "CA",
            i % 100_000 + 1,
            x as f64 * 0.3,
            y as f64 * 0.3,
            z as f64 * 0.3
        );
    }
    text += "   5.0   5.0   5.0\n";
    let path = dir.join(format!("top{atoms}.gro"));
    std::fs::write(&path, text).unwrap();
    path
}

/// The atom count a mismatch error gives for `file` ("... trajectory FILE has N (frame 0)").
fn mismatched_count(stderr: &str, file: &Path) -> Option<usize> {
    let after = format!("trajectory {} has ", file.display());
    let at = stderr.find(&after)? + after.len();
    let digits: String = stderr[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

/// Runs `mdsurf surface [TOP] FILE --stats STATS` (CPU, coarse grid, quiet).
fn surface(topology: Option<&Path>, file: &Path, stats: &Path) -> Outcome {
    let mut args = vec!["surface".to_string()];
    args.extend(topology.map(|t| t.display().to_string()));
    args.push(file.display().to_string());
    args.extend(["--backend", "cpu", "--spacing", "2", "-q", "--stats"].map(String::from));
    args.push(stats.display().to_string());
    run(&args)
}

/// Why the run on `file` broke the rules, if it did.
fn broken(o: &Outcome, file: &Path) -> Option<String> {
    violation(o).or_else(|| {
        let name = file.file_name().unwrap().to_string_lossy();
        (o.code == Some(2) && !o.stderr.contains(&*name))
            .then(|| format!("the error does not name {name}"))
    })
}

#[test]
fn inputs_found_by_fuzzing_end_cleanly_in_the_binary() {
    let inputs = inputs();
    assert!(!inputs.is_empty(), "no regression inputs in tests/fuzz");
    let dir = tempfile::tempdir().unwrap();
    let one_atom = topology(dir.path(), 1);
    let mut failures = Vec::new();
    for (n, (target, source)) in inputs.iter().enumerate() {
        let (_, ext, named) = TARGETS.iter().find(|(t, ..)| t == target).unwrap();
        let file = dir.path().join(format!("input{n}.{ext}"));
        std::fs::copy(source, &file).unwrap();
        let stats = dir.path().join(format!("stats{n}.csv"));
        let mut runs = Vec::new();
        if *named {
            runs.push(surface(None, &file, &stats));
        } else {
            let first = surface(Some(&one_atom), &file, &stats);
            let count = mismatched_count(&first.stderr, &file);
            runs.push(first);
            if let Some(atoms) = count.filter(|&a| a <= MAX_TOPOLOGY_ATOMS) {
                let top = topology(dir.path(), atoms);
                runs.push(surface(Some(&top), &file, &stats));
            }
        }
        for o in &runs {
            if let Some(why) = broken(o, &file) {
                failures.push(format!("{}: {why}: {}", source.display(), o.stderr));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_coordinate_only_input_is_read_with_a_topology_of_its_atom_count() {
    // The seed XTC of 20 atoms: the one-atom run names the count, the second run reads frames.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("small.xtc");
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/xtc/small.xtc");
    std::fs::copy(seed, &file).unwrap();
    let stats = dir.path().join("stats.csv");
    let first = surface(Some(&topology(dir.path(), 1)), &file, &stats);
    assert_eq!(first.code, Some(2), "{}", first.stderr);
    assert_eq!(mismatched_count(&first.stderr, &file), Some(20));
    let second = surface(Some(&topology(dir.path(), 20)), &file, &stats);
    assert_eq!(second.code, Some(0), "{}", second.stderr);
    let rows = std::fs::read_to_string(&stats).unwrap();
    assert!(rows.lines().count() > 1, "no frames: {rows}");
}
