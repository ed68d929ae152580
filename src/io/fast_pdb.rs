//! The fast PDB reader (see [`super::fast`]): one pass over the first model's records gives the
//! topology chemfiles 0.10's PDB reader would give, then the wwPDB columns (B-factor, occupancy,
//! serial, element) and CONECT records are applied as [`super::wwpdb`] and [`super::conect`]
//! apply them on the chemfiles path. Residues follow chemfiles' rules: atoms group by (chain,
//! residue number, insertion code, residue name) between TER records, and residues are listed
//! in that order within each TER segment; standard residues get their template bonds
//! ([`super::pdb_templates`]) and peptide/nucleic links as chemfiles makes them. Positions in Å.

use std::borrow::Cow;
use std::collections::HashMap;

use super::fast::{
    FastRead, TypeTable, cols, columns_text, decode_hybrid36, empty_topology, lines, parse_f64,
    to_vec3, trim,
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
struct Columns {
    b_factor: f32,
    occupancy: f32,
    serial: Option<i64>,
    /// Chain column (22), trimmed: an id in [`Reader::column_chains`].
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
    segment_index: HashMap<ResKey, usize>,
    offsets: Vec<i64>,
    bonds: Vec<[u32; 2]>,
    cell: Option<([f64; 3], [f64; 3])>,
}

/// Reads a PDB file's only frame, or `None` when chemfiles should read it (see
/// [`super::fast`]).
pub(crate) fn read(bytes: &[u8]) -> Option<FastRead> {
    if frame_count(bytes) != 1 {
        return None;
    }
    let mut r = Reader::default();
    let mut atoms_seen = false;
    let mut it = lines(bytes).peekable();
    while let Some(line) = it.next() {
        if line.starts_with(b"ATOM") || line.starts_with(b"HETATM") {
            atoms_seen = true;
        }
        match record(line) {
            Record::Cryst1 => r.cryst1(line)?,
            Record::Atom => r.atom(line)?,
            // A CONECT record before any atom is dropped (as `prepare` drops it for chemfiles).
            Record::Conect if atoms_seen => r.conect(line)?,
            Record::Ter => {
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
            Record::EndModel => {
                if it.peek().is_some_and(|next| record(next) == Record::End) {
                    continue;
                }
                break;
            }
            Record::End => break,
            Record::Conect | Record::Other => {}
        }
    }
    r.chain_ended();
    r.link_standard_residues()?;
    r.finish(bytes)
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

    fn atom(&mut self, line: &[u8]) -> Option<()> {
        if line.len() < 54 {
            return None;
        }
        if self.offsets.is_empty() {
            let first = decode_hybrid36(5, cols(line, 6, 11)).unwrap_or(1);
            self.offsets.push(if first <= 0 { 0 } else { first - 1 });
        }
        let name = columns_text(trim(cols(line, 12, 16)));
        let kind_given = line.len() >= 78;
        let kind = if kind_given {
            columns_text(trim(cols(line, 76, 78)))
        } else {
            String::new()
        };
        let p = |a: usize| parse_f64(cols(line, a, a + 8));
        let position = [p(30)?, p(38)?, p(46)?];
        let atom = self.names.len() as u32;
        self.names.push(name);
        self.kinds.push(kind);
        self.kind_given.push(kind_given);
        self.positions.push(position);
        let columns = enrich_columns(line, &mut self.column_chains);
        self.columns.push(columns);
        self.residue_of.push(u32::MAX);
        let Some(id) = decode_hybrid36(4, cols(line, 22, 26)) else {
            return Some(()); // no residue
        };
        let ascii = |b: u8| if b.is_ascii() { b } else { b'?' };
        let chain = ascii(line[21]);
        let icode = ascii(line[26]);
        let resname = trim(cols(line, 17, 20));
        let mut padded = [0u8; 3];
        for (d, &s) in padded.iter_mut().zip(resname) {
            *d = ascii(s);
        }
        let key = (chain, id, icode, padded);
        let slot = match self.segment_index.get(&key) {
            Some(&slot) => slot,
            None => {
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
                    name: columns_text(resname),
                    chain,
                    segment: segment.trim().to_string(),
                    atoms: Vec::new(),
                });
                self.segment_index.insert(key, self.segment.len() - 1);
                self.segment.len() - 1
            }
        };
        self.segment[slot].atoms.push(atom);
        Some(())
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
        segment.sort_by_key(|r| r.key);
        for residue in segment {
            let index = self.residues.len() as u32;
            for &a in &residue.atoms {
                self.residue_of[a as usize] = index;
            }
            self.residues.push(residue);
        }
    }

    /// chemfiles' `link_standard_residue_bonds`; `None` where chemfiles would fail.
    fn link_standard_residues(&mut self) -> Option<()> {
        let mut link_peptide = false;
        let mut link_nucleic = false;
        let mut previous_id = 0i64;
        let mut previous_link = 0u32;
        let mut bonds = Vec::new();
        for residue in &self.residues {
            let Ok(t) = RESIDUES.binary_search_by(|(n, _)| n.cmp(&residue.name.as_str())) else {
                continue;
            };
            let mut by_name: Vec<(&str, u32)> = Vec::with_capacity(residue.atoms.len());
            for &a in &residue.atoms {
                let name = &self.names[a as usize];
                match by_name.iter_mut().find(|(n, _)| *n == name) {
                    Some(slot) => slot.1 = a,
                    None => by_name.push((name, a)),
                }
            }
            let find = |by_name: &[(&str, u32)], name: &str| {
                by_name.iter().find(|(n, _)| *n == name).map(|&(_, a)| a)
            };
            let id = residue.key.1;
            let nitrogen = find(&by_name, "N");
            if link_peptide
                && let Some(n) = nitrogen
                && id == previous_id + 1
            {
                link_peptide = false;
                bonds.push([previous_link, n]);
            }
            if let Some(c) = find(&by_name, "C") {
                link_peptide = true;
                previous_link = c;
                previous_id = id;
            }
            let o3 = find(&by_name, "O3'");
            if link_nucleic && find(&by_name, "P").is_some() && id == previous_id + 1 {
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
            if let Some(h) = find(&by_name, "HO5'") {
                // `map["O5'"]` inserts atom 0 when the residue has no O5'.
                let o5 = match find(&by_name, "O5'") {
                    Some(o) => o,
                    None => {
                        by_name.push(("O5'", 0));
                        0
                    }
                };
                bonds.push([h, o5]);
            }
            for &(a, b) in RESIDUES[t].1 {
                let (Some(a), Some(b)) = (
                    find(&by_name, NAMES[a as usize]),
                    find(&by_name, NAMES[b as usize]),
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
    fn finish(self, bytes: &[u8]) -> Option<FastRead> {
        let n = self.names.len();
        let mut top = empty_topology(n);
        let mut table = TypeTable::default();
        // Name, type, element, mass and charge follow from the (name, type) pair: worked out
        // once per distinct pair.
        type Derived = (u32, u32, u32, f32, f32);
        let mut derived: HashMap<(u32, u32), Derived> = HashMap::new();
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
            for &a in &residue.atoms {
                let a = a as usize;
                top.residue_names.set(a, &residue.name);
                top.residue_ids[a] = residue.key.1;
                top.chains.set(a, &residue.chain);
                top.segments.set(a, &residue.segment);
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
        super::conect::apply_conect_bytes(bytes, &mut top);
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

/// The wwPDB columns of an ATOM/HETATM line, parsed as [`super::wwpdb`] parses them.
fn enrich_columns(line: &[u8], chains: &mut Labels) -> Columns {
    let number = |a: usize, b: usize| field(line, a, b).parse::<f64>().ok();
    Columns {
        b_factor: number(60, 66).unwrap_or(0.0) as f32,
        occupancy: number(54, 60).unwrap_or(1.0) as f32,
        serial: field(line, 6, 11).parse().ok(),
        chain: chains.intern(&field(line, 21, 22)),
        element: canonical_symbol(&field(line, 76, 78)),
    }
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
