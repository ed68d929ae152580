//! The fast PDB reader (see [`super::fast`]): one pass over the first model's records gives the
//! topology chemfiles 0.10's PDB reader would give, then the wwPDB columns (B-factor, occupancy,
//! serial, element) and CONECT records are applied as [`super::wwpdb`] and [`super::conect`]
//! apply them on the chemfiles path. Residues follow chemfiles' rules: atoms group by (chain,
//! residue number, insertion code, residue name) between TER records, and residues are listed
//! in that order within each TER segment; standard residues get their template bonds
//! ([`super::pdb_templates`]) and peptide/nucleic links as chemfiles makes them. Positions in Å.

use std::borrow::Cow;

use rayon::prelude::*;

use super::fast::{
    FastRead, LocalValues, PIECE_BYTES, QuickMap, TypeTable, cols, columns_text, decode_hybrid36,
    empty_topology, line_pieces, lines, parse_f64, parse_f64_std, to_vec3, trim,
};
use super::pdb_templates::{NAMES, RESIDUES};
use crate::model::elements::canonical_symbol;
use crate::model::{Frame, Labels, Topology};

mod parse;
mod topology;

use parse::*;

/// chemfiles' key of a residue within a TER segment, in its sort order: chain, number,
/// insertion code, name (up to 3 bytes, zero-padded so that shorter names sort first).
type ResKey = (u8, i64, u8, [u8; 3]);

/// One residue as chemfiles builds it.
struct Residue {
    key: ResKey,
    name: String,
    /// The `chainid` property (column 22), else the segment name, trimmed.
    chain: String,
    /// The `segname` property (columns 73-76, trimmed).
    segment: String,
    atoms: Vec<u32>,
}

/// Per-atom values read from the columns the wwPDB enrichment reads.
#[derive(Clone, Copy)]
struct Columns {
    b_factor: f32,
    occupancy: f32,
    serial: Option<i64>,
    /// Chain column (22), trimmed: an id in [`Reader::column_chains`] (set when the atom
    /// joins the reader; [`ParsedAtom::chain_code`] until then).
    chain: u32,
    element: Option<&'static str>,
}

/// The record of a line as chemfiles' `get_record` classifies it (only those we act on).
#[derive(PartialEq)]
enum Record {
    Cryst1,
    Atom,
    Conect,
    Ter,
    End,
    EndModel,
    Other,
}

fn record(line: &[u8]) -> Record {
    let rec = cols(line, 0, 6);
    if rec == b"ENDMDL" {
        Record::EndModel
    } else if rec.starts_with(b"END") {
        Record::End
    } else if rec == b"CRYST1" {
        Record::Cryst1
    } else if rec == b"ATOM  " || rec == b"HETATM" {
        Record::Atom
    } else if rec == b"CONECT" {
        Record::Conect
    } else if rec.starts_with(b"TER") {
        Record::Ter
    } else {
        Record::Other
    }
}

/// The number of frames chemfiles finds in the file (its `forward`: one per `END*` record, an
/// `ENDMDL` directly followed by an `END*` record counting once; 1 without any).
fn frame_count(bytes: &[u8]) -> usize {
    let mut steps = 0;
    let mut it = lines(bytes).peekable();
    while let Some(line) = it.next() {
        if line.starts_with(b"ENDMDL") && it.peek().is_some_and(|next| next.starts_with(b"END")) {
            continue;
        }
        if line.starts_with(b"END") {
            steps += 1;
        }
    }
    steps.max(1)
}

/// The state of one read (chemfiles' `PDBFormat` members).
#[derive(Default)]
struct Reader {
    /// Atom names (columns 13-16, trimmed).
    names: Labels,
    /// Element columns (77-78, trimmed) of lines long enough to have them ...
    kinds: Labels,
    /// ... and whether each atom's line had them.
    kind_given: Vec<bool>,
    /// Distinct values of the chain column of every atom.
    column_chains: Labels,
    positions: Vec<[f64; 3]>,
    columns: Vec<Columns>,
    residue_of: Vec<u32>,
    residues: Vec<Residue>,
    segment: Vec<Residue>,
    segment_index: QuickMap<ResKey, usize>,
    /// The residue key and slot in `segment` of the last atom (neighbours share residues).
    last_residue: Option<(ResKey, usize)>,
    /// Id in `column_chains` of each [`ParsedAtom::chain_code`] seen so far.
    chain_ids: Vec<Option<u32>>,
    offsets: Vec<i64>,
    bonds: Vec<[u32; 2]>,
    cell: Option<([f64; 3], [f64; 3])>,
}

/// Reads a PDB file's only frame, or `None` when chemfiles should read it (see
/// [`super::fast`]).
pub(crate) fn read(bytes: &[u8]) -> Option<FastRead> {
    read_in_pieces(bytes, PIECE_BYTES)
}

/// [`read`], with the lines parsed in pieces of about `piece_bytes` bytes.
fn read_in_pieces(bytes: &[u8], piece_bytes: usize) -> Option<FastRead> {
    if frame_count(bytes) != 1 {
        return None;
    }
    // The lines are parsed in parallel, piece by piece; the records that carry state (atoms
    // joining residues, TER, CONECT, END) are then applied in file order, as chemfiles reads.
    let pieces: Vec<Piece> = line_pieces(bytes, piece_bytes)
        .par_iter()
        .map(|piece| parse_piece(piece))
        .collect();
    let mut r = Reader {
        chain_ids: vec![None; CHAIN_CODES],
        ..Reader::default()
    };
    let mut atoms_seen = false;
    'file: for piece in &pieces {
        // Global ids of the piece's distinct (name, element column) pairs.
        let key_ids: Vec<(u32, u32)> = piece
            .keys
            .values
            .iter()
            .map(|k| (r.names.intern(k.name()), r.kinds.intern(k.kind())))
            .collect();
        let mut atoms = piece.atoms.iter().zip(&piece.keys.ids);
        for event in &piece.events {
            match *event {
                Event::Atom => {
                    atoms_seen = true;
                    let (atom, &local) = atoms.next()?;
                    r.atom(atom, key_ids[local as usize]);
                }
                Event::BadAtom => return None,
                Event::AtomsSeen => atoms_seen = true,
                Event::Cryst1(line) => r.cryst1(line)?,
                // A CONECT record before any atom is dropped (as `prepare` drops it for
                // chemfiles).
                Event::Conect(line) => {
                    if atoms_seen {
                        r.conect(line)?;
                    }
                }
                Event::Ter(line) => {
                    if line.len() >= 12
                        && let Some(serial) = decode_hybrid36(5, cols(line, 6, 11))
                        && serial != 0
                    {
                        if serial < 0 {
                            return None;
                        }
                        r.offsets.push(serial);
                    }
                    r.chain_ended();
                }
                Event::EndModel(line) => {
                    let start = line.as_ptr() as usize - bytes.as_ptr() as usize;
                    let rest = super::fast::skip_lines(&bytes[start..], 1);
                    if lines(rest)
                        .next()
                        .is_some_and(|next| record(next) == Record::End)
                    {
                        continue;
                    }
                    break 'file;
                }
                Event::End => break 'file,
            }
        }
    }
    r.chain_ended();
    r.link_standard_residues()?;
    r.finish(&pieces)
}

/// A column as [`super::wwpdb`] reads it: clipped to the line, trimmed.
fn field(line: &[u8], a: usize, b: usize) -> Cow<'_, str> {
    let bytes = line.get(a..b.min(line.len())).unwrap_or_default();
    match std::str::from_utf8(bytes) {
        Ok(s) if bytes.is_ascii() => Cow::Borrowed(s.trim()),
        _ => Cow::Owned(columns_text(bytes).trim().to_string()),
    }
}

/// The wwPDB columns of an ATOM/HETATM line, parsed as [`super::wwpdb`] parses them, and the
/// chain column as it reads it (the id in [`Columns::chain`] is left 0).
fn enrich_columns(line: &[u8]) -> (Columns, Cow<'_, str>) {
    let number = |a: usize, b: usize| parse_f64_std(&field(line, a, b));
    let columns = Columns {
        b_factor: number(60, 66).unwrap_or(0.0) as f32,
        occupancy: number(54, 60).unwrap_or(1.0) as f32,
        serial: field(line, 6, 11).parse().ok(),
        chain: 0,
        element: canonical_symbol(&field(line, 76, 78)),
    };
    (columns, field(line, 21, 22))
}

/// What [`super::wwpdb::enrich`] copies: B-factors, occupancies, serials, and chains and
/// elements where empty.
fn apply_enrichment(top: &mut Topology, columns: &[Columns], chains: &Labels) {
    for (i, c) in columns.iter().enumerate() {
        top.b_factors[i] = c.b_factor;
        top.occupancies[i] = c.occupancy;
        if let Some(serial) = c.serial {
            top.serials[i] = serial;
        }
        if top.chains[i].is_empty() {
            top.chains.set(i, &*chains.distinct().0[c.chain as usize]);
        }
        if top.elements[i].is_empty()
            && let Some(element) = c.element
        {
            top.elements.set(i, element);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by fuzzing (`scripts/fuzz`, target `pdb`): a CONECT record after an atom line the
    /// reader saw but did not parse indexed the empty list of first serials (a panic). The file
    /// is now declined (left to the chemfiles path, or its one-line error without chemfiles).
    #[test]
    fn conect_without_a_first_serial_is_declined_not_a_panic() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fuzz/pdb/conect_without_first_serial.pdb");
        let bytes = std::fs::read(path).expect("the regression input");
        assert!(read(&bytes).is_none());
    }

    #[test]
    fn frames_are_counted_as_chemfiles_counts_them() {
        assert_eq!(frame_count(b"ATOM\n"), 1);
        assert_eq!(frame_count(b"MODEL 1\nENDMDL\nEND\n"), 1);
        assert_eq!(frame_count(b"MODEL 1\nENDMDL\nMODEL 2\nENDMDL\nEND\n"), 2);
    }

    #[test]
    fn pieces_of_any_size_read_the_same() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        for name in ["1hpv.pdb", "1hvr.pdb", "5a7u.pdb", "adk_open.pdb"] {
            let bytes = std::fs::read(dir.join(name)).expect("test file");
            let whole = read_in_pieces(&bytes, usize::MAX).expect("whole");
            assert!(!whole.topology.bonds.is_empty(), "{name}");
            for size in [1, 81, 4000] {
                let cut = read_in_pieces(&bytes, size).expect("pieces");
                assert!(
                    cut.topology == whole.topology,
                    "{name}: pieces of {size} bytes"
                );
                assert_eq!(cut.frame, whole.frame, "{name}: pieces of {size} bytes");
            }
        }
        // A model ended by ENDMDL then END, split between the two.
        let text = b"ATOM      1  CA  ALA A   1       1.000   2.000   3.000  1.00  0.00           C\nENDMDL\nEND\n";
        let cut = read_in_pieces(text, 1).expect("pieces");
        assert_eq!(cut.topology.len(), 1);
    }

    #[test]
    fn short_or_damaged_atom_lines_go_to_chemfiles() {
        assert!(read(b"ATOM      1  CA  ALA A   1      1.000   2.000\n").is_none());
        let bad =
            b"ATOM      1  CA  ALA A   1      1.000   x.000   3.000  1.00  0.00           C\n";
        assert!(read(bad).is_none());
        let good =
            b"ATOM      1  CA  ALA A   1      1.000   2.000   3.000  1.00  0.00           C\n";
        let f = read(good).expect("read");
        assert_eq!(f.topology.names, vec!["CA"]);
        assert_eq!(f.topology.elements, vec!["C"]);
        assert_eq!(f.frame.positions[0].z, 3.0);
    }
}
