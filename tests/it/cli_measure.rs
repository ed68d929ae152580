//! `mdsurf surface`'s measurement tables end to end on real files: per-atom and per-residue
//! areas that add up to the stats row's area, the buried area of HIV protease's two chains with
//! its contact residues, cavities of adenylate kinase tracked over its trajectory, and bad
//! flags in one line.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use crate::cli_common::{Csv, Run, data, mdsurf};

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

/// `mdsurf surface 1hpv.pdb --backend cpu --interface A B` and `extra`, run in `dir`.
fn protease_interface(dir: &Path, [a, b]: [&str; 2], extra: &[&str]) -> Run {
    let pdb = data("1hpv.pdb");
    let mut args = vec!["surface", &pdb, "--backend", "cpu", "--interface", a, b];
    args.extend_from_slice(extra);
    mdsurf(dir, &args)
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
            "--interface-residues",
            "r.csv",
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
    // The residue table: one row per contact residue, named as in contacts_a/b, on its
    // selection's chain, each losing more than the default 1 Å².
    let residues = Csv::read(&dir.path().join("r.csv"));
    let (sides, chains) = (residues.text_col("side"), residues.text_col("chain"));
    let (ids, names) = (residues.text_col("resid"), residues.text_col("resname"));
    for (side, column) in [("A", "contacts_a"), ("B", "contacts_b")] {
        let listed: Vec<String> = (0..residues.rows.len())
            .filter(|&r| sides[r] == side)
            .inspect(|&r| assert_eq!(chains[r], side, "row {r}"))
            .map(|r| format!("{}:{}{}", chains[r], names[r], ids[r]))
            .collect();
        let named: Vec<String> = csv.text_col(column)[0]
            .split_whitespace()
            .map(str::to_string)
            .collect();
        assert_eq!(listed, named, "side {side}");
    }
    let (alone, with, lost) = (
        residues.col("area_alone_A2"),
        residues.col("area_complex_A2"),
        residues.col("buried_A2"),
    );
    for r in 0..lost.len() {
        assert!(lost[r] > 1.0, "row {r}: {}", lost[r]);
        assert!((alone[r] - with[r] - lost[r]).abs() < 2e-3, "row {r}");
    }
    // With every losing residue counted, the rows' losses hold at least both sides' loss,
    // 2 x buried (residues that gain area in the complex are left out), and more rows; a
    // higher threshold keeps only the rows above it.
    let sides = ["protein and chain A", "protein and chain B"];
    let by_threshold = |threshold: &str, out: &str| {
        let run = protease_interface(
            dir.path(),
            sides,
            &[
                "--contact-threshold",
                threshold,
                "--interface-residues",
                out,
                "-q",
            ],
        );
        assert_eq!(run.code, 0, "{}", run.stderr);
        Csv::read(&dir.path().join(out)).col("buried_A2")
    };
    let all = by_threshold("0", "r0.csv");
    let sum: f64 = all.iter().sum();
    assert!(all.len() > lost.len(), "{} vs {}", all.len(), lost.len());
    assert!(sum >= 2.0 * buried - 0.1, "{sum} vs 2 x {buried}");
    assert!(sum < 2.0 * buried * 1.2, "{sum} vs 2 x {buried}");
    let large = by_threshold("20", "r20.csv");
    assert!(!large.is_empty() && large.len() < lost.len());
    assert!(large.iter().all(|l| *l > 20.0));
    let mut expected: Vec<f64> = lost.iter().copied().filter(|l| *l > 20.0).collect();
    let mut got = large.clone();
    expected.sort_by(f64::total_cmp);
    got.sort_by(f64::total_cmp);
    assert_eq!(got, expected);
    let run = protease_interface(dir.path(), sides, &["--contact-threshold", "-2"]);
    assert_eq!(run.code, 2);
    assert!(run.last_line().contains("'-2'"), "{}", run.stderr);
    // Sides that share atoms: one line naming both selections, no file.
    let overlapping = ["protein", "protein and chain B"];
    let run = protease_interface(dir.path(), overlapping, &["--interface-csv", "k.csv"]);
    assert_eq!(run.code, 2);
    assert!(
        run.last_line()
            .contains("selections 'protein' and 'protein and chain B' share 758 atom(s)"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("k.csv").exists());
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
            "--cavity-events",
            "events.csv",
            "-q",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("cav.csv"));
    check_events(&csv, &Csv::read(&dir.path().join("events.csv")));
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

/// The events of `--cavity-events` agree with the ids of `--cavities`: at each frame, the ids
/// that first appear are the births and the parts split off, and the ids of the frame before
/// that are gone are the deaths and the ids that ended in a merge; a merge or split continues
/// in an id of both frames.
fn check_events(cavities: &Csv, events: &Csv) {
    let mut ids_at: BTreeMap<usize, BTreeSet<u64>> = BTreeMap::new();
    for (f, id) in cavities
        .text_col("frame")
        .iter()
        .zip(cavities.text_col("cavity_id"))
    {
        ids_at
            .entry(f.parse().unwrap())
            .or_default()
            .insert(id.parse().unwrap());
    }
    let mut frame_col = cavities.text_col("frame");
    frame_col.extend(events.text_col("frame"));
    let frames = frame_col.iter().map(|f| f.parse().unwrap()).max().unwrap();
    let kinds = events.text_col("event");
    assert!(kinds.iter().any(|k| k != "birth"), "{kinds:?}");
    let ids = |s: &str| -> Vec<u64> { s.split_whitespace().map(|v| v.parse().unwrap()).collect() };
    for f in 0..=frames {
        let now = ids_at.get(&f).cloned().unwrap_or_default();
        let before = match f {
            0 => BTreeSet::new(),
            _ => ids_at.get(&(f - 1)).cloned().unwrap_or_default(),
        };
        let (mut new, mut ended) = (BTreeSet::new(), BTreeSet::new());
        for (k, row) in events.text_col("frame").iter().enumerate() {
            if row.parse::<usize>().unwrap() != f {
                continue;
            }
            let id: u64 = events.text_col("cavity_id")[k].parse().unwrap();
            let others = ids(&events.text_col("ids")[k]);
            match kinds[k].as_str() {
                "birth" => new.insert(id),
                "death" => ended.insert(id),
                "merge" | "split" => {
                    assert!(now.contains(&id) && before.contains(&id), "frame {f}: {id}");
                    let set = if kinds[k] == "merge" {
                        &mut ended
                    } else {
                        &mut new
                    };
                    set.extend(others);
                    true
                }
                other => panic!("event {other}"),
            };
        }
        let appeared: BTreeSet<u64> = now.difference(&before).copied().collect();
        let gone: BTreeSet<u64> = before.difference(&now).copied().collect();
        assert_eq!(new, appeared, "frame {f}: new ids");
        assert_eq!(ended, gone, "frame {f}: ended ids");
    }
}

/// A LAMMPS dump names no residues: `--per-residue` refuses in one line and writes nothing,
/// and the cavities' lining atoms are labelled by atom name and serial (`1@373`), not by a
/// residue number 0 repeated.
#[test]
fn files_without_residues_label_atoms_and_refuse_per_residue_areas() {
    let dir = tempfile::tempdir().unwrap();
    let dump = data("spce_all_coords.lammpstrj.bz2");
    let args = [
        "surface",
        &dump,
        "--frames",
        "0:1",
        "--backend",
        "cpu",
        "-q",
    ];
    let with = |extra: [&'static str; 2]| [&args[..], &extra[..]].concat();
    let run = mdsurf(dir.path(), &with(["--per-residue", "res.csv"]));
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
    assert!(
        run.stderr.contains("--per-residue") && run.stderr.contains("--per-atom"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("res.csv").exists());

    let run = mdsurf(dir.path(), &with(["--cavities", "cav.csv"]));
    assert_eq!(run.code, 0, "{}", run.stderr);
    let lining = Csv::read(&dir.path().join("cav.csv")).text_col("lining");
    assert!(!lining.is_empty(), "the water box has cavities");
    for label in lining.iter().flat_map(|l| l.split_whitespace()) {
        let (name, serial) = label.split_once('@').expect(label);
        assert!(["1", "2"].contains(&name), "{label}: LAMMPS types 1 and 2");
        let serial: usize = serial.parse().expect(label);
        assert!((1..=4500).contains(&serial), "{label}");
    }
}

/// YiiP's GRO file has no chains and numbers both monomers of the dimer alike: the tables tell
/// their residues apart by `residue` (the index `residue N` selects) and the labels by copy
/// (`PHE9#1`, `PHE9#2`), so that no two rows of a frame share a key and no contact list names a
/// residue twice.
#[test]
fn residues_that_share_chain_number_and_name_are_told_apart() {
    let dir = tempfile::tempdir().unwrap();
    let gro = data("YiiP_lipids.gro.gz");
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            "--select",
            "protein or resname POPE POPG",
            "--backend",
            "cpu",
            "--per-residue",
            "res.csv",
            "--interface",
            "protein",
            "resname POPE POPG",
            "--interface-csv",
            "if.csv",
            "--interface-residues",
            "contacts.csv",
            "-q",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let residues = Csv::read(&dir.path().join("res.csv"));
    let (chain, resid, name) = (
        residues.text_col("chain"),
        residues.text_col("resid"),
        residues.text_col("resname"),
    );
    let index = residues.text_col("residue");
    let mut by_key: HashMap<(String, String, String), Vec<String>> = HashMap::new();
    for k in 0..index.len() {
        let key = (chain[k].clone(), resid[k].clone(), name[k].clone());
        by_key.entry(key).or_default().push(index[k].clone());
    }
    let shared = by_key.values().filter(|v| v.len() == 2).count();
    assert!(
        shared > 200,
        "only {shared} residues shared by both monomers"
    );
    let distinct: BTreeSet<&String> = index.iter().collect();
    assert_eq!(distinct.len(), index.len(), "a residue index appears twice");
    // A residue index selects its residue: the second TYR7's index holds a TYR numbered 7.
    let second = &by_key[&(String::new(), "7".into(), "TYR".into())][1];
    let one = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            "--select",
            &format!("residue {second}"),
            "--backend",
            "cpu",
            "--per-residue",
            "one.csv",
            "--per-atom",
            "one_atoms.csv",
            "-q",
        ],
    );
    assert_eq!(one.code, 0, "{}", one.stderr);
    let one = Csv::read(&dir.path().join("one.csv"));
    assert_eq!(one.text_col("resname"), ["TYR"]);
    assert_eq!(one.text_col("resid"), ["7"]);
    assert_eq!(&one.text_col("residue")[0], second);
    let atoms = Csv::read(&dir.path().join("one_atoms.csv"));
    assert!(atoms.rows.len() > 10, "a tyrosine's atoms");
    assert!(atoms.text_col("residue").iter().all(|r| r == second));

    // Contact lists: each residue once, the monomers' copies by number.
    let interface = Csv::read(&dir.path().join("if.csv"));
    let listed = interface.text_col("contacts_a");
    let labels: Vec<&str> = listed[0].split(' ').collect();
    let once: BTreeSet<&&str> = labels.iter().collect();
    assert_eq!(once.len(), labels.len(), "a label twice in {labels:?}");
    assert!(labels.iter().any(|l| l.ends_with("#1")), "{labels:?}");
    assert!(labels.iter().any(|l| l.ends_with("#2")), "{labels:?}");
    let contacts = Csv::read(&dir.path().join("contacts.csv"));
    let keys: Vec<(String, String)> = contacts
        .text_col("side")
        .into_iter()
        .zip(contacts.text_col("residue"))
        .collect();
    let distinct: BTreeSet<&(String, String)> = keys.iter().collect();
    assert_eq!(distinct.len(), keys.len(), "a contact residue twice");
    assert_eq!(
        contacts
            .text_col("side")
            .iter()
            .filter(|s| *s == "A")
            .count(),
        labels.len(),
        "the contact table and list name the same residues of A"
    );
}
