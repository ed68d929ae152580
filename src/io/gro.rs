//! Our reader of GROMACS GRO files (one or many frames; plain or, through
//! [`super::prepare`], compressed). Each frame is a title line (whose `t=` gives the time in
//! ps), the atom count, one fixed-column line per atom and the box line.
//!
//! Atom lines hold the residue number (columns 1-5), residue name (6-10), atom name (11-15) and
//! atom number (16-20), then x, y, z in nm from column 21 in fields as wide as the distance
//! between their decimal points (8 characters as `gmx` writes them by default, 9 to 11 from
//! `gmx trjconv -ndec 4` to `6`; chemfiles read only the 8-character fields), then optional
//! velocities. Positions and box become Å. The box line holds 3 (rectangular) or 9 (triclinic:
//! v1x v2y v3z v1y v1z v2x v2z v3x v3y) numbers in nm.
//!
//! The topology is what the chemfiles path gives (see `super::chem`): names that are also the
//! types, no element, mass 0, residue numbers and names from columns 1-10 with residues as runs
//! of atoms sharing both. `tests/it/io_native_text.rs` compares both on every GRO test file.
//!
//! A damaged or cut frame is a [`GroError`] naming the line, wrapped in an [`IoError`] naming
//! the file and frame.

use std::path::Path;

use super::IoError;
use super::fast::{QuickMap, parse_u64, trim};
use super::fast::{TypeTable, cols, columns_text, empty_topology, parse_f64, parse_i64, to_vec3};
use super::native::NativeOpen;
use super::prepare::Prepared;
use super::reader_errors::GroError;
use super::text_scan::{FrameSpan, LineScanner, cell_rows, lines, open_spans};
use crate::model::{Frame, Labels, Topology};

/// Width of a coordinate field as `gmx` writes it by default (`%8.3f`).
const DEFAULT_FIELD: usize = 8;

/// Where coordinates start on an atom line (0-based column).
const FIRST_FIELD: usize = 20;

/// Opens the GRO file `path` (its bytes in `prepared`): indexes its frames, reads frame 0 and
/// its topology.
pub(crate) fn open(path: &Path, prepared: Prepared) -> Result<NativeOpen, IoError> {
    open_spans(
        path,
        prepared,
        "GRO",
        index_frame,
        |bytes, line| {
            parse_frame(bytes, line, true).map(|(frame, atoms)| (frame, Some(topology(&atoms))))
        },
        parse_span,
    )
}

/// One frame's positions, box and time for [`super::text_scan::SpanFrames`] (no topology).
fn parse_span(
    bytes: &[u8],
    first_line: u64,
) -> Result<Frame, Box<dyn std::error::Error + Send + Sync>> {
    Ok(parse_frame(bytes, first_line, false)?.0)
}

/// Walks over the next frame: its span, `None` at the end of the file, or why the frame is cut
/// or damaged.
fn index_frame(scan: &mut LineScanner) -> std::io::Result<Result<Option<FrameSpan>, GroError>> {
    let Some((start, line, title)) = scan.next_line()? else {
        return Ok(Ok(None));
    };
    let blank_title = trim(title).is_empty();
    let count = loop {
        match scan.next_line()? {
            Some((_, _, text)) if blank_title && trim(text).is_empty() => continue,
            Some((_, at, text)) => {
                break Some(parse_u64(text).ok_or_else(|| (at, columns_text(trim(text)))));
            }
            None => break None,
        }
    };
    let atoms = match count {
        // Blank lines after the last frame.
        None if blank_title => return Ok(Ok(None)),
        None => return Ok(Err(GroError::EndsBeforeCount { line: line + 1 })),
        Some(Err((at, shown))) => return Ok(Err(GroError::BadCount { line: at, shown })),
        Some(Ok(atoms)) => atoms,
    };
    let mut needed = FIRST_FIELD + 3 * DEFAULT_FIELD;
    for atom in 0..atoms {
        let Some((_, at, text)) = scan.next_line()? else {
            return Ok(Err(GroError::AtomMissing {
                missing: atom + 1,
                atoms,
            }));
        };
        if atom == 0 {
            needed = FIRST_FIELD + 3 * field_width(text);
        }
        if text.len() < needed {
            return Ok(Err(GroError::ShortAtomLine {
                line: at,
                length: text.len(),
                needed,
            }));
        }
    }
    let Some((_, at, text)) = scan.next_line()? else {
        return Ok(Err(GroError::EndsBeforeBox));
    };
    if let Err(error) = parse_box(text, at) {
        return Ok(Err(error));
    }
    Ok(Ok(Some(FrameSpan {
        start,
        end: scan.position(),
        line,
    })))
}

/// The width of the coordinate fields of a frame, from its first atom line: the distance
/// between the decimal points of x and y (as GROMACS reads it), else 8.
fn field_width(line: &[u8]) -> usize {
    let rest = cols(line, FIRST_FIELD, line.len());
    let Some(first) = memchr::memchr(b'.', rest) else {
        return DEFAULT_FIELD;
    };
    match memchr::memchr(b'.', &rest[first + 1..]) {
        Some(gap) if (5..=30).contains(&(gap + 1)) => gap + 1,
        _ => DEFAULT_FIELD,
    }
}

/// The columns of one atom line the topology needs.
struct AtomText {
    /// Columns 1-5 as chemfiles parses them (`None`: not a number).
    residue_number: Option<i64>,
    /// Columns 1-5 as `super::chem` reads them from the file (blank is not a number).
    residue_number_strict: Option<i64>,
    /// Columns 6-10, trimmed.
    residue_name: String,
    /// Columns 11-15, trimmed.
    name: String,
}

/// Parses one frame (`bytes`, whose first line is line `first_line` of the file): positions and
/// box in Å, time in ps, and with `with_atoms` each atom's names. Errors name the line.
fn parse_frame(
    bytes: &[u8],
    first_line: u64,
    with_atoms: bool,
) -> Result<(Frame, Vec<AtomText>), GroError> {
    let mut it = lines(bytes);
    let title = it.next().unwrap_or_default();
    let mut number = first_line + 1;
    // The index skipped blank lines between a blank title and the count.
    let count = loop {
        let text = it.next().ok_or(GroError::FrameEndsBeforeCount)?;
        if !trim(text).is_empty() || !trim(title).is_empty() {
            break text;
        }
        number += 1;
    };
    let n = parse_u64(count)
        .and_then(|n| usize::try_from(n).ok())
        .ok_or(GroError::CountNotNumber { line: number })?;
    let mut positions = Vec::with_capacity(n);
    let mut atoms = Vec::with_capacity(if with_atoms { n } else { 0 });
    let mut width = DEFAULT_FIELD;
    for atom in 0..n {
        number += 1;
        let line = it.next().ok_or(GroError::FrameEndsBeforeAtom {
            line: number,
            atom: atom + 1,
        })?;
        if atom == 0 {
            width = field_width(line);
        }
        let mut xyz = [0.0f64; 3];
        for (k, value) in xyz.iter_mut().enumerate() {
            let from = FIRST_FIELD + k * width;
            let field = cols(line, from, from + width);
            *value = parse_f64(field).ok_or_else(|| GroError::BadCoordinate {
                line: number,
                atom: atom + 1,
                axis: ["x", "y", "z"][k],
                shown: columns_text(trim(field)),
            })? * 10.0;
        }
        positions.push(to_vec3(xyz));
        if with_atoms {
            let residue = cols(line, 0, 5);
            atoms.push(AtomText {
                residue_number: parse_i64(residue),
                residue_number_strict: std::str::from_utf8(residue)
                    .ok()
                    .and_then(|s| s.trim().parse().ok()),
                residue_name: columns_text(trim(cols(line, 5, 10))),
                name: columns_text(trim(cols(line, 10, 15))),
            });
        }
    }
    number += 1;
    let box_line = it
        .next()
        .ok_or(GroError::FrameEndsBeforeBox { line: number })?;
    let cell = parse_box(box_line, number)?;
    let frame = Frame {
        index: 0,
        time_ps: title_time(title),
        positions,
        cell,
    };
    Ok((frame, atoms))
}

/// The box line (`text`, line `line` of the file): 3 or 9 numbers in nm, as rows a, b, c in Å
/// (`None` for a zero box).
fn parse_box(text: &[u8], line: u64) -> Result<Option<[glam::Vec3; 3]>, GroError> {
    let mut values = [0.0f64; 9];
    let mut count = 0usize;
    for token in text
        .split(|&b| matches!(b, b' ' | b'\t'))
        .filter(|t| !t.is_empty())
    {
        if count == 9 {
            count += 1;
            break;
        }
        values[count] = parse_f64(token).ok_or_else(|| GroError::BadBoxValue {
            line,
            shown: columns_text(token),
        })? * 10.0;
        count += 1;
    }
    let v = values;
    let rows = match count {
        3 => right_angled(v[0], v[1], v[2]),
        // v1(x) v2(y) v3(z) v1(y) v1(z) v2(x) v2(z) v3(x) v3(y)
        9 => [[v[0], v[3], v[4]], [v[5], v[1], v[6]], [v[7], v[8], v[2]]],
        _ => return Err(GroError::BoxCount { line, count }),
    };
    cell_rows(rows).map_err(|error| GroError::Cell { line, error })
}

/// A rectangular box of lengths `a`, `b`, `c` (Å) with the rounding of chemfiles, which builds
/// it from lengths and 90° angles (cos 90° is 6e-17 in f64): the same rows to the bit.
fn right_angled(a: f64, b: f64, c: f64) -> [[f64; 3]; 3] {
    let right = 90.0 * std::f64::consts::PI / 180.0;
    let (cos, sin) = (right.cos(), right.sin());
    let c_x = cos;
    let c_y = (cos - cos * cos) / sin;
    let c_z = (1.0 - c_x * c_x - c_y * c_y).sqrt();
    [
        [a, 0.0, 0.0],
        [cos * b, sin * b, 0.0],
        [c_x * c, c_y * c, c_z * c],
    ]
}

/// The time (ps) a title gives as `t= 12.5` (GROMACS writes `... t= 12.50000 step= 6250`).
fn title_time(title: &[u8]) -> Option<f64> {
    let at = memchr::memmem::find_iter(title, b"t=")
        .find(|&i| i == 0 || matches!(title[i - 1], b' ' | b'\t'))?;
    let rest = &title[at + 2..];
    let rest = &rest[rest.iter().position(|&b| b != b' ' && b != b'\t')?..];
    let end = rest
        .iter()
        .position(|&b| b == b' ' || b == b'\t')
        .unwrap_or(rest.len());
    parse_f64(&rest[..end]).filter(|t| t.is_finite())
}

/// The topology of frame 0's atoms, as the chemfiles path leaves it (see the module notes).
fn topology(atoms: &[AtomText]) -> Topology {
    let n = atoms.len();
    let mut top = empty_topology(n);
    let mut table = TypeTable::default();
    for atom in atoms {
        top.names.push(&atom.name);
        top.charges.push(table.get(&atom.name).1);
    }
    top.types = top.names.clone();
    top.elements = Labels::filled("", n);
    top.masses = vec![0.0; n];
    let mut group = vec![u32::MAX; n];
    if atoms.iter().all(|a| a.residue_number_strict.is_some()) {
        // Residue numbers and names from every line, residues as runs (as `super::chem` does).
        let mut run = 0u32;
        for (i, atom) in atoms.iter().enumerate() {
            top.residue_ids[i] = atom.residue_number_strict.unwrap_or_default();
            top.residue_names.set(i, &atom.residue_name);
            if i > 0 {
                let before = &atoms[i - 1];
                let same = before.residue_number_strict == atom.residue_number_strict
                    && before.residue_name == atom.residue_name;
                run += u32::from(!same);
            }
            group[i] = run;
        }
    } else {
        // chemfiles' residues: one per number, named by its first atom; atoms whose number is
        // not one are in none.
        let mut residues: QuickMap<i64, (u32, usize)> = QuickMap::default();
        for (i, atom) in atoms.iter().enumerate() {
            let Some(number) = atom.residue_number else {
                continue;
            };
            let next = residues.len() as u32;
            let (id, first) = *residues.entry(number).or_insert((next, i));
            top.residue_ids[i] = number;
            top.residue_names.set(i, &atoms[first].residue_name);
            group[i] = id;
        }
    }
    top.number_residue_runs(&group);
    top
}

#[cfg(test)]
mod tests {
    use super::super::text_scan::BoxError;
    use super::*;

    #[test]
    fn field_widths_follow_the_decimal_points() {
        let ndec3 = b"    1SOL     OW    1   0.126   1.624   1.679";
        let ndec5 = b"    1SOL     OW    1   0.12612   1.62412   1.67912";
        assert_eq!(field_width(ndec3), 8);
        assert_eq!(field_width(ndec5), 10);
        assert_eq!(field_width(b"    1SOL     OW    1"), 8);
    }

    #[test]
    fn titles_give_times_in_ps() {
        assert_eq!(title_time(b"Protein t=  12.50000 step= 6250"), Some(12.5));
        assert_eq!(title_time(b"t=3"), Some(3.0));
        assert_eq!(title_time(b"Generated by trjconv"), None);
        assert_eq!(title_time(b"start=5"), None);
        assert_eq!(title_time(b"t= soon"), None);
    }

    #[test]
    fn boxes_of_three_and_nine_numbers() {
        let cube = parse_box(b"   1.00000   2.00000   3.00000", 1)
            .unwrap()
            .unwrap();
        assert_eq!(cube[2].z, 30.0);
        assert!(cube[2].x.abs() < 1e-9 && cube[1].x.abs() < 1e-9);
        let tri = parse_box(b" 1 2 3 0 0 0.5 0 0.25 0.75", 1)
            .unwrap()
            .unwrap();
        assert_eq!(tri[1], glam::Vec3::new(5.0, 20.0, 0.0));
        assert_eq!(tri[2], glam::Vec3::new(2.5, 7.5, 30.0));
        assert_eq!(parse_box(b"0 0 0", 1), Ok(None));
        assert_eq!(
            parse_box(b"1 2", 4),
            Err(GroError::BoxCount { line: 4, count: 2 })
        );
        assert_eq!(
            parse_box(b"1 2 3 4 5 6 7 8 9 10 11", 4),
            Err(GroError::BoxCount { line: 4, count: 10 })
        );
        assert_eq!(
            parse_box(b"1 2 x", 4),
            Err(GroError::BadBoxValue {
                line: 4,
                shown: "x".into()
            })
        );
        assert!(matches!(
            parse_box(b"-1 2 3", 4),
            Err(GroError::Cell {
                line: 4,
                error: BoxError::NegativeLength(_)
            })
        ));
    }
}
