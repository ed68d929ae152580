//! Our GRO and LAMMPS dump readers (`io::open`) against chemfiles (`io::open_via_chemfiles`) on
//! every such file in tests/data, every frame; and on files chemfiles misreads or refuses:
//! GRO with 4 to 6 decimals, CR-LF and CR-only line ends, a byte-order mark, no final newline, a
//! multi-frame GRO cut inside a frame, LAMMPS dumps of a group (sparse ids, ids 0 and past
//! 2^31), scaled and image-flagged positions in a tilted box.

use std::path::Path;

use mdsurf::io;

/// True when `a` and `b` agree within 1e-5 relative (1e-5 Å near 0).
fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0)
}

/// Opens `path` both ways and asserts that they read the same atoms and frames.
fn same_as_chemfiles(path: &Path) {
    let ours = io::open(path, None).unwrap_or_else(|e| panic!("{e}"));
    let theirs = io::open_via_chemfiles(path, None).unwrap_or_else(|e| panic!("{e}"));
    let name = path.display();
    let (a, b) = (ours.topology(), theirs.topology());
    assert_eq!(a.len(), b.len(), "{name}: atoms");
    assert_eq!(a.names, b.names, "{name}: names");
    assert_eq!(a.residue_ids, b.residue_ids, "{name}: residue numbers");
    assert_eq!(a.residue_index, b.residue_index, "{name}: residues");
    assert!(a == b, "{name}: topology");
    assert_eq!(ours.len(), theirs.len(), "{name}: frames");
    assert!(ours.damage().is_none() && theirs.damage().is_none());
    for i in 0..ours.len() {
        let (fa, fb) = (ours.read_frame(i).unwrap(), theirs.read_frame(i).unwrap());
        assert_eq!(fa.positions.len(), fb.positions.len());
        for (k, (p, q)) in fa.positions.iter().zip(&fb.positions).enumerate() {
            let same = (0..3).all(|d| close(p[d], q[d]));
            assert!(same, "{name}: frame {i} atom {k}: {p} vs {q}");
        }
        let (ca, cb) = (fa.cell.expect("a box"), fb.cell.expect("a box"));
        for d in 0..3 {
            assert!(
                (0..3).all(|e| close(ca[d][e], cb[d][e])),
                "{name}: box of frame {i}"
            );
        }
        if fb.time_ps.is_some() {
            assert_eq!(fa.time_ps, fb.time_ps, "{name}: time of frame {i}");
        }
    }
}

#[test]
fn every_gro_and_lammps_file_in_tests_data_reads_as_chemfiles_reads_it() {
    let mut seen = Vec::new();
    for entry in std::fs::read_dir(crate::data_support::DATA).unwrap() {
        let path = entry.unwrap().path();
        let Ok(format) = io::detect(&path) else {
            continue;
        };
        if matches!(format.base, "GRO" | "LAMMPS") {
            same_as_chemfiles(&path);
            seen.push(format.base);
        }
    }
    assert!(
        seen.contains(&"GRO") && seen.contains(&"LAMMPS"),
        "{seen:?}"
    );
}

/// A GRO frame of three atoms at `xyz` (nm) with `decimals` decimals, as `gmx trjconv -ndec`
/// writes it (fields `decimals + 5` wide), titled with time `t` ps.
fn gro_frame(xyz: &[[f64; 3]; 3], decimals: usize, t: f64) -> String {
    let width = decimals + 5;
    let mut text = format!("three waters t= {t:.5} step= 10\n    3\n");
    for (k, p) in xyz.iter().enumerate() {
        let name = ["OW", "HW1", "HW2"][k];
        text += &format!("{:>5}{:<5}{:>5}{:>5}", 1, "SOL", name, k + 1);
        for v in p {
            text += &format!("{v:>width$.decimals$}");
        }
        text += "\n";
    }
    text + "   3.00000   3.00000   3.00000\n"
}

const WATER: [[f64; 3]; 3] = [
    [1.2345678, -0.123456, 2.5],
    [1.3, 0.0, -10.654321],
    [0.0, 1.0, 2.0],
];

#[test]
fn gro_files_with_four_to_six_decimals_and_any_line_ends() {
    let dir = tempfile::tempdir().unwrap();
    for decimals in [3, 4, 5, 6] {
        let text = gro_frame(&WATER, decimals, 2.5);
        let variants = [
            ("lf", text.clone()),
            ("crlf", text.replace('\n', "\r\n")),
            ("cr", text.replace('\n', "\r")),
            ("bom", format!("\u{feff}{text}")),
            ("no_final_newline", text.trim_end().to_string()),
        ];
        for (kind, text) in variants {
            let path = dir.path().join(format!("w{decimals}_{kind}.gro"));
            std::fs::write(&path, &text).unwrap();
            let t = io::open(&path, None).unwrap_or_else(|e| panic!("{decimals} {kind}: {e}"));
            assert_eq!(t.len(), 1, "{decimals} {kind}");
            assert_eq!(t.topology().names, vec!["OW", "HW1", "HW2"]);
            let frame = t.read_frame(0).unwrap();
            assert_eq!(frame.time_ps, Some(2.5), "{decimals} {kind}");
            let scale = 10f64.powi(decimals as i32);
            for (p, want) in frame.positions.iter().zip(&WATER) {
                for d in 0..3 {
                    let rounded = (want[d] * scale).round() / scale * 10.0;
                    assert!(
                        close(p[d], rounded as f32),
                        "{decimals} {kind}: {p} vs {want:?}"
                    );
                }
            }
            assert!(close(frame.cell.unwrap()[2][2], 30.0));
        }
    }
}

#[test]
fn a_gro_trajectory_cut_inside_a_frame_keeps_the_frames_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let whole: String = (0..4).map(|k| gro_frame(&WATER, 3, k as f64)).collect();
    let path = dir.path().join("four.gro");
    std::fs::write(&path, &whole).unwrap();
    let t = io::open(&path, None).unwrap();
    assert_eq!(t.len(), 4);
    assert!(t.damage().is_none());
    assert_eq!(t.read_frame(3).unwrap().time_ps, Some(3.0));
    // Cut in the middle of frame 2's first atom line.
    let frame_len = whole.len() / 4;
    let cut = dir.path().join("cut.gro");
    std::fs::write(&cut, &whole[..2 * frame_len + 60]).unwrap();
    let t = io::open(&cut, None).unwrap();
    assert_eq!(t.len(), 2);
    let damage = t.damage().expect("the cut frame is damage");
    assert_eq!(damage.frame, 2);
    let message = damage.error.to_string();
    assert!(
        message.contains("cut.gro") && message.contains("frame 2"),
        "{message}"
    );
    assert!(!message.contains('\n'));
    assert!(t.read_frame(2).is_err());
    // Cut inside frame 0: nothing to read, one line naming the file.
    std::fs::write(&cut, &whole[..60]).unwrap();
    let e = io::open(&cut, None).unwrap_err().to_string();
    assert!(e.contains("cut.gro") && e.contains("frame 0"), "{e}");
}

/// A dump frame of atoms `(id, type, x, y, z)` in a 10 Å cube.
fn dump_frame(atoms: &[(u64, u32, f64, f64, f64)]) -> String {
    let mut text = format!(
        "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS pp pp pp\n\
         0 10\n0 10\n0 10\nITEM: ATOMS x id type y z\n",
        atoms.len()
    );
    for (id, kind, x, y, z) in atoms {
        text += &format!("{x} {id} {kind} {y} {z}\n");
    }
    text
}

#[test]
fn lammps_dumps_of_groups_with_any_ids_read_in_id_order() {
    let dir = tempfile::tempdir().unwrap();
    let atoms = [
        (1u64 << 40, 3, 4.0, 4.0, 4.0),
        (17, 2, 2.0, 2.0, 2.0),
        (0, 1, 1.0, 1.0, 1.0),
        (3_000_000_000, 2, 3.0, 3.0, 3.0),
    ];
    let text = format!("{}\n{}", dump_frame(&atoms), dump_frame(&atoms[1..]));
    let path = dir.path().join("group.lammpstrj");
    std::fs::write(&path, text.replace('\n', "\r\n")).unwrap();
    let t = io::open(&path, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.topology().names, vec!["1", "2", "2", "3"]);
    // The ids are the serial numbers (labels and `--per-atom` rows name the file's atoms).
    assert_eq!(t.topology().serials, [0, 17, 3_000_000_000, 1 << 40]);
    let xs: Vec<f32> = t
        .read_frame(0)
        .unwrap()
        .positions
        .iter()
        .map(|p| p.x)
        .collect();
    assert_eq!(xs, [1.0, 2.0, 3.0, 4.0]);
    assert_eq!(t.len(), 2);
    assert!(t.read_frame(1).is_err(), "frame 1 has fewer atoms");
    // A dump cut inside its second frame: the first is kept, the second is damage.
    let two = format!("{}{}", dump_frame(&atoms), dump_frame(&atoms));
    let cut = dir.path().join("cut.lammpstrj");
    std::fs::write(&cut, &two[..two.len() - 10]).unwrap();
    let t = io::open(&cut, None).unwrap();
    assert_eq!(t.len(), 1);
    let damage = t.damage().expect("damage");
    assert_eq!(damage.frame, 1);
    assert!(damage.error.to_string().contains("cut.lammpstrj"));
}
