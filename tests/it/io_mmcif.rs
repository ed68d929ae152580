//! Our mmCIF reader (issue 29: chemfiles' reader crashed on legal files). On every mmCIF file in
//! `tests/data`, compressed and plain, `io::open` (our reader) gives what
//! `io::open_via_chemfiles` (the chemfiles path it replaced) gives: names, types, elements,
//! residues, chains, segments, radii, masses, charges, bonds, every frame's positions and box.
//! Legal files chemfiles crashed on (a blank line inside the `_atom_site` loop, tabs in atom rows,
//! CRLF line ends, a row split over lines, quoted values) read with the same atoms as the
//! original; damaged rows give one line of error naming the file and the line.

use std::path::{Path, PathBuf};

use mdsurf::io::{self, Trajectory};

use crate::data_support::{data, gunzipped};

/// The mmCIF files of `tests/data`.
const FILES: [&str; 5] = [
    "1a7g.cif.gz",
    "1gbt.cif.gz",
    "2ofg.cif.gz",
    "4zhl.cif.gz",
    "7cfn.cif.gz",
];

fn open(path: &Path) -> Trajectory {
    io::open(path, None).unwrap_or_else(|e| panic!("{e}"))
}

/// Writes `text` as `name` in `dir`.
fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Asserts that `a` and `b` hold the same atoms (all but B-factors, occupancies and serials,
/// see [`same_wwpdb_columns`]) and the same frames (or the same errors reading them).
fn same_atoms_and_frames(a: &Trajectory, b: &Trajectory, name: &str) {
    let (x, y) = (a.topology(), b.topology());
    assert_eq!(x.len(), y.len(), "{name}: atom count");
    assert_eq!(x.names, y.names, "{name}: names");
    assert_eq!(x.types, y.types, "{name}: types");
    assert_eq!(x.elements, y.elements, "{name}: elements");
    assert_eq!(x.residue_names, y.residue_names, "{name}: residue names");
    assert_eq!(x.residue_ids, y.residue_ids, "{name}: residue numbers");
    assert_eq!(x.residue_index, y.residue_index, "{name}: residues");
    assert_eq!(x.chains, y.chains, "{name}: chains");
    assert_eq!(x.segments, y.segments, "{name}: segments");
    assert_eq!(x.radii, y.radii, "{name}: radii");
    assert_eq!(x.masses, y.masses, "{name}: masses");
    assert_eq!(x.charges, y.charges, "{name}: charges");
    assert_eq!(x.bonds, y.bonds, "{name}: bonds");
    assert_eq!(a.len(), b.len(), "{name}: frames");
    assert_eq!(a.damage(), b.damage(), "{name}: damage");
    for i in 0..a.len() {
        match (a.read_frame(i), b.read_frame(i)) {
            (Ok(fa), Ok(fb)) => {
                assert_eq!(fa.positions, fb.positions, "{name}: positions of frame {i}");
                assert_eq!(fa.cell, fb.cell, "{name}: box of frame {i}");
                assert_eq!(fa.time_ps, fb.time_ps, "{name}: time of frame {i}");
            }
            // 2ofg's models differ in size: the same error both ways.
            (Err(ea), Err(eb)) => assert_eq!(
                without_paths(&ea, a, b),
                without_paths(&eb, a, b),
                "{name}: frame {i}"
            ),
            (fa, fb) => panic!(
                "{name}: frame {i} is {:?} one way and {:?} the other",
                fa.map(|f| f.positions.len()),
                fb.map(|f| f.positions.len())
            ),
        }
    }
}

/// Asserts that `a` and `b` have the same B-factors, occupancies and serials.
fn same_wwpdb_columns(a: &Trajectory, b: &Trajectory, name: &str) {
    let (x, y) = (a.topology(), b.topology());
    same_values(&x.b_factors, &y.b_factors, &format!("{name}: B-factors"));
    same_values(
        &x.occupancies,
        &y.occupancies,
        &format!("{name}: occupancies"),
    );
    same_values(&x.serials, &y.serials, &format!("{name}: serials"));
}

/// Asserts `a == b`, naming the first atom that differs (not printing every value).
fn same_values<T: PartialEq + std::fmt::Debug>(a: &[T], b: &[T], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    if let Some(i) = (0..a.len()).find(|&i| a[i] != b[i]) {
        panic!(
            "{what}: atom {i} has {:?} one way and {:?} the other",
            a[i], b[i]
        );
    }
}

/// An error's text with the paths of `a` and `b` taken out (to compare errors of two files).
fn without_paths(e: &io::IoError, a: &Trajectory, b: &Trajectory) -> String {
    let mut text = e.to_string();
    for path in [a.path(), b.path(), a.topology_path(), b.topology_path()] {
        text = text.replace(path.to_string_lossy().as_ref(), "FILE");
    }
    text
}

/// Our reader against the chemfiles path, on every mmCIF file in tests/data, compressed and
/// plain. The chemfiles path took B-factors, occupancies and serials from pdbtbx for plain files
/// only (compressed ones had none): ours has them either way, equal to the plain file's.
#[test]
fn every_mmcif_file_reads_as_the_chemfiles_path_read_it() {
    let dir = tempfile::tempdir().unwrap();
    for file in FILES {
        let gz = data(file);
        let plain = write(dir.path(), file.trim_end_matches(".gz"), gunzipped(file));
        for path in [&gz, &plain] {
            assert!(io::reads_fast(path).unwrap(), "{file}: our reader");
        }
        let ours_gz = open(&gz);
        let ours_plain = open(&plain);
        let theirs_gz = io::open_via_chemfiles(&gz, None).unwrap_or_else(|e| panic!("{e}"));
        let theirs_plain = io::open_via_chemfiles(&plain, None).unwrap_or_else(|e| panic!("{e}"));
        same_atoms_and_frames(&ours_gz, &theirs_gz, file);
        same_atoms_and_frames(&ours_plain, &theirs_plain, file);
        assert_eq!(ours_gz.topology(), ours_plain.topology(), "{file}");
        // B-factors, occupancies and serials are the file's. pdbtbx's (matched by position)
        // agree, but for the occupancies of 7cfn, where pdbtbx gave 1/3 to atoms without an
        // alternate location next to atoms with two.
        let top = ours_gz.topology();
        let rows = first_model_rows(file);
        let column = |name: &str| {
            rows.iter()
                .map(|r| r[name].clone())
                .collect::<Vec<String>>()
        };
        let as_f32 =
            |v: Vec<String>| -> Vec<f32> { v.iter().map(|t| t.parse().unwrap()).collect() };
        same_values(
            &top.b_factors,
            &as_f32(column("B_iso_or_equiv")),
            &format!("{file}: B-factors"),
        );
        same_values(
            &top.occupancies,
            &as_f32(column("occupancy")),
            &format!("{file}: occupancies"),
        );
        let serials: Vec<i64> = column("id").iter().map(|t| t.parse().unwrap()).collect();
        same_values(&top.serials, &serials, &format!("{file}: serials"));
        let theirs = theirs_plain.topology();
        same_values(
            &top.b_factors,
            &theirs.b_factors,
            &format!("{file}: B-factors (pdbtbx)"),
        );
        same_values(
            &top.serials,
            &theirs.serials,
            &format!("{file}: serials (pdbtbx)"),
        );
        if file != "7cfn.cif.gz" {
            let what = format!("{file}: occupancies (pdbtbx)");
            same_values(&top.occupancies, &theirs.occupancies, &what);
        }
    }
}

/// The `_atom_site` rows of the first model of a compressed mmCIF file in `tests/data`, each a
/// map from column name to value (these files have no quoted values).
fn first_model_rows(file: &str) -> Vec<std::collections::HashMap<String, String>> {
    let text = gunzipped(file);
    let columns: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("_atom_site."))
        .map(str::trim)
        .collect();
    let rows: Vec<std::collections::HashMap<String, String>> = text
        .lines()
        .filter(|l| l.starts_with("ATOM") || l.starts_with("HETATM"))
        .map(|l| {
            let values = l.split_whitespace().map(str::to_string);
            columns.iter().map(|c| c.to_string()).zip(values).collect()
        })
        .collect();
    let first_model = rows[0]["pdbx_PDB_model_num"].clone();
    rows.into_iter()
        .take_while(|r| r["pdbx_PDB_model_num"] == first_model)
        .collect()
}

/// The `_atom_site` rows of `text`: (index of the first row's line, number of rows).
fn atom_rows(text: &str) -> (usize, usize) {
    let lines: Vec<&str> = text.lines().collect();
    let first = lines
        .iter()
        .position(|l| l.starts_with("ATOM") || l.starts_with("HETATM"))
        .expect("atom rows");
    let count = lines[first..]
        .iter()
        .take_while(|l| l.starts_with("ATOM") || l.starts_with("HETATM"))
        .count();
    (first, count)
}

/// `text` with `edit(row index, line)` applied to every `_atom_site` row (the lines it returns
/// replace the row's line).
fn edit_rows(text: &str, mut edit: impl FnMut(usize, &str) -> String) -> String {
    let (first, count) = atom_rows(text);
    let mut out = String::with_capacity(text.len() + 4096);
    for (k, line) in text.lines().enumerate() {
        if (first..first + count).contains(&k) {
            out.push_str(&edit(k - first, line));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// Legal mmCIF that crashed chemfiles (SIGSEGV: tabs between values) or lost atoms (it stopped
/// at a blank line inside the `_atom_site` loop): blank lines, tabs, CRLF line ends, a row split
/// over two lines, quoted values, a comment between rows. Each reads with the atoms and
/// positions of the original.
#[test]
fn legal_whitespace_and_quoting_read_the_same_atoms() {
    let dir = tempfile::tempdir().unwrap();
    for file in ["1gbt.cif.gz", "2ofg.cif.gz"] {
        let text = gunzipped(file);
        let original = open(&write(dir.path(), "original.cif", &text));
        let variants = [
            (
                "blank.cif",
                edit_rows(&text, |k, l| match k % 200 {
                    10 => format!("{l}\n"),
                    20 => format!("{l}\n\n   \n\t\n"),
                    _ => l.to_string(),
                }),
            ),
            (
                "tabs.cif",
                edit_rows(&text, |k, l| {
                    let sep = ["\t", " \t", "\t\t ", "\t"][k % 4];
                    l.split_whitespace().collect::<Vec<_>>().join(sep)
                }),
            ),
            ("crlf.cif", text.replace('\n', "\r\n")),
            (
                "split.cif",
                edit_rows(&text, |k, l| {
                    if k % 97 != 5 {
                        return l.to_string();
                    }
                    let values: Vec<&str> = l.split_whitespace().collect();
                    format!("{}\n  {}", values[..7].join(" "), values[7..].join(" "))
                }),
            ),
            (
                "quoted.cif",
                edit_rows(&text, |k, l| {
                    let mut values: Vec<String> =
                        l.split_whitespace().map(str::to_string).collect();
                    // The atom name and residue name quoted, as writers do for names with
                    // primes or spaces.
                    values[3] = format!("\"{}\"", values[3]);
                    values[5] = format!("'{}'", values[5]);
                    let row = values.join(" ");
                    if k == 3 {
                        format!("# a comment\n{row}")
                    } else {
                        row
                    }
                }),
            ),
        ];
        for (name, variant) in variants {
            let path = write(dir.path(), name, &variant);
            let t = open(&path);
            let label = format!("{file} as {name}");
            same_atoms_and_frames(&t, &original, &label);
            same_wwpdb_columns(&t, &original, &label);
        }
    }
}

/// The 1-based line of row `row` of the `_atom_site` loop of `text`.
fn row_line(text: &str, row: usize) -> usize {
    atom_rows(text).0 + row + 1
}

/// Opening `text` (as `name`) must fail with one line naming the file and containing `want`.
fn refused(dir: &Path, name: &str, text: &str, want: &str) {
    let path = write(dir, name, text);
    let e = io::open(&path, None)
        .err()
        .unwrap_or_else(|| panic!("{name} must be refused"))
        .to_string();
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(
        e.contains(name) && e.contains(want),
        "{name}: want {want:?} in {e}"
    );
}

/// A damaged row is refused naming the file and its line, never read as fewer atoms: a value
/// missing in the middle of the loop, one too many, a coordinate or model number that is not a
/// number, a quote left open, the loop cut inside its last row.
#[test]
fn damaged_rows_are_refused_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = gunzipped("1gbt.cif.gz");
    let columns = text
        .lines()
        .filter(|l| l.starts_with("_atom_site."))
        .count();
    let drop_value = |k: usize, l: &str, at: usize| {
        if k != 500 {
            return l.to_string();
        }
        let mut values: Vec<&str> = l.split_whitespace().collect();
        values.remove(at);
        values.join(" ")
    };
    let line = row_line(&text, 500);
    let missing = format!(
        "line {line}: an _atom_site row with {} of its {columns} values",
        columns - 1
    );
    for at in [0, 4, 12, columns - 1] {
        let damaged = edit_rows(&text, |k, l| drop_value(k, l, at));
        refused(dir.path(), "missing.cif", &damaged, &missing);
    }
    let extra = edit_rows(&text, |k, l| {
        if k == 500 {
            format!("{l} 1.00")
        } else {
            l.to_string()
        }
    });
    let want = format!(
        "line {line}: an _atom_site row with {} values where the loop has {columns}",
        columns + 1
    );
    refused(dir.path(), "extra.cif", &extra, &want);
    let bad_x = edit_rows(&text, |k, l| {
        if k != 500 {
            return l.to_string();
        }
        let mut values: Vec<String> = l.split_whitespace().map(str::to_string).collect();
        values[10] = format!("{}x", values[10]);
        values.join(" ")
    });
    refused(
        dir.path(),
        "bad_x.cif",
        &bad_x,
        &format!("line {line}: _atom_site.Cartn_x is '"),
    );
    let bad_model = edit_rows(&text, |k, l| {
        if k == 500 {
            format!("{}A", l.trim_end())
        } else {
            l.to_string()
        }
    });
    refused(
        dir.path(),
        "model.cif",
        &bad_model,
        "pdbx_PDB_model_num is '1A', not a model number",
    );
    let open_quote = edit_rows(&text, |k, l| {
        if k != 500 {
            return l.to_string();
        }
        let mut values: Vec<String> = l.split_whitespace().map(str::to_string).collect();
        values[5] = format!("'{}", values[5]);
        values.join(" ")
    });
    refused(
        dir.path(),
        "quote.cif",
        &open_quote,
        &format!("line {line}: a quoted value is not closed"),
    );
    // The last row cut, then the rest of the file (not at its end), and the file cut there.
    let (first, count) = atom_rows(&text);
    let lines: Vec<&str> = text.lines().collect();
    let last = first + count - 1;
    let cut_row = &lines[last][..40];
    let mut inside = lines[..last].join("\n");
    inside.push('\n');
    inside.push_str(cut_row);
    let within = format!("{inside}\n#\n{}\n", lines[last + 1..].join("\n"));
    refused(
        dir.path(),
        "cut.cif",
        &within,
        &format!("line {}: an _atom_site row with", last + 1),
    );
    refused(
        dir.path(),
        "cut_end.cif",
        &inside,
        "(is the file cut short?)",
    );
    refused(
        dir.path(),
        "empty_loop.cif",
        &format!("{}\n", lines[..first].join("\n")),
        "no atoms",
    );
    refused(
        dir.path(),
        "no_loop.cif",
        "data_x\n_cell.length_a 10\n",
        "no _atom_site loop",
    );
}

/// An mmCIF file as the trajectory of another topology: its models are the frames (chemfiles
/// never reads it).
#[test]
fn an_mmcif_trajectory_gives_its_models_as_frames() {
    let dir = tempfile::tempdir().unwrap();
    let text = gunzipped("1gbt.cif.gz");
    let (first, count) = atom_rows(&text);
    let lines: Vec<&str> = text.lines().collect();
    let mut models = lines[..first + count].join("\n");
    for k in 1..4 {
        for line in &lines[first..first + count] {
            let mut values: Vec<String> = line.split_whitespace().map(str::to_string).collect();
            let x: f64 = values[10].parse().unwrap();
            values[10] = format!("{:.3}", x + k as f64);
            *values.last_mut().unwrap() = (k + 1).to_string();
            models.push('\n');
            models.push_str(&values.join("\t"));
        }
    }
    models.push_str("\n#\n");
    let traj = write(dir.path(), "models.cif", &models);
    let top = data("1gbt.cif.gz");
    let t = io::open(&top, Some(&traj)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.len(), 4);
    let alone = open(&traj);
    assert_eq!(alone.len(), 4);
    assert_eq!(alone.topology(), t.topology());
    let f0 = t.read_frame(0).unwrap();
    let f3 = t.read_frame(3).unwrap();
    assert_eq!(f0.positions.len(), count);
    assert!((f3.positions[7].x - f0.positions[7].x - 3.0).abs() < 1e-3);
    assert_eq!(f3.positions[7].y, f0.positions[7].y);
    assert_eq!(f3.cell, f0.cell);
    assert!(f0.cell.is_some(), "1gbt has a cell");
}

/// A compressed mmCIF file whose stream is cut keeps the models before the cut; one whose only
/// model is cut is refused (never read as fewer atoms).
#[test]
fn a_cut_compressed_stream_never_gives_fewer_atoms() {
    let dir = tempfile::tempdir().unwrap();
    let text = gunzipped("2ofg.cif.gz");
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut encoder, text.as_bytes()).unwrap();
    let gz = encoder.finish().unwrap();
    for keep in [0.3, 0.6, 0.9, 0.99] {
        let cut = write(
            dir.path(),
            "cut.cif.gz",
            &gz[..(gz.len() as f64 * keep) as usize],
        );
        match io::open(&cut, None) {
            Ok(t) => {
                let damage = t.damage().expect("the cut is reported");
                assert_eq!(damage.frame, t.len());
                assert!(t.read_frame(t.len()).is_err());
                assert_eq!(t.read_frame(0).unwrap().positions.len(), 1613);
            }
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains("cut.cif.gz") && !e.contains('\n'), "{e}");
            }
        }
    }
}
