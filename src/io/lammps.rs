//! Our reader of LAMMPS dump files (`dump atom` / `dump custom` text, one or many frames; plain
//! or, through [`super::prepare`], compressed). Each frame is a header (see
//! [`super::lammps_header`]) and one line per atom whose columns the `ITEM: ATOMS` line names,
//! in any order.
//!
//! Atoms are sorted by `id` (as chemfiles places atom `id` at index `id - 1`), but ids need not
//! run from 1 to the atom count: a dump of a group, or one written after `delete_atoms`, has
//! gaps, and any 64-bit id is read (chemfiles crashed on id 0 and on ids from 2^31). Positions
//! as chemfiles picks them (unwrapped, else scaled unwrapped, else wrapped plus images, else
//! scaled; scaled ones are turned into lengths with the box), in the dump's length unit (Å for
//! `units real` and `metal`). A tilted box's `BOX BOUNDS` lines hold the bounds of the whole
//! parallelepiped (LAMMPS' `xlo_bound`, ...), from which the box is rebuilt (chemfiles took
//! them for `xlo`, `xhi`: its boxes were too long by the tilts). No time: a dump's `TIMESTEP`
//! is a step count and its `TIME` has no stated unit.
//!
//! The topology is what the chemfiles path gives (see `super::chem`): the `element` column is
//! the name, else the `type`; `mass` and `q` columns give masses and charges; no residues.
//! The serial numbers are the ids (chemfiles numbers atoms 1 to n; the same where the ids run
//! from 1 without gaps).
//! `tests/it/io_native_text.rs` compares both on every LAMMPS test file.
//!
//! A damaged or cut frame is a [`LammpsError`] naming the line, wrapped in an [`IoError`]
//! naming the file and frame.

use std::path::Path;

use super::IoError;
use super::fast::{TypeTable, empty_topology, free_text, parse_f64, parse_i64, parse_u64};
use super::fast::{to_vec3, trim};
use super::lammps_header::{self, Header, item, words};
use super::native::NativeOpen;
use super::prepare::Prepared;
use super::reader_errors::LammpsError;
use super::text_scan::{FrameSpan, LineScanner, lines, open_spans};
use crate::model::elements::canonical_symbol;
use crate::model::{Frame, Topology};

/// Most header lines a frame may have (its items are 5 to 7, with their values 10 to 14 lines).
const MAX_HEADER_LINES: usize = 64;

/// Opens the LAMMPS dump `path` (its bytes in `prepared`): indexes its frames, reads frame 0
/// and its topology.
pub(crate) fn open(path: &Path, prepared: Prepared) -> Result<NativeOpen, IoError> {
    open_spans(
        path,
        prepared,
        "LAMMPS",
        index_frame,
        |bytes, line| parse_frame(bytes, line, true),
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

/// Walks over the next frame (blank lines before it are skipped): its span, `None` at the end
/// of the file, or why the frame is cut or damaged.
fn index_frame(scan: &mut LineScanner) -> std::io::Result<Result<Option<FrameSpan>, LammpsError>> {
    let mut header: Vec<Vec<u8>> = Vec::new();
    let (mut start, mut first) = (0, 0);
    loop {
        let Some((at, number, line)) = scan.next_line()? else {
            if header.is_empty() {
                return Ok(Ok(None));
            }
            break;
        };
        if header.is_empty() {
            if trim(line).is_empty() {
                continue;
            }
            (start, first) = (at, number);
        }
        let atoms_item = item(line).is_some_and(|name| name.starts_with(b"ATOMS"));
        header.push(line.to_vec());
        if atoms_item || header.len() == MAX_HEADER_LINES {
            break;
        }
    }
    let mut header_lines = header.iter().map(Vec::as_slice);
    let header = match lammps_header::parse(&mut header_lines, first) {
        Ok(header) => header,
        Err(message) => return Ok(Err(message)),
    };
    for atom in 0..header.atoms {
        if scan.next_line()?.is_none() {
            return Ok(Err(LammpsError::AtomMissing {
                missing: atom + 1,
                atoms: header.atoms,
            }));
        }
    }
    Ok(Ok(Some(FrameSpan {
        start,
        end: scan.position(),
        line: first,
    })))
}

/// Parses one frame (`bytes`, whose first line is line `first_line` of the file): positions and
/// box, and with `with_topology` the atoms. Errors name the line.
fn parse_frame(
    bytes: &[u8],
    first_line: u64,
    with_topology: bool,
) -> Result<(Frame, Option<Topology>), LammpsError> {
    let mut it = lines(bytes);
    let header = lammps_header::parse(&mut it, first_line)?;
    let columns = &header.columns;
    let n = header.atoms;
    let mut positions = Vec::with_capacity(n);
    let mut ids = Vec::with_capacity(if columns.id.is_some() { n } else { 0 });
    let mut atom_lines = Vec::with_capacity(if with_topology { n } else { 0 });
    let mut words_of_line: Vec<&[u8]> = Vec::with_capacity(columns.count);
    let first_atom_line = first_line + header.lines;
    for atom in 0..n {
        let number = first_atom_line + atom as u64;
        let line = it.next().ok_or(LammpsError::FrameEndsBeforeAtom {
            line: number,
            atom: atom + 1,
        })?;
        words_of_line.clear();
        words_of_line.extend(words(line));
        if words_of_line.len() != columns.count {
            return Err(LammpsError::ValueCount {
                line: number,
                found: words_of_line.len(),
                columns: columns.count,
            });
        }
        let number_at = |column: Option<usize>, what: &'static str| -> Result<f64, LammpsError> {
            match column {
                Some(k) => parse_f64(words_of_line[k]).ok_or_else(|| LammpsError::NotANumber {
                    line: number,
                    what,
                    shown: free_text(words_of_line[k]),
                }),
                None => Ok(0.0),
            }
        };
        let mut p = [0.0f64; 3];
        for (axis, value) in p.iter_mut().enumerate() {
            *value = number_at(columns.position[axis], "position")?;
        }
        p = place(&header, p, image_of(&words_of_line, &header, number)?);
        positions.push(to_vec3(p));
        if let Some(k) = columns.id {
            let id = parse_u64(words_of_line[k]).ok_or_else(|| LammpsError::BadId {
                line: number,
                shown: free_text(words_of_line[k]),
            })?;
            ids.push(id);
        }
        if with_topology {
            atom_lines.push(AtomText {
                kind: columns.kind.map(|k| words_of_line[k]).unwrap_or_default(),
                element: columns
                    .element
                    .map(|k| words_of_line[k])
                    .unwrap_or_default(),
                mass: columns
                    .mass
                    .map(|_| number_at(columns.mass, "mass"))
                    .transpose()?,
                charge: columns
                    .charge
                    .map(|_| number_at(columns.charge, "charge"))
                    .transpose()?,
            });
        }
    }
    if let Some(order) = id_order(&ids, first_atom_line)? {
        positions = order.iter().map(|&i| positions[i]).collect();
        if with_topology {
            atom_lines = order.iter().map(|&i| atom_lines[i]).collect();
        }
    }
    let frame = Frame {
        index: 0,
        time_ps: None,
        positions,
        cell: header.cell,
    };
    let topology = with_topology.then(|| {
        let mut top = topology(&atom_lines);
        // The atoms' ids as their serial numbers (a dump of a group has gaps; ids past i64 are
        // left at their place).
        if ids.len() == top.len() {
            let mut sorted = ids;
            sorted.sort_unstable();
            for (serial, id) in top.serials.iter_mut().zip(sorted) {
                *serial = i64::try_from(id).unwrap_or(*serial);
            }
        }
        top
    });
    Ok((frame, topology))
}

/// The image flags of an atom line (0 where absent), when they are to be applied.
fn image_of(
    words: &[&[u8]],
    header: &Header,
    number: u64,
) -> Result<Option<[f64; 3]>, LammpsError> {
    let Some(images) = header.columns.images else {
        return Ok(None);
    };
    let mut out = [0.0f64; 3];
    for (value, column) in out.iter_mut().zip(images) {
        if let Some(k) = column {
            let image = parse_i64(words[k]).ok_or_else(|| LammpsError::BadImage {
                line: number,
                shown: free_text(words[k]),
            })?;
            *value = image as f64;
        }
    }
    Ok(Some(out))
}

/// A position as read (`p`: lengths, or fractions of the box when the columns are scaled) made
/// a length, and moved by `images` whole boxes.
fn place(header: &Header, mut p: [f64; 3], images: Option<[f64; 3]>) -> [f64; 3] {
    let [a, b, c] = header.rows;
    if header.columns.scaled {
        let o = header.origin;
        p = [
            o[0] + p[0] * a[0] + p[1] * b[0] + p[2] * c[0],
            o[1] + p[1] * b[1] + p[2] * c[1],
            o[2] + p[2] * c[2],
        ];
    }
    if let Some(i) = images {
        p[0] += i[0] * a[0] + i[1] * b[0] + i[2] * c[0];
        p[1] += i[1] * b[1] + i[2] * c[1];
        p[2] += i[2] * c[2];
    }
    p
}

/// The order that sorts the atoms by `ids` (`None` when they are in order already, or there
/// are none); an error naming the id when two atoms share one.
fn id_order(ids: &[u64], first_atom_line: u64) -> Result<Option<Vec<usize>>, LammpsError> {
    let twice = |id: u64| LammpsError::DuplicateId {
        id,
        first_line: first_atom_line,
    };
    if ids.windows(2).all(|w| w[0] < w[1]) {
        return Ok(None);
    }
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_unstable_by_key(|&i| ids[i]);
    if let Some(w) = order.windows(2).find(|w| ids[w[0]] == ids[w[1]]) {
        return Err(twice(ids[w[0]]));
    }
    Ok(Some(order))
}

/// The columns of one atom line the topology needs.
#[derive(Clone, Copy)]
struct AtomText<'a> {
    /// `type` (empty without the column).
    kind: &'a [u8],
    /// `element` (empty without the column).
    element: &'a [u8],
    /// `mass`, when given.
    mass: Option<f64>,
    /// `q`, when given.
    charge: Option<f64>,
}

/// The topology of frame 0's atoms (in id order), as the chemfiles path leaves it: see
/// `super::chem` (the name is the element column, else the type; an element only where the
/// type names one and differs from the name; a mass only where it is not the type's own).
fn topology(atoms: &[AtomText]) -> Topology {
    let n = atoms.len();
    let mut top = empty_topology(n);
    let mut table = TypeTable::default();
    for atom in atoms {
        let kind = free_text(atom.kind);
        let name = free_text(atom.element);
        let name = if name.trim().is_empty() {
            kind.clone()
        } else {
            name
        };
        let element = if kind != name {
            canonical_symbol(&kind).unwrap_or_default()
        } else {
            ""
        };
        let mass = atom.mass.unwrap_or(0.0) as f32;
        let mass = if kind != name || mass != table.get(&kind).0 {
            mass
        } else {
            0.0
        };
        top.masses.push(if mass.is_finite() { mass } else { 0.0 });
        top.charges.push(atom.charge.unwrap_or(0.0) as f32);
        top.elements.push(element);
        top.types.push(&kind);
        top.names.push(&name);
    }
    top.number_residue_runs(&vec![u32::MAX; n]);
    top
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atoms_sort_by_id_and_ids_may_be_sparse_or_huge() {
        let text = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS pp pp pp\n\
                    0 10\n0 10\n0 10\nITEM: ATOMS id type x y z q\n\
                    4294967296 2 3 3 3 -0.5\n0 1 1 1 1 0.25\n7 1 2 2 2 0.25\n";
        let (frame, top) = parse_frame(text.as_bytes(), 1, true).unwrap();
        let xs: Vec<f32> = frame.positions.iter().map(|p| p.x).collect();
        assert_eq!(xs, [1.0, 2.0, 3.0]);
        let top = top.unwrap();
        assert_eq!(top.names, vec!["1", "1", "2"]);
        assert_eq!(top.charges, [0.25, 0.25, -0.5]);
        let twice = text.replace("\n7 1", "\n0 1");
        let error = parse_frame(twice.as_bytes(), 1, false).unwrap_err();
        assert_eq!(
            error,
            LammpsError::DuplicateId {
                id: 0,
                first_line: 10
            }
        );
        assert_eq!(error.to_string(), "atom id 0 appears twice (lines from 10)");
    }

    #[test]
    fn scaled_positions_and_images_become_lengths() {
        let text = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\n\
                    ITEM: BOX BOUNDS xy xz yz pp pp pp\n0 12 2\n0 20 0\n-5 25 0\n\
                    ITEM: ATOMS id xs ys zs ix iy iz\n1 0.5 0.5 0.5 1 0 -1\n";
        let (frame, _) = parse_frame(text.as_bytes(), 1, false).unwrap();
        // Box: a = (10, 0, 0), b = (2, 20, 0), c = (0, 0, 30) from (0, 0, -5).
        let want = [0.5 * 10.0 + 0.5 * 2.0 + 10.0, 10.0, -5.0 + 15.0 - 30.0];
        let got = frame.positions[0];
        assert_eq!([got.x, got.y, got.z], want.map(|v| v as f32));
        let short = text.replace("1 0.5 0.5 0.5 1 0 -1", "1 0.5 0.5");
        assert_eq!(
            parse_frame(short.as_bytes(), 1, false).unwrap_err(),
            LammpsError::ValueCount {
                line: 10,
                found: 3,
                columns: 7
            }
        );
    }
}
