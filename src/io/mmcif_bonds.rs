//! The bonds [`super::mmcif`] gives an mmCIF file with a `pdbx_PDB_model_num` column: the
//! template bonds of the standard residues ([`super::pdb_templates`]) and the peptide links
//! between consecutive residues, as chemfiles' `link_standard_residue_bonds` made them for its
//! mmCIF reader; consecutive nucleotides are linked O3'-P (chemfiles linked O3' to O3', and its
//! mmCIF reader never matched the quoted primed names anyway).

use super::pdb_templates::{NAMES, RESIDUES};
use crate::model::Labels;

/// One residue as the chemfiles path built it.
pub(crate) struct Residue<'a> {
    /// `label_comp_id` of its first atom.
    pub name: &'a [u8],
    /// Its number.
    pub id: i64,
    /// Its chain.
    pub chain: &'a [u8],
    /// Its atoms, ascending.
    pub atoms: Vec<u32>,
}

/// The bonds of the standard residues among `residues` (in the order they were found) and the
/// peptide and nucleic links between consecutive ones, as chemfiles'
/// `link_standard_residue_bonds` makes them (see the module notes), each as (low, high).
/// `names` are the atom names.
pub(crate) fn link_standard_residues(residues: &[Residue], names: &Labels) -> Vec<[u32; 2]> {
    // Template names are slots: those of NAMES, then HO5' (which no template lists). Each
    // distinct atom name is looked up once.
    const HO5: usize = NAMES.len();
    let slot_of_name: Vec<Option<usize>> = (names.distinct().0.iter())
        .map(|name| match NAMES.iter().position(|n| *n == &**name) {
            Some(k) => Some(k),
            None => (&**name == "HO5'").then_some(HO5),
        })
        .collect();
    let slot = |name: &str| NAMES.iter().position(|n| *n == name).unwrap_or(HO5);
    let [n_slot, c_slot, o3_slot, p_slot, o5_slot] = ["N", "C", "O3'", "P", "O5'"].map(slot);
    // The atom of each slot in the residue at hand (the last atom of a name counts, as in
    // chemfiles' map by name).
    let mut atom_in = vec![u32::MAX; NAMES.len() + 1];
    let mut bonds = Vec::new();
    let mut link_peptide = false;
    let mut link_nucleic = false;
    let mut previous_id = 0i64;
    let mut previous_link = 0u32;
    for residue in residues {
        let Ok(t) = RESIDUES.binary_search_by(|(n, _)| n.as_bytes().cmp(residue.name)) else {
            continue;
        };
        for &a in &residue.atoms {
            if let Some(k) = slot_of_name[names.id(a as usize) as usize] {
                atom_in[k] = a;
            }
        }
        let find = |k: usize| Some(atom_in[k]).filter(|&a| a != u32::MAX);
        let mut bond = |a: u32, b: u32| {
            if a != b {
                bonds.push([a.min(b), a.max(b)]);
            }
        };
        let id = residue.id;
        if link_peptide
            && let Some(n) = find(n_slot)
            && id == previous_id + 1
        {
            link_peptide = false;
            bond(previous_link, n);
        }
        if let Some(c) = find(c_slot) {
            link_peptide = true;
            previous_link = c;
            previous_id = id;
        }
        if link_nucleic
            && let Some(p) = find(p_slot)
            && id == previous_id + 1
        {
            link_nucleic = false;
            bond(previous_link, p);
        }
        if let Some(o3) = find(o3_slot) {
            link_nucleic = true;
            previous_link = o3;
            previous_id = id;
        }
        if let (Some(h), Some(o5)) = (find(HO5), find(o5_slot)) {
            bond(h, o5);
        }
        for &(a, b) in RESIDUES[t].1 {
            if let (Some(a), Some(b)) = (find(a as usize), find(b as usize)) {
                bond(a, b);
            }
        }
        for &a in &residue.atoms {
            if let Some(k) = slot_of_name[names.id(a as usize) as usize] {
                atom_in[k] = u32::MAX;
            }
        }
    }
    bonds
}
