//! The selection language against an independent implementation: every row of
//! `tests/data/selection_counts.csv` (written by `scripts/selection_reference.py` with
//! MDAnalysis) is evaluated with mdsurf and must give exactly MDAnalysis's count. Also errors
//! (column of the bad token), precedence, globs and regexes on real files, residue identity
//! (runs, not numbers), and the `mdsurf select` command.

use std::collections::HashMap;
use std::path::PathBuf;

use mdsurf::io::Trajectory;
use mdsurf::model::{BeadModel, Frame};
use mdsurf::selection::Selection;

use crate::cli_common::mdsurf;
use crate::data_support::data;

/// Fields of one CSV line (RFC 4180 quoting: `"..."` with `""` for a quote).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                fields.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(String::new()),
            _ => fields.last_mut().unwrap().push(c),
        }
    }
    fields
}

/// A trajectory opened from a CSV `file` spec (`TOP` or `TOP TRAJ`) and its frame 0.
fn open(spec: &str) -> (Trajectory, Frame) {
    let files: Vec<PathBuf> = spec.split_whitespace().map(data).collect();
    let trajectory = mdsurf::io::open(&files[0], files.get(1).map(PathBuf::as_path))
        .unwrap_or_else(|e| panic!("{spec}: {e}"));
    let frame = trajectory.read_frame(0).expect("frame 0");
    (trajectory, frame)
}

fn count(trajectory: &Trajectory, frame: &Frame, text: &str) -> usize {
    let selection = Selection::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    selection.bind(trajectory.topology()).indices(frame).len()
}

#[test]
fn counts_match_mdanalysis() {
    let text = std::fs::read_to_string(data("selection_counts.csv")).expect("CSV");
    let mut lines = text.lines();
    assert_eq!(
        csv_fields(lines.next().expect("header")),
        [
            "file",
            "expression_mdsurf",
            "expression_mdanalysis",
            "count"
        ]
    );
    let mut systems: HashMap<String, (Trajectory, Frame)> = HashMap::new();
    let (mut rows, mut wrong) = (0, Vec::new());
    let mut files = std::collections::HashSet::new();
    for line in lines {
        let f = csv_fields(line);
        assert_eq!(f.len(), 4, "{line}");
        let expected: usize = f[3].parse().expect("count");
        let (trajectory, frame) = systems.entry(f[0].clone()).or_insert_with(|| open(&f[0]));
        let got = count(trajectory, frame, &f[1]);
        if got != expected {
            wrong.push(format!(
                "{}: '{}' gives {got}, MDAnalysis '{}' {expected}",
                f[0], f[1], f[2]
            ));
        }
        rows += 1;
        files.insert(f[0].split_whitespace().next().unwrap_or("").to_string());
    }
    assert!(rows >= 30 && files.len() >= 4, "{rows} rows over {files:?}");
    assert!(
        wrong.is_empty(),
        "{} of {rows} differ:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

#[test]
fn precedence_globs_and_regexes_on_a_real_file() {
    let (t, f) = open("adk_oplsaa.gro");
    let c = |s: &str| count(&t, &f, s);
    // not > and > or.
    assert_eq!(c("not protein and name CA"), 0);
    assert_eq!(c("name CA or name CB and resname ALA"), c("name CA") + 19);
    assert_eq!(
        c("(name CA or name CB) and resname ALA"),
        c("resname ALA and name CA CB")
    );
    assert_eq!(c("not not water"), c("water"));
    assert_eq!(c("protein or water and none"), c("protein"));
    // `within` takes everything to its right.
    assert_eq!(
        c("within 3 of ion or name CA"),
        c("within 3 of (ion or name CA)")
    );
    assert_eq!(c("name \"C[AB]\""), c("name C[AB]"));
    assert_eq!(c("name \"C.\""), c("name C?"));
    assert_eq!(
        c("name \"C\""),
        c("name C"),
        "a regex matches the whole name"
    );
    assert_eq!(c("resname \"AL.*\""), c("resname ALA"));
    assert_eq!(c("element h"), c("hydrogen"));
    assert_eq!(c("heavy"), c("noh"));
    assert_eq!(c("index 0 to 9 10:19"), 20);
}

#[test]
fn errors_give_the_column_of_the_first_bad_token() {
    let cases = [
        (
            "protein and resnam ALA",
            13,
            "unknown keyword 'resnam' (did you mean resname?)",
        ),
        ("name CA and", 12, "unexpected end of selection"),
        (
            "resid 5 to",
            11,
            "unexpected end of selection (expected a value)",
        ),
        ("(protein or water", 18, ""),
        ("protein water", 9, "unexpected 'water'"),
        ("resid ALA", 7, "'ALA' is not a number"),
        ("name > 3", 1, "takes names"),
        ("within of protein", 8, "distance"),
        ("name \"C[\"", 6, "bad regex"),
        ("protien or water", 1, "did you mean protein?"),
    ];
    for (text, column, message) in cases {
        let e = Selection::parse(text).expect_err(text);
        assert_eq!(e.column, column, "{text}: {e}");
        assert!(e.message.contains(message), "{text}: {e}");
        let line = e.to_string();
        assert!(line.starts_with(&format!("column {column}: ")) && !line.contains('\n'));
    }
}

#[test]
fn residues_are_runs_in_file_order() {
    // YiiP numbers protein residues and lipids from overlapping ranges: chemfiles alone merges
    // residues that share a number (566). Runs of (number, name) give 848, as MDAnalysis does.
    let (t, f) = open("YiiP_lipids.gro.gz");
    let top = t.topology();
    assert_eq!(top.residue_count(), 848);
    let beads = BeadModel::new(top, &f).expect("beads");
    assert_eq!(beads.len(), 848);
    // Every residue is one contiguous run with one name.
    for w in 0..top.len() - 1 {
        if top.residue_index[w] == top.residue_index[w + 1] {
            assert_eq!(&top.residue_names[w], &top.residue_names[w + 1]);
        } else {
            assert_eq!(top.residue_index[w] + 1, top.residue_index[w + 1]);
        }
    }
    assert_eq!(count(&t, &f, "resname POPE POPG"), 34610);
    assert_eq!(
        count(&t, &f, "same residue as index 43479"),
        127,
        "the last POPG"
    );
}

#[test]
fn topology_fields_from_files() {
    let (t, _) = open("1hpv.pdb");
    let top = t.topology();
    let n = top.len();
    for len in [
        top.types.len(),
        top.masses.len(),
        top.charges.len(),
        top.occupancies.len(),
        top.serials.len(),
        top.segments.len(),
    ] {
        assert_eq!(len, n);
    }
    assert_eq!(top.serials[0], 1);
    assert!(top.occupancies.iter().all(|&o| o == 1.0));
    assert!(top.masses.iter().all(|&m| m > 1.0), "masses from elements");
    let (t, _) = open("adk_oplsaa.gro");
    let top = t.topology();
    let ca = top.names.iter().position(|n| n == "CA").expect("CA");
    assert!(
        (top.masses[ca] - 12.011).abs() < 1e-3,
        "CA is carbon, not calcium"
    );
}

#[test]
fn select_command_prints_count_and_indices() {
    let dir = tempfile::tempdir().expect("tempdir");
    let top = data("1hpv.pdb");
    let top = top.to_str().expect("path");
    let run = mdsurf(
        dir.path(),
        &["select", top, "--indices", "resname 478 and name C1 C2"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert_eq!(run.stdout, "2\n1516 1517\n");
    let run = mdsurf(dir.path(), &["select", top, "water"]);
    assert_eq!((run.code, run.stdout.as_str()), (0, "80\n"));
    let gro = data("adk_oplsaa.gro");
    let xtc = data("adk_oplsaa.xtc");
    let args = ["select", gro.to_str().unwrap(), xtc.to_str().unwrap()];
    let run = mdsurf(
        dir.path(),
        &[&args[..], &["--frame", "3", "within 5 of protein"]].concat(),
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let expected = {
        let (t, _) = open("adk_oplsaa.gro adk_oplsaa.xtc");
        let frame = t.read_frame(3).expect("frame 3");
        count(&t, &frame, "within 5 of protein")
    };
    assert_eq!(run.stdout, format!("{expected}\n"));
    let run = mdsurf(dir.path(), &["select", top, "protein and resnam ALA"]);
    assert_eq!(run.code, 2);
    assert_eq!(run.stdout, "");
    assert_eq!(
        run.stderr.trim_end(),
        "error: selection 'protein and resnam ALA': column 13: unknown keyword 'resnam' \
         (did you mean resname?)"
    );
}

#[test]
fn within_ignores_a_placeholder_box() {
    // 5a7u.pdb (an NMR model) carries `CRYST1 1 1 1`: no periodic box, so `within` measures
    // plain distances, as the transforms and MDAnalysis treat it.
    let (trajectory, frame) = open("5a7u.pdb");
    assert!(frame.cell.is_some(), "the file has its placeholder box");
    let mut no_box = frame.clone();
    no_box.cell = None;
    for text in ["within 4 of resid 5", "within 6 of (name CA and resid 10)"] {
        let with = count(&trajectory, &frame, text);
        assert_eq!(with, count(&trajectory, &no_box, text), "{text}");
        assert!(with < trajectory.topology().len() / 4, "{text}: {with}");
    }
}
