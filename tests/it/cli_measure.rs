//! `mdsurf surface`'s measurement tables end to end on real files: per-atom and per-residue
//! areas that add up to the stats row's area, the buried area of HIV protease's two chains with
//! its contact residues, cavities of adenylate kinase tracked over its trajectory, and bad
//! flags in one line.

use std::collections::HashMap;

use crate::cli_common::{Csv, data, mdsurf};

#[test]
fn per_atom_and_per_residue_areas_add_up_to_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &pdb,
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--stats",
            "s.csv",
            "--per-atom",
            "atoms.csv",
            "--per-residue",
            "res.csv",
            "-q",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let total = Csv::read(&dir.path().join("s.csv")).col("area_A2")[0];
    let atoms = Csv::read(&dir.path().join("atoms.csv"));
    let residues = Csv::read(&dir.path().join("res.csv"));
    let atoms_in_stats = Csv::read(&dir.path().join("s.csv")).col("atoms")[0] as usize;
    assert_eq!(atoms.rows.len(), atoms_in_stats, "one row per atom");
    let sum_atoms: f64 = atoms.col("area_A2").iter().sum();
    let sum_residues: f64 = residues.col("area_A2").iter().sum();
    // Rows carry 3 decimals: the sums agree to their rounding.
    assert!((sum_atoms - total).abs() < 1.0, "{sum_atoms} vs {total}");
    assert!(
        (sum_residues - total).abs() < 0.2,
        "{sum_residues} vs {total}"
    );
    assert!(residues.col("area_A2").iter().all(|a| *a >= 0.0));
    // Exposure: buried residues near 0, exposed ones well above; none far past 1.
    let exposure = residues.col("exposure");
    assert!(
        exposure.iter().all(|e| (0.0..1.5).contains(e)),
        "{exposure:?}"
    );
    assert!(exposure.iter().any(|e| *e < 0.05) && exposure.iter().any(|e| *e > 0.5));
    // Two chains of 99 residues.
    let chains: Vec<String> = residues.text_col("chain");
    assert_eq!(chains.iter().filter(|c| *c == "A").count(), 99);
    assert_eq!(chains.iter().filter(|c| *c == "B").count(), 99);
}

#[test]
fn the_protease_dimer_buries_area_and_names_its_contacts() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = data("1hpv.pdb");
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &pdb,
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--interface",
            "protein and chain A",
            "protein and chain B",
            "--interface-csv",
            "i.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("i.csv"));
    let (a, b, ab, buried) = (
        csv.col("area_a_A2")[0],
        csv.col("area_b_A2")[0],
        csv.col("area_ab_A2")[0],
        csv.col("buried_A2")[0],
    );
    assert!(
        ((a + b - ab) / 2.0 - buried).abs() < 1e-3,
        "{a} {b} {ab} {buried}"
    );
    // A dimer interface of this protease buries well over 1000 Å² on each side's average.
    assert!(buried > 800.0 && buried < 3000.0, "{buried}");
    // The complex's own area is the surface's area of the whole protein.
    let total = Csv::read(&dir.path().join("i.csv")).col("area_ab_A2")[0];
    assert!(total > a && total > b);
    for side in ["contacts_a", "contacts_b"] {
        let contacts = &csv.text_col(side)[0];
        let n = contacts.split_whitespace().count();
        assert!(n > 10, "{side}: {contacts}");
    }
    // A side that picks nothing: one line naming it, no file.
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &pdb,
            "--backend",
            "cpu",
            "--interface",
            "chain A",
            "resname XYZ",
            "--interface-csv",
            "j.csv",
        ],
    );
    assert_eq!(run.code, 2);
    assert!(run.last_line().contains("resname XYZ"), "{}", run.stderr);
    assert!(!dir.path().join("j.csv").exists());
}

#[test]
fn adenylate_kinase_cavities_keep_their_ids_over_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (gro, xtc) = (data("adk_oplsaa.gro"), data("adk_oplsaa.xtc"));
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            &xtc,
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--cavities",
            "cav.csv",
            "-q",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("cav.csv"));
    assert!(!csv.rows.is_empty());
    let frames: Vec<String> = csv.text_col("frame");
    let ids: Vec<String> = csv.text_col("cavity_id");
    let mut frames_of: HashMap<&str, Vec<&str>> = HashMap::new();
    for (f, id) in frames.iter().zip(&ids) {
        frames_of.entry(id).or_default().push(f);
    }
    // One cavity persists over several frames under one id.
    assert!(frames_of.values().any(|f| f.len() >= 3), "{frames_of:?}");
    assert!(
        csv.col("volume_A3").iter().all(|v| *v >= 1.0),
        "--min-cavity-volume 1 Å³"
    );
    assert!(csv.text_col("lining").iter().all(|l| !l.is_empty()));
}
