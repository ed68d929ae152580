//! Residue-name knowledge shared by element guessing, colouring and beads: which residues are
//! amino acids, nucleotides, water, ions or lipids, and how an amino acid behaves.

/// The broad chemical class of an amino acid side chain (for the residue-type colour scheme).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResidueClass {
    /// Apolar side chain (ALA, VAL, LEU, ILE, MET, PHE, TRP, PRO, GLY).
    Hydrophobic,
    /// Polar, uncharged side chain (SER, THR, CYS, TYR, ASN, GLN).
    Polar,
    /// Negatively charged side chain (ASP, GLU).
    Acid,
    /// Positively charged side chain (LYS, ARG, HIS).
    Base,
    /// Not an amino acid (water, ions, lipids, ligands, nucleotides).
    Other,
}

/// Amino-acid names with their class; protonation and force-field variants included.
const AMINO_ACIDS: [(&str, ResidueClass); 38] = {
    use ResidueClass::*;
    [
        ("ALA", Hydrophobic),
        ("VAL", Hydrophobic),
        ("LEU", Hydrophobic),
        ("ILE", Hydrophobic),
        ("MET", Hydrophobic),
        ("PHE", Hydrophobic),
        ("TRP", Hydrophobic),
        ("PRO", Hydrophobic),
        ("GLY", Hydrophobic),
        ("MSE", Hydrophobic),
        ("NLE", Hydrophobic),
        ("SER", Polar),
        ("THR", Polar),
        ("CYS", Polar),
        ("CYX", Polar),
        ("CYM", Polar),
        ("TYR", Polar),
        ("ASN", Polar),
        ("GLN", Polar),
        ("ASP", Acid),
        ("GLU", Acid),
        ("ASH", Acid),
        ("GLH", Acid),
        ("ASPP", Acid),
        ("GLUP", Acid),
        ("LYS", Base),
        ("LYN", Base),
        ("LSN", Base),
        ("ARG", Base),
        ("ARN", Base),
        ("HIS", Base),
        ("HID", Base),
        ("HIE", Base),
        ("HIP", Base),
        ("HSD", Base),
        ("HSE", Base),
        ("HSP", Base),
        ("HISH", Base),
    ]
};

/// Nucleotide residue names (DNA and RNA, with common terminal variants).
pub const NUCLEOTIDES: [&str; 16] = [
    "A", "C", "G", "U", "T", "DA", "DC", "DG", "DT", "RA", "RC", "RG", "RU", "ADE", "CYT", "GUA",
];

/// Water residue names of the common force fields.
pub const WATERS: [&str; 16] = [
    "SOL", "WAT", "HOH", "H2O", "TIP3", "TIP4", "TIP5", "SPC", "T3P", "T4P", "T5P", "TIP3P",
    "TIP4P", "SPCE", "OPC", "WATER",
];

/// Lipid residue names (all-atom CHARMM/GROMACS/Slipids names, AMBER Lipid14 fragments, and
/// Martini coarse-grained lipids, which share the all-atom names). Their atoms use the usual
/// C/H/N/O/P naming in all-atom files.
pub const LIPIDS: [&str; 65] = [
    // Phosphatidylcholines (PC), -ethanolamines (PE), -glycerols (PG), -serines (PS),
    // -acids (PA), -inositols (PI).
    "POPC", "POPE", "POPG", "POPS", "POPA", "POPI", "DPPC", "DPPE", "DPPG", "DPPS", "DOPC", "DOPE",
    "DOPG", "DOPS", "DMPC", "DMPE", "DMPG", "DMPS", "DSPC", "DSPE", "DSPG", "DLPC", "DLPE", "DLPG",
    "DAPC", "DUPC", "DIPC", "DIPE", "PAPC", "PAPE", "PAPS", "PUPC", "PUPE", "PIPC", "PIPE", "DPPI",
    "POPX", "SOPC", "SDPC",
    // Phosphoinositides, cardiolipin, sphingolipids and ceramides.
    "PIP2", "POP2", "PIP3", "CDL", "CDL2", "TOCL", "CARD", "DPSM", "PSM", "SSM", "DPCE",
    // Sterols.
    "CHOL", "CHL1", "CHL", "ERG", // Glycerides and fatty acids.
    "TRIO", "DAG", "PALM", "OLEO",
    // AMBER Lipid14/17 fragments: tails (PA palmitoyl, OL oleoyl, MY myristoyl) and heads.
    "PA", "PC", "OL", "MY", "PE", "PGR", "PGS",
];

/// Water residue names of coarse-grained Martini models (`W` standard, `PW` polarisable, `WF`
/// antifreeze); all-atom waters are in [`is_water`]'s other list.
pub const CG_WATERS: [&str; 3] = ["W", "PW", "WF"];

/// Coarse-grained or generic ion residue names that are no element (Martini's `ION` residue
/// holds `NA+`/`CL-` beads; `ZNM` is the zinc cationic dummy model).
pub const GENERIC_IONS: [&str; 2] = ["ION", "ZNM"];

/// Strips a terminal prefix (`N`/`C` as in AMBER's `NALA`, `CALA`) when the rest is an amino acid.
fn strip_terminal(residue: &str) -> &str {
    if residue.len() == 4 && (residue.starts_with('N') || residue.starts_with('C')) {
        let rest = &residue[1..];
        if AMINO_ACIDS.iter().any(|(n, _)| *n == rest) {
            return rest;
        }
    }
    residue
}

/// The class of residue `name` (case-insensitive).
pub fn residue_class(name: &str) -> ResidueClass {
    let upper = name.trim().to_ascii_uppercase();
    let core = strip_terminal(&upper);
    AMINO_ACIDS
        .iter()
        .find(|(n, _)| *n == core)
        .map_or(ResidueClass::Other, |(_, class)| *class)
}

/// True for amino acids (any protonation state or terminal variant).
pub fn is_amino_acid(name: &str) -> bool {
    residue_class(name) != ResidueClass::Other
}

/// True for residues made of ordinary organic atoms named by the C/H/N/O/S/P convention
/// (amino acids, nucleotides, water, common lipids).
pub fn is_standard_organic(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    is_amino_acid(&upper)
        || NUCLEOTIDES.contains(&upper.as_str())
        || WATERS.contains(&upper.as_str())
        || LIPIDS.contains(&upper.as_str())
}

/// True for nucleotide residue names (DNA and RNA), case-insensitive.
pub fn is_nucleotide(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    NUCLEOTIDES.contains(&upper.as_str())
}

/// True for water residue names, all-atom (`SOL`, `WAT`, `HOH`, `TIP3`, ...) or Martini (`W`,
/// `PW`, `WF`), case-insensitive.
pub fn is_water(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    WATERS.contains(&upper.as_str()) || CG_WATERS.contains(&upper.as_str())
}

/// True for lipid residue names ([`LIPIDS`]), case-insensitive.
pub fn is_lipid(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    LIPIDS.contains(&upper.as_str())
}

/// True for ion residue names: a monatomic ion ([`ion_element`]) or a generic ion residue
/// ([`GENERIC_IONS`]), case-insensitive.
pub fn is_ion(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    ion_element(&upper).is_some() || GENERIC_IONS.contains(&upper.as_str())
}

/// The element of a monatomic ion residue (`NA`, `SOD`, `CL`, `CLA`, `CA`, `CAL`, `ZN`, ...).
pub fn ion_element(residue: &str) -> Option<&'static str> {
    const IONS: [(&str, &str); 24] = [
        ("NA", "Na"),
        ("NA+", "Na"),
        ("SOD", "Na"),
        ("CL", "Cl"),
        ("CL-", "Cl"),
        ("CLA", "Cl"),
        ("K", "K"),
        ("K+", "K"),
        ("POT", "K"),
        ("CA", "Ca"),
        ("CAL", "Ca"),
        ("CA2+", "Ca"),
        ("MG", "Mg"),
        ("MG2+", "Mg"),
        ("ZN", "Zn"),
        ("ZN2", "Zn"),
        ("FE", "Fe"),
        ("FE2", "Fe"),
        ("CU", "Cu"),
        ("MN", "Mn"),
        ("LI", "Li"),
        ("CS", "Cs"),
        ("RB", "Rb"),
        ("BR", "Br"),
    ];
    let upper = residue.trim().to_ascii_uppercase();
    IONS.iter().find(|(n, _)| *n == upper).map(|(_, e)| *e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes() {
        assert_eq!(residue_class("LEU"), ResidueClass::Hydrophobic);
        assert_eq!(residue_class("asp"), ResidueClass::Acid);
        assert_eq!(residue_class("HSD"), ResidueClass::Base);
        assert_eq!(residue_class("NSER"), ResidueClass::Polar);
        assert_eq!(residue_class("SOL"), ResidueClass::Other);
        assert!(is_standard_organic("TIP3"));
        assert!(!is_standard_organic("HEM"));
        assert_eq!(ion_element("SOD"), Some("Na"));
        assert_eq!(ion_element("ALA"), None);
        assert!(is_water("PW") && is_water("sol") && !is_water("ALA"));
        assert!(is_lipid("POPG") && is_lipid("CHOL") && !is_lipid("SOL"));
        assert!(is_ion("ION") && is_ion("NA+") && !is_ion("POPE"));
        assert!(is_nucleotide("DA") && !is_nucleotide("ALA"));
    }
}
