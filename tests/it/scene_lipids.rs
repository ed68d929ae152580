//! Lipids recognised by what they are (issue 30 section 3): membranes whose lipids carry names
//! outside the built-in list (DMPC as `DMP`, POPC as `POP`, Martini lipids renamed) are still
//! `lipid`, never `ligand`, and open with a membrane representation; a single copy of a large
//! molecule stays a ligand, and systems without lipids get none.

use mdsurf::io::Trajectory;
use mdsurf::model::{Frame, Topology};
use mdsurf::scene::defaults::default_representations;
use mdsurf::scene::representation::Representation;
use mdsurf::selection::Selection;

use crate::data_support::data;

fn open(name: &str) -> (Topology, Frame) {
    let t: Trajectory = mdsurf::io::open(&data(name), None).unwrap_or_else(|e| panic!("{e}"));
    let frame = t.read_frame(0).expect("frame 0");
    (t.topology().clone(), frame)
}

fn count(top: &Topology, frame: &Frame, text: &str) -> usize {
    let s = Selection::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    s.bind(top).indices(frame).len()
}

/// `top` with every residue named `from` renamed `to`.
fn renamed(top: &Topology, renames: &[(&str, &str)]) -> Topology {
    let mut out = top.clone();
    for i in 0..out.len() {
        let name = top.residue_names.get(i).unwrap_or("").trim().to_string();
        if let Some((_, to)) = renames.iter().find(|(from, _)| *from == name) {
            out.residue_names.set(i, to);
        }
    }
    out
}

#[test]
fn all_atom_lipids_under_other_names() {
    let (top, frame) = open("YiiP_lipids.gro.gz");
    let lipids = count(&top, &frame, "lipid");
    let ligands = count(&top, &frame, "ligand");
    assert_eq!(lipids, 34_610, "POPE and POPG by name");
    let top2 = renamed(&top, &[("POPE", "POP"), ("POPG", "DMP")]);
    assert_eq!(count(&top2, &frame, "resname POP DMP"), lipids);
    assert_eq!(count(&top2, &frame, "lipid"), lipids);
    assert_eq!(count(&top2, &frame, "ligand"), ligands);
    let reps = default_representations(&top2, &frame, &Representation::default());
    let names: Vec<&str> = reps.iter().map(|r| r.name.as_str()).collect();
    assert!(names.contains(&"lipids"), "{names:?}");
    assert!(!names.contains(&"all"), "{names:?}");
}

#[test]
fn coarse_grained_lipids_under_other_names() {
    let (top, frame) = open("martini_dppc_chol_bilayer.gro");
    let lipids = count(&top, &frame, "lipid");
    assert_eq!(lipids, 5_040, "DPPC and CHOL by name");
    let top2 = renamed(&top, &[("DPPC", "DPP"), ("CHOL", "STR")]);
    assert_eq!(count(&top2, &frame, "lipid"), lipids);
    assert_eq!(count(&top2, &frame, "ligand"), 0);
    let reps = default_representations(&top2, &frame, &Representation::default());
    assert!(reps.iter().any(|r| r.name == "lipids"), "{reps:?}");
}

#[test]
fn few_copies_or_small_molecules_are_no_lipids() {
    // 1hpv's inhibitor is one copy: a ligand.
    let (top, frame) = open("1hpv.pdb");
    assert!(count(&top, &frame, "ligand") > 0);
    assert_eq!(count(&top, &frame, "lipid"), 0);
    // A protein in water with ions: no lipid.
    let (top, frame) = open("adk_oplsaa.gro");
    assert_eq!(count(&top, &frame, "lipid"), 0);
    // Only 9 copies of a renamed POPE: below the copies needed, so a ligand.
    let (top, frame) = open("YiiP_lipids.gro.gz");
    let mut top9 = top.clone();
    let mut seen = std::collections::HashSet::new();
    for i in 0..top.len() {
        if top.residue_names.get(i) == Some("POPE") {
            let residue = top.residue_index[i];
            if seen.len() < 9 || seen.contains(&residue) {
                seen.insert(residue);
                top9.residue_names.set(i, "XPE");
            }
        }
    }
    assert_eq!(seen.len(), 9);
    assert!(count(&top9, &frame, "resname XPE") > 0);
    assert_eq!(count(&top9, &frame, "resname XPE and lipid"), 0);
    assert_eq!(
        count(&top9, &frame, "resname XPE and ligand"),
        count(&top9, &frame, "resname XPE")
    );
}
