//! CONECT records of a PDB file, read by us. chemfiles 0.10 turns each CONECT line of some files
//! (1hpv.pdb, with TER records and identifiers in columns 73-80) into bonds from atom 0 to every
//! atom of the line, which drew a fan of nanometre-long sticks through the protein. Here CONECT
//! serials are mapped to atoms through the ATOM/HETATM serial column of the first model, and the
//! bonds of every atom that a CONECT record names become exactly the ones the records list
//! (template bonds of standard residues, which touch no such atom, stay as chemfiles made them).

use std::collections::{HashMap, HashSet};
use std::path::Path;

use crate::model::Topology;

/// The bonds the CONECT records of `text` list, as sorted pairs of 0-based atom indices, and
/// the number of atoms of the first model (`None` when the text has no CONECT record).
/// Bytes that are not ASCII never form a number.
fn conect_bonds(text: &[u8]) -> Option<(HashSet<[u32; 2]>, usize)> {
    let number = |field: Option<&[u8]>| -> Option<i64> {
        std::str::from_utf8(field?).ok()?.trim().parse().ok()
    };
    let mut serials: HashMap<i64, u32> = HashMap::new();
    let mut atoms = 0u32;
    let mut model_done = false;
    let mut bonds = HashSet::new();
    for line in super::fast::lines(text) {
        let record = line.get(..6).unwrap_or(line);
        match record.trim_ascii_end() {
            b"ATOM" | b"HETATM" if !model_done => {
                if let Some(serial) = number(line.get(6..11)) {
                    serials.entry(serial).or_insert(atoms);
                }
                atoms += 1;
            }
            b"ENDMDL" => model_done = true,
            b"CONECT" => {
                let field = |k: usize| -> Option<u32> {
                    serials
                        .get(&number(line.get(6 + 5 * k..11 + 5 * k))?)
                        .copied()
                };
                let Some(a) = field(0) else { continue };
                for b in (1..5).filter_map(field) {
                    if a != b {
                        bonds.insert([a.min(b), a.max(b)]);
                    }
                }
            }
            _ => {}
        }
    }
    (!bonds.is_empty()).then_some((bonds, atoms as usize))
}

/// Replaces the bonds of every atom named in `path`'s CONECT records by the bonds those records
/// list. Does nothing when the file has no CONECT record, cannot be read as text, or its first
/// model has another atom count than `topology`.
pub(crate) fn apply_conect(path: &Path, topology: &mut Topology) {
    if let Ok(bytes) = std::fs::read(path) {
        apply_conect_bytes(&bytes, topology);
    }
}

/// [`apply_conect`] on the bytes of a PDB file already in memory.
pub(crate) fn apply_conect_bytes(text: &[u8], topology: &mut Topology) {
    let Some((conect, atoms)) = conect_bonds(text) else {
        return;
    };
    if atoms != topology.len() {
        return;
    }
    let named: HashSet<u32> = conect.iter().flatten().copied().collect();
    let mut kept: HashSet<[u32; 2]> = topology
        .bonds
        .iter()
        .map(|&[a, b]| [a.min(b), a.max(b)])
        .filter(|[a, b]| !named.contains(a) && !named.contains(b))
        .collect();
    kept.extend(conect);
    let mut bonds: Vec<[u32; 2]> = kept.into_iter().collect();
    bonds.sort_unstable();
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
        let (bonds, atoms) = conect_bonds(text.as_bytes()).expect("bonds");
        assert_eq!(atoms, 3);
        assert_eq!(bonds, HashSet::from([[1, 2]]));
    }
}
