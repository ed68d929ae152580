//! The mass (amu) an atom gets from its type when the file states none: the standard atomic
//! weight of the element the type names (Blue Obelisk data, as chemfiles ships it), found the
//! way chemfiles finds it, so our readers and the chemfiles path agree on every file: a type of
//! one or two bytes is matched as an element symbol in any case (`CA`, `ca`: calcium), a longer
//! type only as written (the placeholder names `Uut`, `Uup`, `Uus`, `Uuo` of elements 113, 115,
//! 117 and 118); anything else has mass 0. Charges from a type are always 0.

/// Element symbols (elements 113, 115, 117, 118 under their placeholder names) and standard
/// atomic weights (amu), in atomic-number order.
const MASSES: [(&str, f64); 118] = [
    ("H", 1.008),
    ("He", 4.002602),
    ("Li", 6.94),
    ("Be", 9.012182),
    ("B", 10.81),
    ("C", 12.011),
    ("N", 14.007),
    ("O", 15.999),
    ("F", 18.9984032),
    ("Ne", 20.1797),
    ("Na", 22.98976928),
    ("Mg", 24.305),
    ("Al", 26.9815386),
    ("Si", 28.085),
    ("P", 30.973762),
    ("S", 32.06),
    ("Cl", 35.45),
    ("Ar", 39.948),
    ("K", 39.0983),
    ("Ca", 40.078),
    ("Sc", 44.955912),
    ("Ti", 47.867),
    ("V", 50.9415),
    ("Cr", 51.9961),
    ("Mn", 54.938045),
    ("Fe", 55.845),
    ("Co", 58.933195),
    ("Ni", 58.6934),
    ("Cu", 63.546),
    ("Zn", 65.38),
    ("Ga", 69.723),
    ("Ge", 72.63),
    ("As", 74.9216),
    ("Se", 78.96),
    ("Br", 79.904),
    ("Kr", 83.798),
    ("Rb", 85.4678),
    ("Sr", 87.62),
    ("Y", 88.90585),
    ("Zr", 91.224),
    ("Nb", 92.90638),
    ("Mo", 95.96),
    ("Tc", 97.0),
    ("Ru", 101.07),
    ("Rh", 102.9055),
    ("Pd", 106.42),
    ("Ag", 107.8682),
    ("Cd", 112.411),
    ("In", 114.818),
    ("Sn", 118.71),
    ("Sb", 121.76),
    ("Te", 127.6),
    ("I", 126.90447),
    ("Xe", 131.293),
    ("Cs", 132.9054519),
    ("Ba", 137.327),
    ("La", 138.90547),
    ("Ce", 140.116),
    ("Pr", 140.90765),
    ("Nd", 144.242),
    ("Pm", 145.0),
    ("Sm", 150.36),
    ("Eu", 151.964),
    ("Gd", 157.25),
    ("Tb", 158.92535),
    ("Dy", 162.5),
    ("Ho", 164.93032),
    ("Er", 167.259),
    ("Tm", 168.93421),
    ("Yb", 173.054),
    ("Lu", 174.9668),
    ("Hf", 178.49),
    ("Ta", 180.94788),
    ("W", 183.84),
    ("Re", 186.207),
    ("Os", 190.23),
    ("Ir", 192.217),
    ("Pt", 195.084),
    ("Au", 196.966569),
    ("Hg", 200.592),
    ("Tl", 204.38),
    ("Pb", 207.2),
    ("Bi", 208.9804),
    ("Po", 209.0),
    ("At", 210.0),
    ("Rn", 222.0),
    ("Fr", 223.0),
    ("Ra", 226.0),
    ("Ac", 227.0),
    ("Th", 232.03806),
    ("Pa", 231.03588),
    ("U", 238.02891),
    ("Np", 237.0),
    ("Pu", 244.0),
    ("Am", 243.0),
    ("Cm", 247.0),
    ("Bk", 247.0),
    ("Cf", 251.0),
    ("Es", 252.0),
    ("Fm", 257.0),
    ("Md", 258.0),
    ("No", 259.0),
    ("Lr", 262.0),
    ("Rf", 267.0),
    ("Db", 270.0),
    ("Sg", 271.0),
    ("Bh", 270.0),
    ("Hs", 277.0),
    ("Mt", 276.0),
    ("Ds", 281.0),
    ("Rg", 282.0),
    ("Cn", 285.0),
    ("Uut", 285.0),
    ("Fl", 289.0),
    ("Uup", 289.0),
    ("Lv", 293.0),
    ("Uus", 294.0),
    ("Uuo", 294.0),
];

/// The mass (amu) of an atom of type `kind`, 0 when the type names no element (see the module
/// documentation).
pub(crate) fn type_mass(kind: &str) -> f64 {
    let found = if kind.len() <= 2 {
        MASSES
            .iter()
            .find(|(symbol, _)| symbol.len() == kind.len() && symbol.eq_ignore_ascii_case(kind))
    } else {
        MASSES.iter().find(|(symbol, _)| *symbol == kind)
    };
    found.map_or(0.0, |(_, mass)| *mass)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_match_in_any_case_and_long_types_only_exactly() {
        assert_eq!(type_mass("C"), 12.011);
        assert_eq!(type_mass("ca"), type_mass("Ca"));
        assert!(type_mass("CA") > 40.0);
        assert_eq!(type_mass("Uuo"), 294.0);
        assert_eq!(type_mass("UUO"), 0.0);
        assert_eq!(type_mass("CA1"), 0.0);
        assert_eq!(type_mass(""), 0.0);
        assert_eq!(type_mass("Xx"), 0.0);
    }

    /// Every element symbol, in several cases, and types that name none, against chemfiles.
    #[cfg(feature = "chemfiles")]
    #[test]
    fn masses_are_chemfiles_masses() {
        let mut kinds: Vec<String> = Vec::new();
        for (symbol, _) in MASSES {
            kinds.push(symbol.to_string());
            kinds.push(symbol.to_uppercase());
            kinds.push(symbol.to_lowercase());
        }
        kinds.extend(["Nh", "Og", "Xx", "CA1", "OW", "HW1", "1", "", "é"].map(String::from));
        for kind in kinds {
            let theirs = chemfiles::Atom::new(kind.as_str());
            assert_eq!(type_mass(&kind), theirs.mass(), "mass of type {kind:?}");
            assert_eq!(theirs.charge(), 0.0, "charge of type {kind:?}");
        }
    }
}
