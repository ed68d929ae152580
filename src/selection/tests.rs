//! Unit tests of the selection language on a small hand-made topology.

use glam::Vec3;

use super::*;

/// Two chains: an ALA-GLY peptide (chain A), a water, a sodium ion, a POPC fragment and a
/// ligand (chain B), along x 1.0 Å apart.
fn system() -> (Topology, Frame) {
    let atoms: [(&str, &str, &str, i64, &str); 12] = [
        ("N", "N", "ALA", 1, "A"),
        ("CA", "C", "ALA", 1, "A"),
        ("CB", "C", "ALA", 1, "A"),
        ("HA", "H", "ALA", 1, "A"),
        ("N", "N", "GLY", 2, "A"),
        ("CA", "C", "GLY", 2, "A"),
        ("OW", "O", "SOL", 3, "B"),
        ("HW1", "H", "SOL", 3, "B"),
        ("NA", "Na", "NA", 4, "B"),
        ("P", "P", "POPC", 5, "B"),
        ("C1", "C", "LIG", 6, "B"),
        ("CL1", "Cl", "LIG", 6, "B"),
    ];
    let mut top = Topology::default();
    let mut residue = 0u32;
    for (i, (name, element, resname, resid, chain)) in atoms.iter().enumerate() {
        if i > 0 && atoms[i - 1].3 != *resid {
            residue += 1;
        }
        top.names.push(name);
        top.elements.push(element);
        top.residue_names.push(resname);
        top.residue_ids.push(*resid);
        top.residue_index.push(residue);
        top.chains.push(chain);
        top.masses.push(i as f32);
        top.b_factors.push(10.0 * i as f32);
    }
    let frame = Frame {
        positions: (0..atoms.len())
            .map(|i| Vec3::new(i as f32, 0.0, 0.0))
            .collect(),
        ..Default::default()
    };
    (top, frame)
}

fn select(text: &str) -> Vec<u32> {
    let (top, frame) = system();
    let selection = Selection::parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    selection.bind(&top).indices(&frame)
}

fn error(text: &str) -> SelectionError {
    Selection::parse(text).expect_err(text)
}

#[test]
fn keywords_and_macros() {
    assert_eq!(select("all").len(), 12);
    assert_eq!(select("none"), Vec::<u32>::new());
    assert_eq!(select("name CA"), vec![1, 5]);
    assert_eq!(select("resname ALA GLY"), vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(select("protein"), vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(select("backbone"), vec![0, 1, 4, 5]);
    assert_eq!(select("sidechain"), vec![2]);
    assert_eq!(select("water"), vec![6, 7]);
    assert_eq!(select("ion"), vec![8]);
    assert_eq!(select("lipid"), vec![9]);
    assert_eq!(select("ligand"), vec![10, 11]);
    assert_eq!(select("hydrogen"), vec![3, 7]);
    assert_eq!(select("noh").len(), 10);
    assert_eq!(select("heavy"), select("not hydrogen"));
    assert_eq!(select("element cl"), vec![11]);
    assert_eq!(select("chain B and not water"), vec![8, 9, 10, 11]);
    assert_eq!(select("type OW"), vec![6], "type falls back to the name");
    assert_eq!(select("serial 1 12"), vec![0, 11]);
}

#[test]
fn numbers_ranges_and_comparisons() {
    assert_eq!(select("resid 1 3"), vec![0, 1, 2, 3, 6, 7]);
    assert_eq!(select("resid 2 to 3"), vec![4, 5, 6, 7]);
    assert_eq!(select("index 0:2"), vec![0, 1, 2]);
    assert_eq!(select("residue 5"), vec![10, 11]);
    assert_eq!(select("resid >= 5"), vec![9, 10, 11]);
    assert_eq!(select("resid != 1 and protein"), vec![4, 5]);
    assert_eq!(select("mass < 2.0"), vec![0, 1]);
    assert_eq!(select("beta == 30"), vec![3]);
    assert_eq!(select("x > 9.5"), vec![10, 11]);
    assert_eq!(select("x<=1"), vec![0, 1]);
    assert_eq!(select("occupancy 1").len(), 12, "occupancy defaults to 1");
}

#[test]
fn precedence_and_grouping() {
    // not > and > or.
    assert_eq!(select("not protein and chain A"), Vec::<u32>::new());
    assert_eq!(select("name CA or name N and resid 2"), vec![1, 4, 5]);
    assert_eq!(select("(name CA or name N) and resid 2"), vec![4, 5]);
    assert_eq!(select("not (water or protein) and resid <= 5"), vec![8, 9]);
    assert_eq!(select("not not ion"), vec![8]);
}

#[test]
fn globs_and_regexes() {
    assert_eq!(select("name C*"), vec![1, 2, 5, 10, 11]);
    assert_eq!(select("name C?"), vec![1, 2, 5, 10]);
    assert_eq!(select("name C[AB]"), vec![1, 2, 5]);
    assert_eq!(select("name \"C[AB]\""), vec![1, 2, 5]);
    assert_eq!(
        select("name \"C\""),
        Vec::<u32>::new(),
        "regexes match whole names"
    );
    assert_eq!(select("resname \"(ALA|SOL)\""), vec![0, 1, 2, 3, 6, 7]);
    assert_eq!(select("name HW?"), vec![7]);
}

#[test]
fn dynamic_parts() {
    let (top, frame) = system();
    let s = Selection::parse("within 1.0 of name P").expect("parse");
    assert!(s.is_dynamic() && s.bind(&top).is_dynamic());
    assert_eq!(s.bind(&top).indices(&frame), vec![8, 9, 10]);
    assert_eq!(select("exwithin 1.0 of name P"), vec![8, 10]);
    assert_eq!(select("same residue as name CB"), vec![0, 1, 2, 3]);
    assert_eq!(
        select("same chain as name NA"),
        (6..12).collect::<Vec<u32>>()
    );
    assert_eq!(select("same residue as within 0.5 of name P"), vec![9]);
    assert_eq!(select("water and within 2 of ion"), vec![6, 7]);
    assert_eq!(select("within 1 of ion or lipid"), vec![7, 8, 9, 10]);
    assert_eq!(select("x < 2 or name CL1"), vec![0, 1, 11]);
    assert!(
        !Selection::parse("same residue as name CA")
            .unwrap()
            .is_dynamic()
    );
    // A periodic box 12 Å along x: atom 11 (x = 11) is 1 Å from atom 0.
    let mut boxed = frame.clone();
    boxed.cell = Some([Vec3::X * 12.0, Vec3::Y * 12.0, Vec3::Z * 12.0]);
    let s = Selection::parse("exwithin 1.0 of index 0")
        .unwrap()
        .bind(&top);
    assert_eq!(s.indices(&boxed), vec![1, 11]);
    assert_eq!(s.indices(&frame), vec![1]);
    assert_eq!(s.mask(&frame).len(), 12);
}

#[test]
fn errors_name_their_column() {
    let e = error("protein and resnam ALA");
    assert_eq!(e.column, 13);
    assert_eq!(
        e.to_string(),
        "column 13: unknown keyword 'resnam' (did you mean resname?)"
    );
    assert_eq!(error("name CA and").column, 12);
    assert_eq!(error("(protein").column, 9);
    assert_eq!(error("protein)").column, 8);
    assert_eq!(error("resid ALA").column, 7);
    assert_eq!(error("name > 3").column, 1);
    assert_eq!(error("within x of protein").column, 8);
    assert_eq!(error("name \"C[\"").column, 6);
    assert_eq!(error("name").column, 1);
    assert_eq!(error("").column, 1);
    assert!(error("protien").message.contains("did you mean protein?"));
    assert_eq!(
        error("name CA and qqq ALA or (").column,
        13,
        "the first error wins"
    );
    for text in ["name CA and", "(protein", "resid ALA", "name \"C["] {
        assert!(!error(text).to_string().contains('\n'), "{text}");
    }
}

#[test]
fn text_clone_and_equality() {
    let s = Selection::parse("  name CA ").expect("parse");
    assert_eq!(s.text(), "  name CA ");
    assert_eq!(s.clone(), s);
    assert_ne!(s, Selection::parse("name CB").expect("parse"));
    fn send_sync<T: Send + Sync>() {}
    send_sync::<BoundSelection>();
    send_sync::<Selection>();
}
