//! Every real file in `tests/data` opens with the atom and frame counts its README lists,
//! and its topology comes out complete (elements, radii, residues).

use crate::data_support::data;

use mdsurf::io::{self, Trajectory};

fn open(top: &str, traj: Option<&str>) -> Trajectory {
    let top = data(top);
    let traj = traj.map(data);
    match io::open(&top, traj.as_deref()) {
        Ok(t) => t,
        Err(e) => panic!("cannot open {top:?} {traj:?}: {e}"),
    }
}

/// Opens, checks counts, and reads the first, a middle and the last frame.
fn check(top: &str, traj: Option<&str>, atoms: usize, frames: usize) -> Trajectory {
    let t = open(top, traj);
    assert_eq!(t.topology().len(), atoms, "{top}: atoms");
    assert_eq!(t.len(), frames, "{top} {traj:?}: frames");
    assert!(t.damage().is_none(), "{top}: {:?}", t.damage());
    for i in [0, frames / 2, frames - 1] {
        let f = t.read_frame(i).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(f.index, i);
        assert_eq!(f.positions.len(), atoms);
        assert!(f.positions.iter().all(|p| p.is_finite()));
    }
    let top = t.topology();
    assert_eq!(top.radii.len(), atoms);
    assert!(
        top.radii.iter().all(|&r| r > 0.0 && r < 5.0),
        "radii out of range"
    );
    assert!(
        t.read_frame(frames).is_err(),
        "frame past the end must fail"
    );
    t
}

#[test]
fn rhodopsin_gro_xtc() {
    let t = check("md_1u19.gro", Some("md_1u19.xtc"), 5547, 51);
    let f = t.read_frame(1).expect("frame 1");
    assert!(f.time_ps.is_some(), "XTC frames carry a time");
    assert!(f.cell.is_some(), "XTC frames carry a box");
    let top = t.topology();
    assert!(
        top.elements.iter().all(|e| !e.is_empty()),
        "every protein atom gets an element"
    );
    assert!(top.elements.iter().any(|e| e == "H"));
}

#[test]
fn adk_pdb_dcd() {
    let t = check("adk_open.pdb", Some("adk_dims.dcd"), 3341, 98);
    let top = t.topology();
    assert_eq!(top.residue_count(), 214, "adk has 214 residues");
    // MD-style PDB without element column: CD (in ILE/LYS/...) must be carbon.
    let cd: Vec<usize> = (0..top.len()).filter(|&i| &top.names[i] == "CD").collect();
    assert!(!cd.is_empty());
    for i in cd {
        assert_eq!(
            &top.elements[i], "C",
            "CD in {} must be carbon",
            &top.residue_names[i]
        );
        assert_eq!(top.radii[i], 1.5);
    }
}

#[test]
fn adk_pdb_alone() {
    check("adk_open.pdb", None, 3341, 1);
}

#[test]
fn adk_water_box_gro_xtc() {
    let t = check("adk_oplsaa.gro", Some("adk_oplsaa.xtc"), 47681, 10);
    let top = t.topology();
    let ow = top
        .names
        .iter()
        .position(|n| n == "OW")
        .expect("water oxygen");
    assert_eq!(&top.elements[ow], "O");
    assert_eq!(top.radii[ow], 1.3);
}

#[test]
fn yiip_gzipped_gro_xtc() {
    check("YiiP_lipids.gro.gz", Some("YiiP_lipids.xtc"), 43480, 5);
    check("YiiP_lipids.gro.gz", None, 43480, 1);
}

#[test]
fn hiv_protease_wwpdb() {
    let t = check("1hpv.pdb", None, 1631, 1);
    let top = t.topology();
    let chains: std::collections::BTreeSet<&str> = top.chains.iter().collect();
    assert!(
        chains.contains("A") && chains.contains("B"),
        "chains {chains:?}"
    );
    let b_lo = top.b_factors.iter().copied().fold(f32::INFINITY, f32::min);
    let b_hi = top
        .b_factors
        .iter()
        .copied()
        .fold(f32::NEG_INFINITY, f32::max);
    assert!(
        b_hi > b_lo && b_lo >= 0.0,
        "B-factors read from the file: {b_lo}..{b_hi}"
    );
    assert!(top.elements.iter().all(|e| !e.is_empty()));
}

#[test]
fn martini_beads_get_bead_radius() {
    let t = check("martini_dppc_chol_bilayer.gro", None, 5040, 1);
    let top = t.topology();
    assert!(
        top.radii.iter().all(|&r| (r - 2.35).abs() < 1e-6),
        "Martini beads are 2.35 Å"
    );
    assert!(
        top.elements.iter().all(str::is_empty),
        "beads have no element"
    );
}

#[test]
fn lammps_bz2() {
    let t = check("spce_all_coords.lammpstrj.bz2", None, 4500, 11);
    let top = t.topology();
    let types: std::collections::BTreeSet<&str> = top.names.iter().collect();
    assert!(types.len() >= 2, "SPC/E has two particle types: {types:?}");
}

#[test]
fn argon_tng() {
    check("argon_npt_compressed.tng", None, 1000, 101);
}

/// The `_atom_site` rows of a gzip-compressed mmCIF file in `tests/data`, each a map from
/// column name to value (rows with quoted spaces are skipped: none in these files).
fn atom_site_rows(file: &str) -> Vec<std::collections::HashMap<String, String>> {
    let text = crate::data_support::gunzipped(file);
    let columns: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("_atom_site."))
        .map(str::trim)
        .collect();
    text.lines()
        .filter(|l| l.starts_with("ATOM") || l.starts_with("HETATM"))
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .filter(|t| t.len() == columns.len())
        .map(|t| {
            let pairs = columns.iter().zip(t);
            pairs.map(|(c, v)| (c.to_string(), v.to_string())).collect()
        })
        .collect()
}

/// An mmCIF file's waters are one residue each, numbered as the author numbered them
/// (chemfiles made every water of a chain one residue, numbered by its entity), its polymer
/// residues stay as its sequence numbers them, and the compressed and plain files agree.
#[test]
fn mmcif_waters_are_a_residue_each_with_the_author_number() {
    let rows = atom_site_rows("1gbt.cif.gz");
    let water_numbers: std::collections::BTreeSet<i64> = (rows.iter())
        .filter(|r| r["label_comp_id"] == "HOH")
        .map(|r| r["auth_seq_id"].parse().unwrap())
        .collect();
    let polymer_residues: std::collections::BTreeSet<(String, String)> = (rows.iter())
        .filter(|r| r["group_PDB"] == "ATOM")
        .map(|r| (r["label_asym_id"].clone(), r["label_seq_id"].clone()))
        .collect();
    assert!(water_numbers.len() > 100);

    let gz = check("1gbt.cif.gz", None, rows.len(), 1);
    let plain = tempfile::tempdir().unwrap();
    let copy = plain.path().join("1gbt.cif");
    std::fs::write(&copy, crate::data_support::gunzipped("1gbt.cif.gz")).unwrap();
    let plain = io::open(&copy, None).expect("plain 1gbt.cif");
    for t in [&gz, &plain] {
        let top = t.topology();
        let waters: Vec<usize> = (0..top.len())
            .filter(|&i| &top.residue_names[i] == "HOH")
            .collect();
        assert_eq!(waters.len(), water_numbers.len(), "one oxygen per water");
        let residues: std::collections::BTreeSet<u32> =
            waters.iter().map(|&i| top.residue_index[i]).collect();
        assert_eq!(residues.len(), waters.len(), "every water its own residue");
        let ids: std::collections::BTreeSet<i64> =
            waters.iter().map(|&i| top.residue_ids[i]).collect();
        assert_eq!(ids, water_numbers);
        // Atoms come in the file's order.
        let polymer: std::collections::BTreeSet<u32> = (0..top.len())
            .filter(|&i| rows[i]["group_PDB"] == "ATOM")
            .map(|i| top.residue_index[i])
            .collect();
        assert_eq!(polymer.len(), polymer_residues.len());
    }
    assert_eq!(gz.topology().residue_ids, plain.topology().residue_ids);
}

/// An mmCIF file written by another tool with `?` for every entity (Biopython's 7CFN) opens,
/// and its ligand carries the author's residue number (chemfiles refused the whole file).
#[test]
fn mmcif_with_unknown_entities_opens() {
    let rows = atom_site_rows("7cfn.cif.gz");
    assert!(rows.iter().all(|r| r["label_entity_id"] == "?"));
    let ligand: std::collections::BTreeSet<i64> = (rows.iter())
        .filter(|r| r["group_PDB"] == "HETATM")
        .map(|r| r["auth_seq_id"].parse().unwrap())
        .collect();
    assert!(!ligand.is_empty());
    let t = check("7cfn.cif.gz", None, rows.len(), 1);
    let top = t.topology();
    let het: std::collections::BTreeSet<i64> = (0..top.len())
        .filter(|&i| rows[i]["group_PDB"] == "HETATM")
        .map(|i| top.residue_ids[i])
        .collect();
    assert_eq!(het, ligand);
}

/// An mmCIF file cut in the middle of an `_atom_site` row, compressed or not, is refused with
/// the line (chemfiles read past the end of the row: a segmentation fault on the `.cif.gz`).
#[test]
fn mmcif_cut_in_a_row_is_refused_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let gz = dir.path().join("cut.cif.gz");
    let bytes = std::fs::read(data("1gbt.cif.gz")).unwrap();
    std::fs::write(&gz, &bytes[..30_000]).unwrap();
    let plain = dir.path().join("cut.cif");
    let text = crate::data_support::gunzipped("1gbt.cif.gz");
    // 40 characters into the 500th atom row.
    let row = text
        .match_indices("\nATOM")
        .nth(500)
        .expect("500 atom rows")
        .0;
    let cut = &text[..row + 40];
    std::fs::write(&plain, cut).unwrap();
    for path in [&gz, &plain] {
        let e = io::open(path, None).expect_err("a cut row").to_string();
        assert!(
            e.contains("cut.cif") && e.contains("line ") && e.contains("_atom_site row"),
            "{e}"
        );
    }
}
