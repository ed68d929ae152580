//! Elements and radii: validating element symbols from files, guessing elements from atom names
//! with residue context (DESIGN section 2), recognising coarse-grained beads, and the radius table.

use super::residues::{ion_element, is_amino_acid, is_standard_organic};

/// Every element symbol, in atomic-number order.
const SYMBOLS: [&str; 118] = [
    "H", "He", "Li", "Be", "B", "C", "N", "O", "F", "Ne", "Na", "Mg", "Al", "Si", "P", "S", "Cl",
    "Ar", "K", "Ca", "Sc", "Ti", "V", "Cr", "Mn", "Fe", "Co", "Ni", "Cu", "Zn", "Ga", "Ge", "As",
    "Se", "Br", "Kr", "Rb", "Sr", "Y", "Zr", "Nb", "Mo", "Tc", "Ru", "Rh", "Pd", "Ag", "Cd", "In",
    "Sn", "Sb", "Te", "I", "Xe", "Cs", "Ba", "La", "Ce", "Pr", "Nd", "Pm", "Sm", "Eu", "Gd", "Tb",
    "Dy", "Ho", "Er", "Tm", "Yb", "Lu", "Hf", "Ta", "W", "Re", "Os", "Ir", "Pt", "Au", "Hg", "Tl",
    "Pb", "Bi", "Po", "At", "Rn", "Fr", "Ra", "Ac", "Th", "Pa", "U", "Np", "Pu", "Am", "Cm", "Bk",
    "Cf", "Es", "Fm", "Md", "No", "Lr", "Rf", "Db", "Sg", "Bh", "Hs", "Mt", "Ds", "Rg", "Cn", "Nh",
    "Fl", "Mc", "Lv", "Ts", "Og",
];

/// Two-letter elements that win over a C/N/O/H/S/P first letter in non-standard residues
/// (ligands, cofactors): `FE` in HEM is iron, `CL1` in a drug is chlorine. `NA`..`ND` in HEM stay
/// nitrogens because NA/CA/CD are left out on purpose.
const LIGAND_TWO_LETTER: [&str; 8] = ["Cl", "Br", "Fe", "Zn", "Mg", "Mn", "Cu", "Se"];

/// Martini (and similar) coarse-grained bead names that are not plausible atom names.
const CG_BEADS: [&str; 24] = [
    "BB", "SC1", "SC2", "SC3", "SC4", "SC5", "PO4", "NC3", "NH3", "CNO", "GL1", "GL2", "ROH", "R1",
    "R2", "R3", "R4", "R5", "R6", "C1", "W", "WF", "PW", "ION",
];

/// Radius of a coarse-grained bead in Å (a Martini bead's van der Waals size).
pub const BEAD_RADIUS: f32 = 2.35;

/// Radius in Å for anything not in [`element_radius`]'s table.
pub const DEFAULT_RADIUS: f32 = 1.5;

/// Canonical symbol (`Fe`) of `symbol` in any case (`FE`, `fe`), or `None` if it is no element.
pub fn canonical_symbol(symbol: &str) -> Option<&'static str> {
    let s = symbol.trim();
    SYMBOLS.iter().copied().find(|e| e.eq_ignore_ascii_case(s))
}

/// Guesses the element of atom `name` in residue `residue` (DESIGN section 2).
///
/// Leading digits are ignored (`1HB`). Ion residues give their ion (`CA` in `CAL` is calcium);
/// in amino acids, nucleotides, water and lipids the first letter decides (`CD` is carbon, `OW`
/// oxygen, `HW1` hydrogen); in other residues a two-letter metal or halogen wins (`FE` in `HEM`).
/// Names without letters (numeric LAMMPS types) have no element.
pub fn guess_element(name: &str, residue: &str) -> Option<&'static str> {
    let letters: String = name
        .trim()
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .chars()
        .take_while(|c| c.is_ascii_alphabetic())
        .collect();
    if letters.is_empty() {
        return None;
    }
    if let Some(ion) = ion_element(residue)
        && ion_element(&letters).is_some_and(|e| e == ion)
    {
        return Some(ion);
    }
    let first = canonical_symbol(&letters[..1]);
    if !is_standard_organic(residue) && letters.len() >= 2 {
        let two = canonical_symbol(&letters[..2]);
        if let Some(two) = two.filter(|t| LIGAND_TWO_LETTER.contains(t)) {
            return Some(two);
        }
        if letters.len() == 2 && first.is_none() {
            return two;
        }
    }
    if first.is_none() && !is_amino_acid(residue) {
        return canonical_symbol(&letters);
    }
    first
}

/// True when `name` is a coarse-grained bead name (Martini `PO4`, `GL1`, `C1A`, `BB`, `SC1`).
pub fn is_bead_name(name: &str) -> bool {
    let upper = name.trim().to_ascii_uppercase();
    if CG_BEADS.contains(&upper.as_str()) {
        return true;
    }
    // Martini lipid tails: C1A..C6B, D1A..D6B.
    let b = upper.as_bytes();
    b.len() == 3
        && (b[0] == b'C' || b[0] == b'D')
        && (b'1'..=b'6').contains(&b[1])
        && (b[2] == b'A' || b[2] == b'B')
}

/// True when most particles carry bead names and none looks like a hydrogen: a coarse-grained
/// system (all its particles then get [`BEAD_RADIUS`] and no element).
pub fn looks_coarse_grained<'a>(names: impl Iterator<Item = &'a str>) -> bool {
    let (mut total, mut beads) = (0usize, 0usize);
    for name in names {
        let n = name.trim_start_matches(|c: char| c.is_ascii_digit());
        if n.starts_with('H') || n.starts_with('h') {
            return false;
        }
        total += 1;
        beads += usize::from(is_bead_name(name));
    }
    total > 0 && beads * 2 >= total
}

/// Radius in Å of `element` per DESIGN section 2: H 1.0, C 1.5, N 1.4, O 1.3, F 1.2, S 1.9,
/// P 1.8, anything else (including no element) 1.5.
pub fn element_radius(element: &str) -> f32 {
    match element {
        "H" => 1.0,
        "C" => 1.5,
        "N" => 1.4,
        "O" => 1.3,
        "F" => 1.2,
        "S" => 1.9,
        "P" => 1.8,
        _ => DEFAULT_RADIUS,
    }
}

/// Standard atomic mass in amu (IUPAC conventional values) of the elements common in
/// biomolecular simulations; 0 for anything else (including no element).
pub fn element_mass(element: &str) -> f32 {
    match element {
        "H" => 1.008,
        "He" => 4.0026,
        "Li" => 6.94,
        "B" => 10.81,
        "C" => 12.011,
        "N" => 14.007,
        "O" => 15.999,
        "F" => 18.998,
        "Ne" => 20.180,
        "Na" => 22.990,
        "Mg" => 24.305,
        "Al" => 26.982,
        "Si" => 28.085,
        "P" => 30.974,
        "S" => 32.06,
        "Cl" => 35.45,
        "Ar" => 39.948,
        "K" => 39.098,
        "Ca" => 40.078,
        "Mn" => 54.938,
        "Fe" => 55.845,
        "Co" => 58.933,
        "Ni" => 58.693,
        "Cu" => 63.546,
        "Zn" => 65.38,
        "Se" => 78.971,
        "Br" => 79.904,
        "Kr" => 83.798,
        "Rb" => 85.468,
        "Sr" => 87.62,
        "Cd" => 112.41,
        "I" => 126.90,
        "Xe" => 131.29,
        "Cs" => 132.91,
        "Ba" => 137.33,
        "Pt" => 195.08,
        "Au" => 196.97,
        "Hg" => 200.59,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protein_names_are_organic() {
        assert_eq!(guess_element("CD", "LYS"), Some("C"));
        assert_eq!(guess_element("CA", "ALA"), Some("C"));
        assert_eq!(guess_element("HG21", "THR"), Some("H"));
        assert_eq!(guess_element("1HB", "SER"), Some("H"));
        assert_eq!(guess_element("SD", "MET"), Some("S"));
        assert_eq!(guess_element("NE2", "HIS"), Some("N"));
    }

    #[test]
    fn ions_water_ligands_and_types() {
        assert_eq!(guess_element("CA", "CAL"), Some("Ca"));
        assert_eq!(guess_element("CA", "CA"), Some("Ca"));
        assert_eq!(guess_element("NA", "NA"), Some("Na"));
        assert_eq!(guess_element("SOD", "SOD"), Some("Na"));
        assert_eq!(guess_element("CLA", "CLA"), Some("Cl"));
        assert_eq!(guess_element("OW", "SOL"), Some("O"));
        assert_eq!(guess_element("HW1", "SOL"), Some("H"));
        assert_eq!(guess_element("FE", "HEM"), Some("Fe"));
        assert_eq!(guess_element("NA", "HEM"), Some("N"));
        assert_eq!(guess_element("CL1", "LIG"), Some("Cl"));
        assert_eq!(guess_element("2", ""), None);
        assert_eq!(guess_element("Ar", ""), Some("Ar"));
    }

    #[test]
    fn beads_and_radii() {
        assert!(is_bead_name("PO4") && is_bead_name("C1A") && is_bead_name("ROH"));
        assert!(!is_bead_name("CA"));
        assert!(looks_coarse_grained(
            ["NC3", "PO4", "GL1", "C1A"].into_iter()
        ));
        assert!(!looks_coarse_grained(["N", "H1", "CA"].into_iter()));
        assert_eq!(element_radius("O"), 1.3);
        assert_eq!(element_radius("Fe"), DEFAULT_RADIUS);
        assert_eq!(canonical_symbol("FE"), Some("Fe"));
        assert_eq!(element_mass("C"), 12.011);
        assert_eq!(element_mass(""), 0.0);
    }
}
