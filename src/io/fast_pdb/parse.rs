//! Parsing the PDB records of one piece of the file (pieces are parsed in parallel): ATOM/HETATM
//! lines into [`ParsedAtom`]s with their name keys, and the other records into [`Event`]s in
//! file order.

use super::*;

/// Number of [`ParsedAtom::chain_code`]s: one per byte value, and one for an empty column.
pub(super) const CHAIN_CODES: usize = 257;

/// An atom name (columns 13-16) and element column (77-78), trimmed, each byte that is not
/// ASCII made `?`: the pair that decides an atom's name, type, element, mass and charge.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct NameKey {
    pub(super) name: [u8; 4],
    pub(super) name_len: u8,
    pub(super) kind: [u8; 2],
    pub(super) kind_len: u8,
}

impl NameKey {
    pub(super) fn new(name: &[u8], kind: &[u8]) -> NameKey {
        let mut key = NameKey {
            name: [0; 4],
            name_len: name.len().min(4) as u8,
            kind: [0; 2],
            kind_len: kind.len().min(2) as u8,
        };
        for (d, &b) in key.name.iter_mut().zip(name) {
            *d = if b.is_ascii() { b } else { b'?' };
        }
        for (d, &b) in key.kind.iter_mut().zip(kind) {
            *d = if b.is_ascii() { b } else { b'?' };
        }
        key
    }

    pub(super) fn name(&self) -> &str {
        std::str::from_utf8(&self.name[..self.name_len as usize]).unwrap_or_default()
    }

    pub(super) fn kind(&self) -> &str {
        std::str::from_utf8(&self.kind[..self.kind_len as usize]).unwrap_or_default()
    }
}

/// What an ATOM/HETATM line holds, parsed on its own (no state needed).
pub(super) struct ParsedAtom<'a> {
    pub(super) line: &'a [u8],
    /// Whether the line reaches the element columns (77-78).
    pub(super) kind_given: bool,
    /// Position in Å.
    pub(super) position: [f64; 3],
    pub(super) columns: Columns,
    /// The chain column (22) as [`enrich_columns`] reads it: its byte, or 256 when blank.
    pub(super) chain_code: u16,
    /// chemfiles' residue key, when the residue number parses.
    pub(super) residue: Option<ResKey>,
}

/// The lines of one piece that matter, in order.
pub(super) enum Event<'a> {
    /// The next of [`Piece::atoms`].
    Atom,
    /// An ATOM/HETATM record chemfiles refuses.
    BadAtom,
    /// Another line starting with `ATOM` or `HETATM`.
    AtomsSeen,
    Cryst1(&'a [u8]),
    Conect(&'a [u8]),
    Ter(&'a [u8]),
    End,
    EndModel(&'a [u8]),
}

/// One piece of the file, parsed.
pub(super) struct Piece<'a> {
    pub(super) events: Vec<Event<'a>>,
    /// The lines CONECT records are resolved with.
    pub(super) conect: Vec<crate::io::conect::ConectLine<'a>>,
    pub(super) atoms: Vec<ParsedAtom<'a>>,
    /// The name key of each of `atoms`.
    pub(super) keys: LocalValues<NameKey>,
}

/// Parses every line of `piece` that matters (see [`Event`]).
pub(super) fn parse_piece(piece: &[u8]) -> Piece<'_> {
    let mut out = Piece {
        events: Vec::new(),
        conect: Vec::new(),
        atoms: Vec::with_capacity(piece.len() / 81 + 1),
        keys: LocalValues::with_capacity(piece.len() / 81 + 1),
    };
    for line in lines(piece) {
        if let Some(c) = crate::io::conect::ConectLine::of(line) {
            out.conect.push(c);
        }
        let event = match record(line) {
            Record::Atom => match parse_atom(line) {
                Some((atom, key)) => {
                    out.atoms.push(atom);
                    out.keys.push(key);
                    Event::Atom
                }
                None => Event::BadAtom,
            },
            Record::Cryst1 => Event::Cryst1(line),
            Record::Conect => Event::Conect(line),
            Record::Ter => Event::Ter(line),
            Record::End => Event::End,
            Record::EndModel => Event::EndModel(line),
            Record::Other if line.starts_with(b"ATOM") || line.starts_with(b"HETATM") => {
                Event::AtomsSeen
            }
            Record::Other => continue,
        };
        out.events.push(event);
    }
    out
}

/// An ATOM/HETATM line as chemfiles reads it; `None` where chemfiles refuses the file.
pub(super) fn parse_atom(line: &[u8]) -> Option<(ParsedAtom<'_>, NameKey)> {
    if line.len() < 54 {
        return None;
    }
    let kind_given = line.len() >= 78;
    let kind: &[u8] = if kind_given {
        trim(cols(line, 76, 78))
    } else {
        b""
    };
    let key = NameKey::new(trim(cols(line, 12, 16)), kind);
    let p = |a: usize| parse_f64(cols(line, a, a + 8));
    let position = [p(30)?, p(38)?, p(46)?];
    let (columns, chain) = enrich_columns(line);
    let chain_code = match chain.as_bytes() {
        [] => 256,
        [b] => u16::from(*b),
        _ => return None, // one column cannot hold more
    };
    let residue = decode_hybrid36(4, cols(line, 22, 26)).map(|id| {
        let ascii = |b: u8| if b.is_ascii() { b } else { b'?' };
        let resname = trim(cols(line, 17, 20));
        let mut padded = [0u8; 3];
        for (d, &s) in padded.iter_mut().zip(resname) {
            *d = ascii(s);
        }
        (ascii(line[21]), id, ascii(line[26]), padded)
    });
    let atom = ParsedAtom {
        line,
        kind_given,
        position,
        columns,
        chain_code,
        residue,
    };
    Some((atom, key))
}
