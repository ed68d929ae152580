//! The user's numbers to colour by (`--color data:FILE.csv`): a CSV of one value per atom
//! (`index,value`) or per frame and atom (`frame,index,value`), atom indices 0-based in topology
//! order and frames 0-based in trajectory order, a header row optional, `#` comments allowed; or
//! the B-factor column of every model of a multi-model PDB, one model per frame. Parsed with the
//! `csv` crate; every error is one line naming the file and line.
//!
//! Loaded tables live in a process-wide registry and a [`super::ColorScheme`] refers to one by
//! [`DataId`], which keeps the scheme a small `Copy` value (as the representations, commands and
//! state files pass it around) while the values are shared.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Why a data file could not be used: one line naming the file (and line).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct DataError(pub String);

/// Values to colour atoms by.
#[derive(Debug, Clone, PartialEq)]
pub struct DataTable {
    /// The file they came from.
    pub path: PathBuf,
    /// True when the values change per frame (`frame,index,value`, or a multi-model PDB).
    pub per_frame: bool,
    /// Values per frame (one entry for a per-atom file) and atom index; NaN where an atom has
    /// no value.
    frames: Vec<Vec<f32>>,
    /// Smallest and largest value over all frames.
    pub min_max: [f32; 2],
    /// The largest atom index and the line it is on.
    max_index: (usize, usize),
}

impl DataTable {
    /// The values of trajectory frame `frame` (the only set of a per-atom file); `None` when a
    /// per-frame file has no values for it.
    pub fn values(&self, frame: usize) -> Option<&[f32]> {
        if self.per_frame {
            self.frames.get(frame).map(Vec::as_slice)
        } else {
            self.frames.first().map(Vec::as_slice)
        }
    }

    /// Frames with values (1 for a per-atom file).
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Checks the table against a topology of `atoms` atoms and, when given, the frames used
    /// (`0..frames`): every index must be an atom, and a per-frame table must cover those frames.
    pub fn check(&self, atoms: usize, frames: Option<usize>) -> Result<(), DataError> {
        let file = self.path.display();
        let (index, line) = self.max_index;
        if index >= atoms {
            return Err(DataError(format!(
                "{file}:{line}: atom index {index} is not in the topology ({atoms} atoms, indices 0 to {})",
                atoms.saturating_sub(1)
            )));
        }
        if let Some(frames) = frames
            && self.per_frame
            && self.frames.len() < frames
        {
            return Err(DataError(format!(
                "{file}: no values for frame {} (the file has frames 0 to {}; {frames} frames are used)",
                frames - 1,
                self.frames.len().saturating_sub(1)
            )));
        }
        Ok(())
    }
}

/// Reads a data file: a multi-model PDB (`.pdb`, `.ent`) for its B-factors, else a CSV.
pub fn load(path: &Path) -> Result<DataTable, DataError> {
    let bytes = std::fs::read(path)
        .map_err(|e| DataError(format!("{}: cannot read: {e}", path.display())))?;
    // Spreadsheets on Windows write Latin-1 (a `é` in a comment or a label): bytes that are
    // not UTF-8 are read as Latin-1, as the structure readers do.
    let text = match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("pdb" | "ent")) {
        parse_pdb_bfactors(path, &text)
    } else {
        parse_csv(path, &text)
    }
}

/// Parses `index,value` or `frame,index,value` rows (see the module docs).
pub fn parse_csv(path: &Path, text: &str) -> Result<DataTable, DataError> {
    let file = path.display();
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    let mut columns: Option<usize> = None;
    // (frame, atom) -> value, with frames and atoms as given.
    let mut frames: BTreeMap<usize, Vec<f32>> = BTreeMap::new();
    let mut first_line_of_frame: BTreeMap<usize, usize> = BTreeMap::new();
    let mut max_index = (0usize, 0usize);
    let mut rows = 0usize;
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            DataError(format!("{file}:{line}: {e}"))
        })?;
        let line = record.position().map_or(0, |p| p.line()) as usize;
        let fields: Vec<&str> = record.iter().collect();
        if fields.iter().all(|f| f.is_empty()) {
            continue;
        }
        let is_header = rows == 0
            && columns.is_none()
            && fields.iter().any(|f| f.parse::<f64>().is_err())
            && fields
                .iter()
                .all(|f| f.chars().all(|c| c.is_alphabetic() || c == '_'));
        if is_header {
            let names: Vec<String> = fields.iter().map(|f| f.to_ascii_lowercase()).collect();
            let n = match names.iter().map(String::as_str).collect::<Vec<_>>()[..] {
                ["index" | "atom", "value"] => 2,
                ["frame", "index" | "atom", "value"] => 3,
                _ => {
                    return Err(DataError(format!(
                        "{file}:{line}: columns '{}': expected index,value or frame,index,value",
                        fields.join(",")
                    )));
                }
            };
            columns = Some(n);
            continue;
        }
        let n = *columns.get_or_insert(fields.len());
        if fields.len() != n || !(n == 2 || n == 3) {
            return Err(DataError(format!(
                "{file}:{line}: {} fields, expected {}",
                fields.len(),
                if n == 2 || n == 3 {
                    if n == 2 {
                        "2 (index,value)".to_string()
                    } else {
                        "3 (frame,index,value)".to_string()
                    }
                } else {
                    "2 (index,value) or 3 (frame,index,value)".to_string()
                }
            )));
        }
        let whole = |what: &str, s: &str| -> Result<usize, DataError> {
            s.parse().map_err(|_| {
                DataError(format!(
                    "{file}:{line}: {what} '{s}' is not a whole number from 0"
                ))
            })
        };
        let frame = if n == 3 {
            whole("frame", fields[0])?
        } else {
            0
        };
        let index = whole("atom index", fields[n - 2])?;
        let raw = fields[n - 1];
        let value: f32 = match raw.parse::<f32>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(DataError(format!(
                    "{file}:{line}: value '{raw}' is not a finite number"
                )));
            }
        };
        if index > 100_000_000 {
            return Err(DataError(format!(
                "{file}:{line}: atom index {index} is too large"
            )));
        }
        let values = frames.entry(frame).or_default();
        first_line_of_frame.entry(frame).or_insert(line);
        if values.len() <= index {
            values.resize(index + 1, f32::NAN);
        }
        if !values[index].is_nan() {
            let of = if n == 3 {
                format!(" of frame {frame}")
            } else {
                String::new()
            };
            return Err(DataError(format!(
                "{file}:{line}: atom {index}{of} has a value already"
            )));
        }
        values[index] = value;
        if index > max_index.0 || max_index.1 == 0 {
            max_index = (index, line);
        }
        rows += 1;
    }
    if rows == 0 {
        return Err(DataError(format!(
            "{file}: no values (expected rows index,value or frame,index,value)"
        )));
    }
    // Per-frame files must give frames 0, 1, 2, ... without gaps.
    for (expected, (&frame, _)) in frames.iter().enumerate() {
        if frame != expected {
            let line = first_line_of_frame.get(&frame).copied().unwrap_or(0);
            return Err(DataError(format!(
                "{file}:{line}: frame {frame} follows frame {}: frame {expected} is missing",
                expected.saturating_sub(1)
            )));
        }
    }
    let frames: Vec<Vec<f32>> = frames.into_values().collect();
    Ok(table(path, columns == Some(3), frames, max_index))
}

/// Builds a table and its value range.
fn table(
    path: &Path,
    per_frame: bool,
    frames: Vec<Vec<f32>>,
    max_index: (usize, usize),
) -> DataTable {
    let (lo, hi) = frames
        .iter()
        .flatten()
        .filter(|v| v.is_finite())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    DataTable {
        path: path.to_path_buf(),
        per_frame,
        frames,
        min_max: [lo, hi],
        max_index,
    }
}

/// The B-factors (columns 61-66 of ATOM/HETATM records) of every model (MODEL ... ENDMDL) of a
/// PDB file, one frame per model. Read here because the column is all that is needed and MD
/// files (no element columns, hybrid-36 serials) are read the same way.
pub fn parse_pdb_bfactors(path: &Path, text: &str) -> Result<DataTable, DataError> {
    let file = path.display();
    let mut models: Vec<Vec<f32>> = vec![Vec::new()];
    let mut max_index = (0, 0);
    for (k, line) in text.lines().enumerate() {
        let no = k + 1;
        if line.starts_with("ENDMDL") {
            models.push(Vec::new());
        } else if line.starts_with("ATOM  ") || line.starts_with("HETATM") {
            let field = line.get(60..66).map(str::trim).unwrap_or("");
            let b = if field.is_empty() {
                f32::NAN
            } else {
                match field.parse::<f32>() {
                    Ok(v) if v.is_finite() => v,
                    _ => {
                        return Err(DataError(format!(
                            "{file}:{no}: B-factor '{field}' (columns 61-66) is not a number"
                        )));
                    }
                }
            };
            let model = models.last_mut().expect("one model at least");
            model.push(b);
            max_index = max_index.max((model.len() - 1, no));
        }
    }
    models.retain(|m| !m.is_empty());
    if models.is_empty() {
        return Err(DataError(format!("{file}: no ATOM or HETATM records")));
    }
    Ok(table(path, true, models, max_index))
}

/// A loaded table's number in the registry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DataId(pub u32);

/// Every table loaded in this process (a few: one per data file the user picked).
static TABLES: Mutex<Vec<Arc<DataTable>>> = Mutex::new(Vec::new());

/// Adds `table` to the registry (an equal table already there is reused) and returns its id.
pub fn register(table: DataTable) -> DataId {
    let mut tables = TABLES.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(k) = tables.iter().position(|t| **t == table) {
        return DataId(k as u32);
    }
    tables.push(Arc::new(table));
    DataId(tables.len() as u32 - 1)
}

/// The table with `id`.
pub fn get(id: DataId) -> Option<Arc<DataTable>> {
    let tables = TABLES.lock().unwrap_or_else(|p| p.into_inner());
    tables.get(id.0 as usize).cloned()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<DataTable, DataError> {
        parse_csv(Path::new("q.csv"), text)
    }

    #[test]
    fn per_atom_and_per_frame_files_parse() {
        let t = parse("index,value\n0,1.5\n2,-0.5\n").unwrap();
        assert!(!t.per_frame);
        let v = t.values(7).unwrap();
        assert_eq!((v[0], v[2]), (1.5, -0.5));
        assert!(v[1].is_nan());
        assert_eq!(t.min_max, [-0.5, 1.5]);
        let t = parse("# charges\n0,0,1\n0,1,2\n1,0,3\n1,1,4\n").unwrap();
        assert!(t.per_frame && t.frame_count() == 2);
        assert_eq!(t.values(1).unwrap(), [3.0, 4.0]);
        assert!(t.values(2).is_none());
        assert!(t.check(2, Some(2)).is_ok() && t.check(2, None).is_ok());
        let e = t.check(2, Some(3)).unwrap_err().0;
        assert!(e.starts_with("q.csv: no values for frame 2"), "{e}");
        let e = t.check(1, None).unwrap_err().0;
        assert!(e.starts_with("q.csv:3: atom index 1 is not"), "{e}");
    }

    #[test]
    fn bad_rows_name_file_and_line() {
        let cases = [
            ("index,value\n0,1\n1,abc\n", "q.csv:3: value 'abc'"),
            ("0,1\n-1,2\n", "q.csv:2: atom index '-1'"),
            (
                "0,0,1\n2,0,1\n",
                "q.csv:2: frame 2 follows frame 0: frame 1 is missing",
            ),
            ("0,1\n0,2\n", "q.csv:2: atom 0 has a value already"),
            ("0,1\n1,2,3\n", "q.csv:2: 3 fields, expected 2"),
            ("idx,val\n", "q.csv:1: columns 'idx,val'"),
            ("", "q.csv: no values"),
            ("0,nan\n", "q.csv:1: value 'nan'"),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err().0;
            assert!(e.starts_with(want), "{text:?}: {e}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn pdb_models_give_one_frame_each() {
        let atom = |b: &str| {
            format!(
                "ATOM      1  CA  ALA A   1       0.000   0.000   0.000  1.00{b:>6}           C"
            )
        };
        let text = format!(
            "MODEL 1\n{}\n{}\nENDMDL\nMODEL 2\n{}\n{}\nENDMDL\nEND\n",
            atom("10.00"),
            atom("20.00"),
            atom("30.00"),
            atom("40.00")
        );
        let t = parse_pdb_bfactors(Path::new("m.pdb"), &text).unwrap();
        assert!(t.per_frame);
        assert_eq!(t.values(1).unwrap(), [30.0, 40.0]);
        let bad = text.replace("40.00", " x.yz");
        let e = parse_pdb_bfactors(Path::new("m.pdb"), &bad).unwrap_err().0;
        assert!(e.starts_with("m.pdb:7: B-factor 'x.yz'"), "{e}");
    }
}
