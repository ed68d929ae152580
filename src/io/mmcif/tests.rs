//! Unit tests of the mmCIF reader: cells, quoting, damaged loops, models and bonds.

use super::*;

const HEADER: &str = "data_x\n_cell.length_a 10.0(2)\n_cell.length_b 20\n\
    _cell.length_c 30\n#\nloop_\n_atom_site.group_PDB\n_atom_site.id\n\
    _atom_site.type_symbol\n_atom_site.label_atom_id\n_atom_site.label_comp_id\n\
    _atom_site.label_asym_id\n_atom_site.label_entity_id\n_atom_site.label_seq_id\n\
    _atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n\
    _atom_site.B_iso_or_equiv\n_atom_site.auth_seq_id\n_atom_site.pdbx_PDB_model_num\n";

fn read_text(text: &str) -> Result<CifRead, IoError> {
    read(Path::new("t.cif"), text.as_bytes())
}

fn glycines(model: u32, dx: f32) -> String {
    let mut out = String::new();
    for (k, name) in ["N", "CA", "C", "O"].iter().enumerate() {
        for res in 1..=2 {
            let serial = res * 10 + k;
            let x = k as f32 + 5.0 * res as f32 + dx;
            out += &format!(
                "ATOM {serial} {} {name} GLY A 1 {res} {x:.3} 0.5 -1.25 {}.5 {res} {model}\n",
                &name[..1],
                k
            );
        }
    }
    out
}

#[test]
fn atoms_residues_bonds_models_and_cell() {
    let text = format!(
        "{HEADER}{}{}HETATM 99 O O HOH B 2 . 1 2 3 ? 301 1\n#\n",
        glycines(1, 0.0),
        glycines(2, 0.25)
    );
    // Model 2 has no water: the model numbers are 1, 1, ..., 2, 2, ..., 1.
    let read = read_text(&text).expect("reads");
    assert_eq!(read.frames.len(), 3);
    let top = &read.topology;
    assert_eq!(top.len(), 8);
    assert_eq!(top.names.to_strings()[..4], ["N", "N", "CA", "CA"]);
    assert_eq!(top.elements.to_strings()[..3], ["N", "N", "C"]);
    assert_eq!(top.residue_ids, [1, 2, 1, 2, 1, 2, 1, 2]);
    // Two residues, interleaved in the file: runs of one atom each.
    assert_eq!(top.residue_index, [0, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(&top.chains[0], "A");
    assert_eq!(top.b_factors[2], 1.5);
    assert_eq!(top.serials[..2], [10, 20]);
    // GLY N-CA, CA-C, C-O in each residue and the peptide link C(1)-N(2).
    let bonds: Vec<[u32; 2]> = vec![[0, 2], [1, 3], [1, 4], [2, 4], [3, 5], [4, 6], [5, 7]];
    assert_eq!(top.bonds, bonds);
    assert_eq!(read.frames[0].positions[0], Vec3::new(5.0, 0.5, -1.25));
    assert_eq!(read.frames[1].positions[0], Vec3::new(5.25, 0.5, -1.25));
    assert_eq!(read.frames[2].positions, [Vec3::new(1.0, 2.0, 3.0)]);
    let cell = read.frames[0].cell.expect("a box");
    assert!(
        cell[0].abs_diff_eq(Vec3::new(10.0, 0.0, 0.0), 1e-5),
        "{cell:?}"
    );
    assert!(
        cell[2].abs_diff_eq(Vec3::new(0.0, 0.0, 30.0), 1e-5),
        "{cell:?}"
    );
}

#[test]
fn quoted_primed_names_link_nucleotides_o3_to_p() {
    let mut text = HEADER.to_string();
    let names = ["P", "\"O5'\"", "\"C5'\"", "\"C4'\"", "\"C3'\"", "'O3''"];
    for res in 1..=2 {
        for (k, name) in names.iter().enumerate() {
            let serial = res * 10 + k;
            let x = (res * 10 + k) as f32;
            text += &format!("ATOM {serial} X {name} DA B 1 {res} {x} 0 0 1 {res} 1\n");
        }
    }
    let read = read_text(&text).expect("reads");
    let top = &read.topology;
    assert_eq!(&top.names[1], "O5'");
    assert_eq!(&top.names[5], "O3'");
    let chain = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]];
    let mut want: Vec<[u32; 2]> = chain.to_vec();
    want.extend(chain.iter().map(|[a, b]| [a + 6, b + 6]));
    // O3' of the first nucleotide to P of the second.
    want.push([5, 6]);
    want.sort_unstable();
    assert_eq!(top.bonds, want);
}

#[test]
fn damaged_rows_name_their_line() {
    let good = glycines(1, 0.0);
    let lines: Vec<&str> = good.lines().collect();
    let first_row = HEADER.lines().count() + 1;
    // A value missing from the third row.
    let short = lines[2].replacen(" GLY", "", 1);
    let text = format!(
        "{HEADER}{}\n{}\n{short}\n{}\n",
        lines[0], lines[1], lines[3]
    );
    let e = read_text(&text).err().expect("a short row").to_string();
    assert!(
        e.contains(&format!(
            "line {}: an _atom_site row with 13 of its 14 values",
            first_row + 2
        )),
        "{e}"
    );
    // A value too many.
    let long = format!("{} 7", lines[1]);
    let text = format!("{HEADER}{}\n{long}\n{}\n", lines[0], lines[2]);
    let e = read_text(&text).err().expect("a long row").to_string();
    assert!(
        e.contains("row with 15 values where the loop has 14"),
        "{e}"
    );
    // Cut inside the last row.
    let text = format!("{HEADER}{}\nATOM 3 C", lines[0]);
    let e = read_text(&text).err().expect("a cut row").to_string();
    assert!(
        e.contains("of its 14 values (is the file cut short?)"),
        "{e}"
    );
    // A coordinate that is not a number.
    let text = format!("{HEADER}{}\n", lines[0].replace("0.5", "0.5x"));
    let e = read_text(&text).err().expect("a bad number").to_string();
    assert!(
        e.contains(&format!(
            "line {first_row}: _atom_site.Cartn_y is '0.5x', not a number"
        )),
        "{e}"
    );
    let e = read_text("data_x\n_cell.length_a 3\n")
        .err()
        .expect("no loop");
    assert!(e.to_string().contains("no _atom_site loop"), "{e}");
    let e = read_text(&format!("{HEADER}#\n")).err().expect("no atoms");
    assert!(matches!(e, IoError::Empty { .. }), "{e}");
}
