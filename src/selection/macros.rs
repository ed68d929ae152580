//! The selection language's vocabulary: keyword names, and the macros (`protein`, `water`, ...)
//! with the residue and atom-name lists that define them. The residue lists live in
//! [`crate::model::residues`], shared with element guessing, colouring and beads.

use super::ast::{NumField, StrField};
use crate::model::Topology;
use crate::model::lipid_like::lipid_like_names;
use crate::model::residues::{is_amino_acid, is_ion, is_lipid, is_nucleotide, is_water};

/// Backbone atom names of amino-acid residues: the all-atom heavy backbone (`N CA C O`), the
/// C-terminal oxygens of the common force fields (`OXT OT1 OT2 OC1 OC2`), and the Martini
/// backbone bead `BB`.
pub const BACKBONE_NAMES: [&str; 10] =
    ["N", "CA", "C", "O", "OXT", "OT1", "OT2", "OC1", "OC2", "BB"];

/// Hydrogens bound to backbone atoms (amide `H`/`HN`, N-terminal `H1 H2 H3`/`HT1 HT2 HT3`,
/// alpha `HA`, glycine `HA1 HA2 HA3`); [`Macro::Sidechain`] leaves them out.
pub const BACKBONE_HYDROGENS: [&str; 12] = [
    "H", "HN", "H1", "H2", "H3", "HT1", "HT2", "HT3", "HA", "HA1", "HA2", "HA3",
];

/// A named class of atoms.
///
/// Residue-name tests are case-insensitive and use the lists of [`crate::model::residues`]:
/// amino acids (`AMINO_ACIDS`, with protonation variants such as `HSD HIE ASPP` and AMBER
/// terminal forms `NALA`/`CALA`), [`NUCLEOTIDES`](crate::model::residues::NUCLEOTIDES),
/// [`WATERS`](crate::model::residues::WATERS) and
/// [`CG_WATERS`](crate::model::residues::CG_WATERS),
/// [`LIPIDS`](crate::model::residues::LIPIDS), and ions (monatomic ion residues such as `NA`,
/// `NA+`, `SOD`, `CL`, `CL-`, `CLA`, `K`, `CA`, `MG`, `ZN`, plus
/// [`GENERIC_IONS`](crate::model::residues::GENERIC_IONS): Martini's `ION`, `ZNM`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Macro {
    /// Atoms of amino-acid residues (all-atom or Martini).
    Protein,
    /// Atoms of nucleotide residues (`DA`, `RU`, `A`, ...; a trailing `5`/`3` terminal mark, as
    /// in AMBER's `DA5`, is ignored).
    Nucleic,
    /// Protein atoms named in [`BACKBONE_NAMES`].
    Backbone,
    /// Protein atoms that are neither backbone nor in [`BACKBONE_HYDROGENS`] (Martini `SC1`...).
    Sidechain,
    /// Atoms of water residues (`SOL WAT HOH TIP3 ...`, Martini `W PW WF`).
    Water,
    /// Atoms of ion residues.
    Ion,
    /// Atoms of lipid residues (`POPC POPE POPG DPPC CHOL ...`), and of residue types that
    /// hold what lipids hold ([`crate::model::lipid_like`]: `DMP`, `POP`, Martini lipids under
    /// any name).
    Lipid,
    /// Atoms whose element is hydrogen (elements come from the file or are guessed from names).
    Hydrogen,
    /// Atoms that are not hydrogen (the same as `noh`).
    Heavy,
    /// Atoms that are not hydrogen (the same as `heavy`).
    NoH,
    /// Atoms in none of protein, nucleic, water, ion, lipid (drugs, cofactors, anything else;
    /// lipids recognised by content are no ligands either).
    Ligand,
}

impl Macro {
    /// The macro called `word`.
    pub(crate) fn from_word(word: &str) -> Option<Macro> {
        Some(match word {
            "protein" => Macro::Protein,
            "nucleic" => Macro::Nucleic,
            "backbone" => Macro::Backbone,
            "sidechain" => Macro::Sidechain,
            "water" => Macro::Water,
            "ion" => Macro::Ion,
            "lipid" => Macro::Lipid,
            "hydrogen" => Macro::Hydrogen,
            "heavy" => Macro::Heavy,
            "noh" => Macro::NoH,
            "ligand" => Macro::Ligand,
            _ => return None,
        })
    }

    /// Whether each atom of `topology` belongs to this class.
    pub(crate) fn mask(self, topology: &Topology) -> Vec<bool> {
        let n = topology.len();
        let name = |i: usize| &topology.names[i];
        let element = |i: usize| topology.elements.get(i).unwrap_or("");
        let by_residue = |test: fn(&str) -> bool| per_residue_name(topology, test);
        match self {
            Macro::Protein => by_residue(is_amino_acid),
            Macro::Nucleic => by_residue(is_nucleic),
            Macro::Water => by_residue(is_water),
            Macro::Ion => by_residue(is_ion),
            Macro::Lipid => lipid_mask(topology),
            Macro::Backbone => {
                let protein = by_residue(is_amino_acid);
                (0..n)
                    .map(|i| protein[i] && BACKBONE_NAMES.contains(&name(i)))
                    .collect()
            }
            Macro::Sidechain => {
                let protein = by_residue(is_amino_acid);
                (0..n)
                    .map(|i| {
                        protein[i]
                            && !BACKBONE_NAMES.contains(&name(i))
                            && !BACKBONE_HYDROGENS.contains(&name(i))
                    })
                    .collect()
            }
            Macro::Hydrogen => (0..n).map(|i| element(i) == "H").collect(),
            Macro::Heavy | Macro::NoH => (0..n).map(|i| element(i) != "H").collect(),
            Macro::Ligand => {
                let lipid = lipid_mask(topology);
                by_residue(is_ligand)
                    .into_iter()
                    .zip(lipid)
                    .map(|(ligand, lipid)| ligand && !lipid)
                    .collect()
            }
        }
    }
}

/// Atoms of lipid residues: named in the list, or recognised by what they hold
/// ([`lipid_like_names`]).
fn lipid_mask(topology: &Topology) -> Vec<bool> {
    let by_content = lipid_like_names(topology);
    let (names, ids) = topology.residue_names.distinct();
    let verdicts: Vec<bool> = names
        .iter()
        .map(|name| is_lipid(name) || by_content.contains(name))
        .collect();
    let mut mask: Vec<bool> = ids.iter().map(|&id| verdicts[id as usize]).collect();
    mask.resize(topology.len(), false);
    mask
}

/// Applies `test` once per distinct residue name (names repeat, tests are string searches).
fn per_residue_name(topology: &Topology, test: fn(&str) -> bool) -> Vec<bool> {
    let (names, ids) = topology.residue_names.distinct();
    let verdicts: Vec<bool> = names.iter().map(|name| test(name)).collect();
    let mut mask: Vec<bool> = ids.iter().map(|&id| verdicts[id as usize]).collect();
    // Atoms past the end of the residue names have the empty name.
    mask.resize(topology.len(), test(""));
    mask
}

/// Residue names in none of the classes protein, nucleic, water, ion, lipid.
fn is_ligand(r: &str) -> bool {
    !(is_amino_acid(r) || is_nucleic(r) || is_water(r) || is_ion(r) || is_lipid(r))
}

/// Nucleotide names, with AMBER's 5'/3' terminal marks (`DA5`, `RU3`) allowed.
fn is_nucleic(name: &str) -> bool {
    let name = name.trim();
    is_nucleotide(name)
        || (name.len() > 1
            && (name.ends_with('5') || name.ends_with('3'))
            && is_nucleotide(&name[..name.len() - 1]))
}

/// What a keyword selects on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Keyword {
    /// A string property.
    Str(StrField),
    /// A numeric property.
    Num(NumField),
}

/// The keyword called `word`.
pub(crate) fn keyword(word: &str) -> Option<Keyword> {
    use Keyword::{Num, Str};
    Some(match word {
        "name" => Str(StrField::Name),
        "type" => Str(StrField::Type),
        "element" => Str(StrField::Element),
        "resname" => Str(StrField::ResName),
        "chain" => Str(StrField::Chain),
        "segname" | "segid" => Str(StrField::Segment),
        "resid" => Num(NumField::ResId),
        "residue" => Num(NumField::Residue),
        "index" => Num(NumField::Index),
        "serial" => Num(NumField::Serial),
        "mass" => Num(NumField::Mass),
        "charge" => Num(NumField::Charge),
        "beta" | "bfactor" => Num(NumField::Beta),
        "occupancy" => Num(NumField::Occupancy),
        "x" => Num(NumField::Coord(0)),
        "y" => Num(NumField::Coord(1)),
        "z" => Num(NumField::Coord(2)),
        _ => return None,
    })
}

/// Every word the language knows, for "did you mean" suggestions.
pub(crate) const VOCABULARY: [&str; 36] = [
    "name",
    "type",
    "element",
    "resname",
    "chain",
    "segname",
    "segid",
    "resid",
    "residue",
    "index",
    "serial",
    "mass",
    "charge",
    "beta",
    "bfactor",
    "occupancy",
    "protein",
    "nucleic",
    "backbone",
    "sidechain",
    "water",
    "ion",
    "lipid",
    "hydrogen",
    "heavy",
    "noh",
    "ligand",
    "all",
    "none",
    "and",
    "or",
    "not",
    "within",
    "exwithin",
    "same",
    "of",
];

/// The known word closest to `word` (edit distance at most 2, and less than its length), for
/// "did you mean" hints.
pub(crate) fn suggest(word: &str) -> Option<&'static str> {
    let lower = word.to_ascii_lowercase();
    let mut best: Option<(usize, &'static str)> = None;
    for &candidate in VOCABULARY.iter().chain(["x", "y", "z"].iter()) {
        let d = edit_distance(&lower, candidate);
        if d <= 2 && d < word.len().max(2) && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, candidate));
        }
    }
    best.map(|(_, w)| w)
}

/// Levenshtein distance between two ASCII-ish strings (by chars).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(above + 1);
            diagonal = above;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions() {
        assert_eq!(suggest("resnam"), Some("resname"));
        assert_eq!(suggest("protien"), Some("protein"));
        assert_eq!(suggest("Name"), Some("name"));
        assert_eq!(suggest("qqqqqq"), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert!(is_nucleic("DA5") && is_nucleic("U") && !is_nucleic("ALA"));
    }
}
