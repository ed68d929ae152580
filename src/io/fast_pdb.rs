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

/// Number of [`ParsedAtom::chain_code`]s: one per byte value, and one for an empty column.
const CHAIN_CODES: usize = 257;

/// An atom name (columns 13-16) and element column (77-78), trimmed, each byte that is not
/// ASCII made `?`: the pair that decides an atom's name, type, element, mass and charge.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct NameKey {
    name: [u8; 4],
    name_len: u8,
    kind: [u8; 2],
    kind_len: u8,
}

impl NameKey {
    fn new(name: &[u8], kind: &[u8]) -> NameKey {
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

    fn name(&self) -> &str {
        std::str::from_utf8(&self.name[..self.name_len as usize]).unwrap_or_default()
    }

    fn kind(&self) -> &str {
        std::str::from_utf8(&self.kind[..self.kind_len as usize]).unwrap_or_default()
    }
}

/// What an ATOM/HETATM line holds, parsed on its own (no state needed).
struct ParsedAtom<'a> {
    line: &'a [u8],
    /// Whether the line reaches the element columns (77-78).
    kind_given: bool,
    /// Position in Å.
    position: [f64; 3],
    columns: Columns,
    /// The chain column (22) as [`enrich_columns`] reads it: its byte, or 256 when blank.
    chain_code: u16,
    /// chemfiles' residue key, when the residue number parses.
    residue: Option<ResKey>,
}

/// The lines of one piece that matter, in order.
enum Event<'a> {
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
struct Piece<'a> {
    events: Vec<Event<'a>>,
    /// The lines CONECT records are resolved with.
    conect: Vec<super::conect::ConectLine<'a>>,
    atoms: Vec<ParsedAtom<'a>>,
    /// The name key of each of `atoms`.
    keys: LocalValues<NameKey>,
}

/// Parses every line of `piece` that matters (see [`Event`]).
fn parse_piece(piece: &[u8]) -> Piece<'_> {
    let mut out = Piece {
        events: Vec::new(),
        conect: Vec::new(),
        atoms: Vec::with_capacity(piece.len() / 81 + 1),
        keys: LocalValues::with_capacity(piece.len() / 81 + 1),
    };
    for line in lines(piece) {
        if let Some(c) = super::conect::ConectLine::of(line) {
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
fn parse_atom(line: &[u8]) -> Option<(ParsedAtom<'_>, NameKey)> {
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

impl Reader {
    fn cryst1(&mut self, line: &[u8]) -> Option<()> {
        if line.len() < 54 {
            return None;
        }
        let v = |a: usize, b: usize| parse_f64(cols(line, a, b));
        let lengths = [v(6, 15)?, v(15, 24)?, v(24, 33)?];
        let angles = [v(33, 40)?, v(40, 47)?, v(47, 54)?];
        self.cell = Some((lengths, angles));
        Some(())
    }

    /// An atom joins: its name and element column are `names` and `kinds` ids.
    fn atom(&mut self, atom: &ParsedAtom, (name, kind): (u32, u32)) {
        let line = atom.line;
        if self.offsets.is_empty() {
            let first = decode_hybrid36(5, cols(line, 6, 11)).unwrap_or(1);
            self.offsets.push(if first <= 0 { 0 } else { first - 1 });
        }
        let index = self.names.len() as u32;
        self.names.push_id(name);
        self.kinds.push_id(kind);
        self.kind_given.push(atom.kind_given);
        self.positions.push(atom.position);
        let code = usize::from(atom.chain_code);
        let chain = match self.chain_ids[code] {
            Some(id) => id,
            None => {
                let text = match u8::try_from(code) {
                    Ok(b) => char::from(b).to_string(),
                    Err(_) => String::new(),
                };
                let id = self.column_chains.intern(&text);
                self.chain_ids[code] = Some(id);
                id
            }
        };
        self.columns.push(Columns {
            chain,
            ..atom.columns
        });
        self.residue_of.push(u32::MAX);
        let Some(key) = atom.residue else {
            return; // no residue
        };
        let slot = match self.last_residue {
            Some((last, slot)) if last == key => slot,
            _ => match self.segment_index.get(&key) {
                Some(&slot) => slot,
                None => {
                    let (chain, _, _, _) = key;
                    let chain_text = columns_text(&[chain]);
                    let segment = if line.len() > 72 {
                        columns_text(trim(cols(line, 72, 76)))
                    } else {
                        String::new()
                    };
                    let chain = match chain_text.trim() {
                        "" => segment.trim().to_string(),
                        c => c.to_string(),
                    };
                    self.segment.push(Residue {
                        key,
                        name: columns_text(trim(cols(line, 17, 20))),
                        chain,
                        segment: segment.trim().to_string(),
                        atoms: Vec::new(),
                    });
                    self.segment_index.insert(key, self.segment.len() - 1);
                    self.segment.len() - 1
                }
            },
        };
        self.last_residue = Some((key, slot));
        self.segment[slot].atoms.push(index);
    }

    /// chemfiles' `read_CONECT`: serials map to atoms through the first serial and the TER
    /// serials seen so far; bonds to atoms not (yet) read are dropped.
    fn conect(&mut self, line: &[u8]) -> Option<()> {
        if line.len() < 11 {
            return None;
        }
        let length = trim(line).len();
        let n = self.names.len() as i64;
        let index = |at: usize| -> Option<i64> {
            let id = decode_hybrid36(5, cols(line, at, at + 5))?;
            let below = self.offsets.partition_point(|&o| o < id) as i64;
            Some(id - below - self.offsets[0])
        };
        let i = index(6)?;
        for at in [11, 16, 21, 26] {
            if length <= at {
                break;
            }
            let j = index(at)?;
            if (0..n).contains(&i) && (0..n).contains(&j) {
                if i == j {
                    return None; // chemfiles refuses the file
                }
                self.bonds.push([i as u32, j as u32]);
            }
        }
        Some(())
    }

    /// chemfiles' `chain_ended`: the segment's residues join the topology in key order.
    fn chain_ended(&mut self) {
        let mut segment = std::mem::take(&mut self.segment);
        self.segment_index.clear();
        self.last_residue = None;
        segment.sort_by_key(|r| r.key);
        for residue in segment {
            let index = self.residues.len() as u32;
            for &a in &residue.atoms {
                self.residue_of[a as usize] = index;
            }
            self.residues.push(residue);
        }
    }

    /// chemfiles' `link_standard_residue_bonds`; `None` where chemfiles would fail. Atom names
    /// are compared as ids: those of [`Reader::names`], and ids past them for template names
    /// no atom has.
    fn link_standard_residues(&mut self) -> Option<()> {
        const SPECIAL: [&str; 6] = ["N", "C", "O3'", "P", "HO5'", "O5'"];
        let absent = self.names.distinct().0.len() as u32;
        let id_of = |name: &str| -> u32 {
            self.names
                .find(name)
                .unwrap_or_else(|| match NAMES.iter().position(|n| *n == name) {
                    Some(k) => absent + k as u32,
                    None => {
                        let k = SPECIAL.iter().position(|n| *n == name).unwrap_or(0);
                        absent + (NAMES.len() + k) as u32
                    }
                })
        };
        let template: Vec<u32> = NAMES.iter().map(|n| id_of(n)).collect();
        let [n_id, c_id, o3_id, p_id, ho5_id, o5_id] = SPECIAL.map(id_of);
        let mut link_peptide = false;
        let mut link_nucleic = false;
        let mut previous_id = 0i64;
        let mut previous_link = 0u32;
        let mut bonds = Vec::new();
        let mut by_name: Vec<(u32, u32)> = Vec::new();
        for residue in &self.residues {
            let Ok(t) = RESIDUES.binary_search_by(|(n, _)| n.cmp(&residue.name.as_str())) else {
                continue;
            };
            by_name.clear();
            for &a in &residue.atoms {
                let name = self.names.id(a as usize);
                match by_name.iter_mut().find(|(n, _)| *n == name) {
                    Some(slot) => slot.1 = a,
                    None => by_name.push((name, a)),
                }
            }
            let find = |by_name: &[(u32, u32)], name: u32| {
                by_name.iter().find(|(n, _)| *n == name).map(|&(_, a)| a)
            };
            let id = residue.key.1;
            let nitrogen = find(&by_name, n_id);
            if link_peptide
                && let Some(n) = nitrogen
                && id == previous_id + 1
            {
                link_peptide = false;
                bonds.push([previous_link, n]);
            }
            if let Some(c) = find(&by_name, c_id) {
                link_peptide = true;
                previous_link = c;
                previous_id = id;
            }
            let o3 = find(&by_name, o3_id);
            if link_nucleic && find(&by_name, p_id).is_some() && id == previous_id + 1 {
                link_nucleic = false;
                // chemfiles links the previous O3' to this residue's O3' (and reads past its
                // map when there is none).
                bonds.push([previous_link, o3?]);
            }
            if let Some(o) = o3 {
                link_nucleic = true;
                previous_link = o;
                previous_id = id;
            }
            if let Some(h) = find(&by_name, ho5_id) {
                // `map["O5'"]` inserts atom 0 when the residue has no O5'.
                let o5 = match find(&by_name, o5_id) {
                    Some(o) => o,
                    None => {
                        by_name.push((o5_id, 0));
                        0
                    }
                };
                bonds.push([h, o5]);
            }
            for &(a, b) in RESIDUES[t].1 {
                let (Some(a), Some(b)) = (
                    find(&by_name, template[a as usize]),
                    find(&by_name, template[b as usize]),
                ) else {
                    continue;
                };
                bonds.push([a, b]);
            }
        }
        if bonds.iter().any(|[a, b]| a == b) {
            return None;
        }
        self.bonds.extend(bonds);
        Some(())
    }

    /// The topology and frame as the chemfiles path leaves them after enrichment and CONECT.
    fn finish(self, pieces: &[Piece]) -> Option<FastRead> {
        let n = self.names.len();
        let mut top = empty_topology(n);
        let mut table = TypeTable::default();
        // Name, type, element, mass and charge follow from the (name, type) pair: worked out
        // once per distinct pair.
        type Derived = (u32, u32, u32, f32, f32);
        let mut derived: QuickMap<(u32, u32), Derived> = QuickMap::default();
        for i in 0..n {
            let given = self.kind_given[i];
            let key = (
                self.names.id(i),
                if given { self.kinds.id(i) } else { u32::MAX },
            );
            let (name, kind, element, mass, charge) = match derived.get(&key) {
                Some(&d) => d,
                None => {
                    let raw_name = &self.names[i];
                    let kind = if given { &self.kinds[i] } else { raw_name };
                    let name = if raw_name.trim().is_empty() {
                        kind
                    } else {
                        raw_name
                    };
                    let (mass, charge) = table.get(kind);
                    let (element, mass) = if kind != name {
                        (canonical_symbol(kind).unwrap_or_default(), mass)
                    } else {
                        ("", 0.0)
                    };
                    let d = (
                        top.names.intern(name),
                        top.types.intern(kind),
                        top.elements.intern(element),
                        if mass.is_finite() { mass } else { 0.0 },
                        charge,
                    );
                    derived.insert(key, d);
                    d
                }
            };
            top.masses.push(mass);
            top.charges.push(charge);
            top.elements.push_id(element);
            top.types.push_id(kind);
            top.names.push_id(name);
        }
        for residue in &self.residues {
            let name = top.residue_names.intern(&residue.name);
            let chain = top.chains.intern(&residue.chain);
            let segment = top.segments.intern(&residue.segment);
            for &a in &residue.atoms {
                let a = a as usize;
                top.residue_names.set_id(a, name);
                top.residue_ids[a] = residue.key.1;
                top.chains.set_id(a, chain);
                top.segments.set_id(a, segment);
            }
        }
        super::chem::number_residue_runs(&mut top, &self.residue_of);
        let mut bonds: Vec<[u32; 2]> = self
            .bonds
            .into_iter()
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        bonds.sort_unstable();
        bonds.dedup();
        top.bonds = bonds;
        apply_enrichment(&mut top, &self.columns, &self.column_chains);
        super::conect::resolve(
            pieces.iter().flat_map(|p| p.conect.iter().copied()),
            &mut top,
        );
        let cell = match self.cell {
            Some((lengths, angles)) => {
                let cell = super::quiet::silenced(|| {
                    super::chem::cell_rows_of(&chemfiles::UnitCell::triclinic(lengths, angles))
                });
                cell.ok()?
            }
            None => None,
        };
        let frame = Frame {
            index: 0,
            time_ps: None,
            positions: self.positions.into_iter().map(to_vec3).collect(),
            cell,
        };
        Some(FastRead {
            topology: top,
            frame,
        })
    }
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
