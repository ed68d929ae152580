//! CONECT records of a PDB file, read by us. chemfiles 0.10 turns each CONECT line of some files
//! (1hpv.pdb, with TER records and identifiers in columns 73-80) into bonds from atom 0 to every
//! atom of the line, which drew a fan of nanometre-long sticks through the protein. Here CONECT
//! serials are mapped to atoms through the ATOM/HETATM serial column of the first model, and the
//! bonds of every atom that a CONECT record names become exactly the ones the records list
//! (template bonds of standard residues, which touch no such atom, stay as chemfiles made them).

use super::fast::QuickMap;
use std::path::Path;

use crate::model::Topology;

/// A line of a PDB file as the CONECT pass reads it: every line of the file (not only the first
/// model's), classified by its first six bytes, trimmed.
#[derive(Debug, Clone, Copy)]
pub(crate) enum ConectLine<'a> {
    /// An ATOM/HETATM record and its serial number, when it has one.
    Atom(Option<i64>),
    /// An ENDMDL record.
    EndModel,
    /// A CONECT record (the whole line).
    Conect(&'a [u8]),
}

impl ConectLine<'_> {
    /// The [`ConectLine`] of `line`, or `None` for a record this pass ignores.
    pub(crate) fn of(line: &[u8]) -> Option<ConectLine<'_>> {
        let record = line.get(..6).unwrap_or(line);
        match record.trim_ascii_end() {
            b"ATOM" | b"HETATM" => Some(ConectLine::Atom(serial(line.get(6..11)))),
            b"ENDMDL" => Some(ConectLine::EndModel),
            b"CONECT" => Some(ConectLine::Conect(line)),
            _ => None,
        }
    }
}

/// A serial-number field (whitespace around digits); bytes that are not ASCII never form a
/// number.
fn serial(field: Option<&[u8]>) -> Option<i64> {
    std::str::from_utf8(field?).ok()?.trim().parse().ok()
}

/// The bonds the CONECT records among `lines` list, as sorted pairs of 0-based atom indices
/// (repeats possible), and the number of atoms of the first model. Serials map to atoms through
/// the ATOM/HETATM records of the first model read so far.
fn conect_bonds<'a>(lines: impl IntoIterator<Item = ConectLine<'a>>) -> (Vec<[u32; 2]>, usize) {
    let mut serials: QuickMap<i64, u32> = QuickMap::default();
    let mut atoms = 0u32;
    let mut model_done = false;
    let mut bonds = Vec::new();
    for line in lines {
        match line {
            ConectLine::Atom(number) if !model_done => {
                if let Some(number) = number {
                    serials.entry(number).or_insert(atoms);
                }
                atoms += 1;
            }
            ConectLine::Atom(_) => {}
            ConectLine::EndModel => model_done = true,
            ConectLine::Conect(line) => {
                let field = |k: usize| -> Option<u32> {
                    serials
                        .get(&serial(line.get(6 + 5 * k..11 + 5 * k))?)
                        .copied()
                };
                let Some(a) = field(0) else { continue };
                for b in (1..5).filter_map(field) {
                    if a != b {
                        bonds.push([a.min(b), a.max(b)]);
                    }
                }
            }
        }
    }
    (bonds, atoms as usize)
}

/// Replaces the bonds of every atom named in `path`'s CONECT records by the bonds those records
/// list. Does nothing when the file has no CONECT record, cannot be read as text, or its first
/// model has another atom count than `topology`.
pub(crate) fn apply_conect(path: &Path, topology: &mut Topology) {
    if let Ok(bytes) = std::fs::read(path) {
        resolve(
            super::fast::lines(&bytes).filter_map(ConectLine::of),
            topology,
        );
    }
}

/// [`apply_conect`] on the classified lines of a PDB file, in file order. The bonds end up as
/// sorted pairs `[low, high]` without repeats.
pub(crate) fn resolve<'a>(
    lines: impl IntoIterator<Item = ConectLine<'a>>,
    topology: &mut Topology,
) {
    let (conect, atoms) = conect_bonds(lines);
    if conect.is_empty() || atoms != topology.len() {
        return;
    }
    let mut named = vec![false; topology.len()];
    for &[a, b] in &conect {
        named[a as usize] = true;
        named[b as usize] = true;
    }
    let mut bonds: Vec<[u32; 2]> = topology
        .bonds
        .iter()
        .map(|&[a, b]| [a.min(b), a.max(b)])
        .filter(|&[a, b]| {
            !named.get(a as usize).copied().unwrap_or(false)
                && !named.get(b as usize).copied().unwrap_or(false)
        })
        .collect();
    bonds.extend(conect);
    bonds.sort_unstable();
    bonds.dedup();
    topology.bonds = bonds;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serials_skip_ter_records_and_blank_fields_are_ignored() {
        let text = "\
ATOM      1  N   ALA A   1       0.000   0.000   0.000  1.00  0.00           N
TER       2      ALA A   1
HETATM    3  C1  LIG   200       1.000   0.000   0.000  1.00  0.00           C
HETATM    4  C2  LIG   200       2.000   0.000   0.000  1.00  0.00           C
CONECT    3    4                                                    1XYZ  12
CONECT    4    3
END
";
        let lines = crate::io::fast::lines(text.as_bytes()).filter_map(ConectLine::of);
        let (bonds, atoms) = conect_bonds(lines);
        assert_eq!(atoms, 3);
        assert_eq!(bonds, [[1, 2], [1, 2]]);
    }
}
