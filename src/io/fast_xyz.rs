//! The fast XYZ reader (see [`super::fast`]): a plain single-frame XYZ file (atom count,
//! comment, then `NAME X Y Z` per atom, in Å) read in one pass, giving what chemfiles' XYZ
//! reader gives: names that are also the types, no elements (guessed later from the names), no
//! residues, bonds or box, each atom's charge from chemfiles' table. Extended XYZ (a comment with
//! `Properties=species:S:1:pos:R:3`) and files with more than one frame go to chemfiles.

use glam::Vec3;
use rayon::prelude::*;

use super::fast::{FastRead, LocalValues, PIECE_BYTES, TypeTable, empty_topology, free_text};
use super::fast::{is_space, line_count, line_pieces, lines, parse_f64, parse_u64, skip_lines};
use super::fast::{to_vec3, trim};
use crate::model::{Frame, Labels};

/// The atom lines of one piece of the file: positions (Å) and names.
struct Piece<'a> {
    positions: Vec<Vec3>,
    names: LocalValues<&'a [u8]>,
}

/// Reads an XYZ file's only frame, or `None` when chemfiles should read it. The atom lines
/// are parsed in parallel, in pieces of whole lines ([`line_pieces`]) joined in order.
pub(crate) fn read(bytes: &[u8]) -> Option<FastRead> {
    read_in_pieces(bytes, PIECE_BYTES)
}

/// [`read`], with the atom lines parsed in pieces of about `piece_bytes` bytes.
fn read_in_pieces(bytes: &[u8], piece_bytes: usize) -> Option<FastRead> {
    let mut it = lines(bytes);
    let n = usize::try_from(parse_u64(it.next()?)?).ok()?;
    let comment = it.next()?;
    if n == 0 || memchr::memmem::find(comment, b"species:S:1:pos:R:3").is_some() {
        return None;
    }
    // Each atom line holds at least a name and three numbers (4 bytes and 3 spaces).
    if bytes.len() / 8 < n {
        return None;
    }
    let body = skip_lines(bytes, 2);
    let pieces = line_pieces(body, piece_bytes);
    // The first line of each piece, counted from the first atom line.
    let counts: Vec<usize> = pieces.par_iter().map(|p| line_count(p)).collect();
    let mut first = Vec::with_capacity(pieces.len());
    let mut total = 0usize;
    for &c in &counts {
        first.push(total);
        total += c;
    }
    if total < n {
        return None; // the file ends before its last atom
    }
    let parsed: Vec<Piece> = pieces
        .par_iter()
        .zip(&first)
        .filter(|&(_, &f)| f < n)
        .map(|(piece, &f)| parse_piece(piece, n - f))
        .collect::<Option<_>>()?;
    let mut top = empty_topology(n);
    let mut table = TypeTable::default();
    // The pieces' distinct names, in order, become the topology's (first seen first); each
    // piece's atoms then take their global name ids and charges in parallel.
    let mut charge_of: Vec<f32> = Vec::new();
    let globals: Vec<Vec<u32>> = parsed
        .iter()
        .map(|piece| {
            piece
                .names
                .values
                .iter()
                .map(|name| {
                    let text = free_text(name);
                    let id = top.names.intern(&text);
                    if id as usize == charge_of.len() {
                        charge_of.push(table.get(&text).1);
                    }
                    id
                })
                .collect()
        })
        .collect();
    if parsed.iter().map(|p| p.positions.len()).sum::<usize>() != n {
        return None;
    }
    let mut ids = vec![0u32; n];
    let mut charges = vec![0.0f32; n];
    let mut targets = Vec::with_capacity(parsed.len());
    let (mut ids_rest, mut charges_rest) = (&mut ids[..], &mut charges[..]);
    for piece in &parsed {
        let len = piece.positions.len();
        let (ids_head, ids_tail) = ids_rest.split_at_mut(len);
        let (charges_head, charges_tail) = charges_rest.split_at_mut(len);
        targets.push((ids_head, charges_head));
        (ids_rest, charges_rest) = (ids_tail, charges_tail);
    }
    targets.into_par_iter().zip(&parsed).zip(&globals).for_each(
        |(((ids, charges), piece), global)| {
            for ((id, charge), &local) in ids.iter_mut().zip(charges).zip(&piece.names.ids) {
                *id = global[local as usize];
                *charge = charge_of[*id as usize];
            }
        },
    );
    top.names.extend_ids(&ids);
    top.charges = charges;
    let mut positions = Vec::with_capacity(n);
    for piece in &parsed {
        positions.extend_from_slice(&piece.positions);
    }
    // Names are the types; no element (guessed later from the name) and no mass.
    top.types = top.names.clone();
    top.elements = Labels::filled("", n);
    top.masses = vec![0.0; n];
    // chemfiles counts another frame unless the next line is blank (or there is none).
    let after = skip_lines(body, n);
    if lines(after)
        .next()
        .is_some_and(|line| !trim(line).is_empty())
    {
        return None;
    }
    let no_residue = vec![u32::MAX; n];
    top.number_residue_runs(&no_residue);
    Some(FastRead {
        topology: top,
        frame: Frame {
            index: 0,
            time_ps: None,
            positions,
            cell: None,
        },
    })
}

/// The first `limit` lines of `piece` (or all of them), each `NAME X Y Z ...`; `None` when one
/// does not parse.
fn parse_piece(piece: &[u8], limit: usize) -> Option<Piece<'_>> {
    let count = line_count(piece).min(limit);
    let mut positions = Vec::with_capacity(count);
    let mut names = LocalValues::with_capacity(count);
    for line in lines(piece).take(count) {
        let mut tokens = line.split(|&b| is_space(b)).filter(|t| !t.is_empty());
        let name = tokens.next()?;
        let x = parse_f64(tokens.next()?)?;
        let y = parse_f64(tokens.next()?)?;
        let z = parse_f64(tokens.next()?)?;
        positions.push(to_vec3([x, y, z]));
        names.push(name);
    }
    Some(Piece { positions, names })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_of_any_size_read_the_same() {
        let mut text = String::from("40\nnames repeat, some are new in later pieces\n");
        for i in 0..40 {
            let name = ["C", "H", "H", "O", "N", "Ca\u{e9}"][i % 6];
            let name = if i == 33 { "Zn" } else { name };
            text += &format!("{name} {}.125 -{}.5 {}\r\n", i, i * 2, i % 7);
        }
        text += "\n";
        let whole = read_in_pieces(text.as_bytes(), usize::MAX).expect("whole");
        for size in [1, 10, 64, 300] {
            let cut = read_in_pieces(text.as_bytes(), size).expect("pieces");
            assert!(cut.topology == whole.topology, "pieces of {size} bytes");
            assert_eq!(cut.frame, whole.frame, "pieces of {size} bytes");
            let (names, _) = cut.topology.names.distinct();
            let names: Vec<&str> = names.iter().map(|n| &**n).collect();
            assert_eq!(names, ["C", "H", "O", "N", "Ca\u{e9}", "Zn"]);
        }
        let short = &text[..text.len() - 40];
        assert!(read_in_pieces(short.as_bytes(), 64).is_none(), "short");
        let extra = format!("{}O 1 2 3\n", &text[..text.len() - 1]);
        assert!(
            read_in_pieces(extra.as_bytes(), 64).is_none(),
            "a second frame"
        );
    }

    #[test]
    fn plain_single_frames_only() {
        let f = read(b"2\nwater\nO 0 0 0\nH 0.96 0 0\n").expect("plain");
        assert_eq!(f.topology.names, vec!["O", "H"]);
        assert_eq!(f.topology.residue_index, vec![0, 1]);
        assert_eq!(f.frame.positions[1].x, 0.96);
        assert!(
            read(b"1\na\nO 0 0 0\n1\nb\nO 0 0 1\n").is_none(),
            "two frames"
        );
        assert!(read(b"2\na\nO 0 0 0\n").is_none(), "short");
        assert!(read(b"1\na\nO 0 0 zero\n").is_none(), "bad number");
        assert!(read(b"1\nProperties=species:S:1:pos:R:3\nO 0 0 0\n").is_none());
        assert!(read(b"0\nnothing\n").is_none());
    }
}
