//! Lipids recognised by what they are, not only by name ([`super::residues::LIPIDS`]): a system
//! whose DMPC is named `DMP` or whose POPC is named `POP` must still open with its membrane as a
//! membrane. The `lipid` selection keyword (and so the default representations) takes a residue
//! type as a lipid when its name is in the list, or when it
//!
//! - is no amino acid, nucleotide, water or ion,
//! - occurs at least [`MIN_COPIES`] times (a membrane has many copies of each lipid; one copy
//!   of a large greasy molecule is a ligand), and
//! - looks like a lipid: in an all-atom file at least [`MIN_CARBONS`] carbons with a
//!   phosphorus (phospholipids) or with carbons making at least [`MIN_CARBON_SHARE`] of the
//!   heavy atoms (sterols, fatty acids, glycerides: long aliphatic chains); in a coarse-grained
//!   (Martini) file at least [`MIN_CG_BEADS`] beads, one of them a lipid head or linker bead
//!   ([`CG_HEAD_BEADS`]).
//!
//! The composition is read from the first residue of each name (residues of one name share
//! their atoms).

use std::collections::HashSet;
use std::sync::Arc;

use super::Topology;
use super::residues::{is_amino_acid, is_ion, is_lipid, is_nucleotide, is_water};

/// Residues of one name needed before the name can be a lipid.
pub const MIN_COPIES: usize = 10;
/// Carbons an all-atom lipid residue has at least (a C14 chain; DMPC has 36, cholesterol 27).
pub const MIN_CARBONS: usize = 14;
/// Share of carbons among the heavy atoms of an all-atom lipid without phosphorus.
pub const MIN_CARBON_SHARE: f32 = 0.75;
/// Beads a coarse-grained lipid residue has at least (Martini cholesterol has 8, POPC 12).
pub const MIN_CG_BEADS: usize = 6;
/// Martini bead names of lipid head groups, glycerol linkers and the sterol hydroxyl: choline
/// `NC3`, amine `NH3`, phosphate `PO4`, glycerol `GL1 GL2`, sphingosine `AM1 AM2`, cholesterol
/// `ROH`, glycerol head `GL0`, serine `CNO`.
pub const CG_HEAD_BEADS: [&str; 10] = [
    "NC3", "NH3", "PO4", "GL1", "GL2", "AM1", "AM2", "ROH", "GL0", "CNO",
];

/// What one residue holds.
#[derive(Debug, Default, Clone, Copy)]
struct Composition {
    atoms: usize,
    heavy: usize,
    carbons: usize,
    phosphorus: bool,
    cg_head: bool,
}

impl Composition {
    fn looks_like_lipid(&self) -> bool {
        let all_atom = self.carbons >= MIN_CARBONS
            && (self.phosphorus
                || self.carbons as f32 >= MIN_CARBON_SHARE * self.heavy.max(1) as f32);
        let coarse = self.cg_head && self.atoms >= MIN_CG_BEADS;
        all_atom || coarse
    }
}

/// The residue names of `topology` that are lipids by what they hold (not by the name list),
/// as written in the file.
pub fn lipid_like_names(topology: &Topology) -> HashSet<Arc<str>> {
    let (names, ids) = topology.residue_names.distinct();
    let n = ids.len().min(topology.residue_index.len());
    let candidate: Vec<bool> = names
        .iter()
        .map(|r| !(is_lipid(r) || is_amino_acid(r) || is_nucleotide(r) || is_water(r) || is_ion(r)))
        .collect();
    let mut copies = vec![0usize; names.len()];
    // The first residue of each name, as its residue index, and what it holds.
    let mut first: Vec<Option<u32>> = vec![None; names.len()];
    let mut holds = vec![Composition::default(); names.len()];
    for (i, &name) in ids.iter().enumerate().take(n) {
        let name = name as usize;
        if !candidate[name] {
            continue;
        }
        let residue = topology.residue_index[i];
        let starts_residue = i == 0 || topology.residue_index[i - 1] != residue;
        if starts_residue {
            copies[name] += 1;
        }
        let first_residue = *first[name].get_or_insert(residue);
        if residue != first_residue {
            continue;
        }
        let c = &mut holds[name];
        c.atoms += 1;
        let element = topology.elements.get(i).unwrap_or("");
        if element != "H" {
            c.heavy += 1;
        }
        c.carbons += usize::from(element == "C");
        c.phosphorus |= element == "P";
        let atom = topology.names.get(i).unwrap_or("").trim();
        c.cg_head |= CG_HEAD_BEADS.contains(&atom);
    }
    names
        .iter()
        .enumerate()
        .filter(|&(k, _)| candidate[k] && copies[k] >= MIN_COPIES && holds[k].looks_like_lipid())
        .map(|(_, name)| name.clone())
        .collect()
}
