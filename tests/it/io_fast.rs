//! The fast PDB and XYZ readers against the chemfiles path: on every structure file in
//! tests/data, on a tiled PDB whose serials cross into hybrid-36, and on XYZ files with odd
//! bytes, `io::open` and `io::open_via_chemfiles` give the same topology (names, elements,
//! residues, chains, radii, bonds, ...) and the same frames (positions, box). Damaged files still
//! give one line of error naming the file, never a panic.

use std::path::{Path, PathBuf};

use mdsurf::io;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Opens `path` both ways and asserts that everything read is identical.
fn same_both_ways(path: &Path) {
    let fast = io::open(path, None).unwrap_or_else(|e| panic!("{e}"));
    let slow = io::open_via_chemfiles(path, None).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (fast.topology(), slow.topology());
    let name = path.display();
    assert_eq!(a.len(), b.len(), "{name}: atom count");
    assert_eq!(a.names, b.names, "{name}: names");
    assert_eq!(a.types, b.types, "{name}: types");
    assert_eq!(a.elements, b.elements, "{name}: elements");
    assert_eq!(a.residue_names, b.residue_names, "{name}: residue names");
    assert_eq!(a.residue_ids, b.residue_ids, "{name}: residue numbers");
    assert_eq!(a.residue_index, b.residue_index, "{name}: residues");
    assert_eq!(a.chains, b.chains, "{name}: chains");
    assert_eq!(a.segments, b.segments, "{name}: segments");
    assert_eq!(a.radii, b.radii, "{name}: radii");
    assert_eq!(a.masses, b.masses, "{name}: masses");
    assert_eq!(a.charges, b.charges, "{name}: charges");
    assert_eq!(a.b_factors, b.b_factors, "{name}: B-factors");
    assert_eq!(a.occupancies, b.occupancies, "{name}: occupancies");
    assert_eq!(a.serials, b.serials, "{name}: serials");
    assert_eq!(a.bonds, b.bonds, "{name}: bonds");
    assert_eq!(a, b, "{name}: topology");
    assert_eq!(fast.len(), slow.len(), "{name}: frames");
    for i in 0..fast.len().min(3) {
        match (fast.read_frame(i), slow.read_frame(i)) {
            (Ok(fa), Ok(fb)) => {
                assert_eq!(fa.positions, fb.positions, "{name}: positions of frame {i}");
                assert_eq!(fa.cell, fb.cell, "{name}: box of frame {i}");
                // chemfiles gives no time for GRO files; our reader reads the title's `t=`
                // (tested in io_native_text.rs).
                if fb.time_ps.is_some() || !name.to_string().contains(".gro") {
                    assert_eq!(fa.time_ps, fb.time_ps, "{name}: time of frame {i}");
                }
            }
            // A frame that does not fit the topology (1lcd's models differ in size) is the
            // same error both ways.
            (Err(ea), Err(eb)) => assert_eq!(ea.to_string(), eb.to_string(), "{name}: frame {i}"),
            (a, b) => panic!(
                "{name}: frame {i} is {:?} one way and {:?} the other",
                a.map(|f| f.positions.len()),
                b.map(|f| f.positions.len())
            ),
        }
    }
}

#[test]
fn every_structure_in_tests_data_reads_the_same_both_ways() {
    let mut fast = Vec::new();
    for entry in std::fs::read_dir(data("")).unwrap() {
        let path = entry.unwrap().path();
        let Ok(format) = io::detect(&path) else {
            continue;
        };
        // mmCIF files are read by our mmCIF reader, compared with chemfiles in io_mmcif.rs.
        if !format.has_names || format.base == "mmCIF" {
            continue;
        }
        if io::reads_fast(&path).unwrap() {
            fast.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
        same_both_ways(&path);
    }
    fast.sort();
    assert_eq!(
        fast,
        [
            "1hpv.pdb",
            "1hvr.pdb",
            "5a7u.pdb",
            "adk_closed.pdb",
            "adk_open.pdb"
        ],
        "the plain PDB files take the fast path (compressed ones go to chemfiles)"
    );
}

/// Hybrid-36 as PDB writers encode serials past 99,999.
fn hybrid36(width: u32, value: i64) -> String {
    if value < 10i64.pow(width) {
        return format!("{value:>w$}", w = width as usize);
    }
    let mut v = value - 10i64.pow(width) + 10 * 36i64.pow(width - 1);
    let digits = b"0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ";
    let mut out = Vec::new();
    for _ in 0..width {
        out.push(digits[(v % 36) as usize]);
        v /= 36;
    }
    out.reverse();
    String::from_utf8(out).unwrap()
}

/// Three copies of 1hpv.pdb, shifted, with chains renamed, serials starting at 97,000 (so they
/// cross into hybrid-36), TER records and the ligand's CONECT records renumbered per copy.
fn tiled_1hpv() -> String {
    let text = std::fs::read_to_string(data("1hpv.pdb")).unwrap();
    let records: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("ATOM") || l.starts_with("HETATM") || l.starts_with("TER"))
        .collect();
    let conect: Vec<&str> = text.lines().filter(|l| l.starts_with("CONECT")).collect();
    let mut out = String::from("CRYST1  200.000  100.000  100.000  90.00  90.00  90.00 P 1\n");
    let mut serial = 96_999i64;
    for copy in 0..3 {
        let mut renumber = std::collections::HashMap::new();
        for line in &records {
            serial += 1;
            renumber.insert(line[6..11].trim().to_string(), serial);
            let chain = match &line[21..22] {
                "A" => ["A", "C", "E"][copy],
                "B" => ["B", "D", "F"][copy],
                c => c,
            };
            let head = format!(
                "{}{}{}{}",
                &line[..6],
                hybrid36(5, serial),
                &line[11..21],
                chain
            );
            if line.starts_with("TER") {
                out.push_str(&format!("{head}{}\n", &line[22..]));
                continue;
            }
            let x: f64 = line[30..38].trim().parse().unwrap();
            out.push_str(&format!(
                "{head}{}{:8.3}{}\n",
                &line[22..30],
                x + 70.0 * copy as f64,
                &line[38..]
            ));
        }
        for line in &conect {
            let fields: Vec<String> = (0..5)
                .filter_map(|k| line.get(6 + 5 * k..11 + 5 * k))
                .filter_map(|f| renumber.get(f.trim()))
                .map(|&s| hybrid36(5, s))
                .collect();
            out.push_str(&format!("CONECT{}\n", fields.concat()));
        }
    }
    out.push_str("END\n");
    out
}

#[test]
fn a_tiled_pdb_with_hybrid36_serials_reads_the_same_both_ways() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiled.pdb");
    std::fs::write(&path, tiled_1hpv()).unwrap();
    assert!(io::reads_fast(&path).unwrap());
    same_both_ways(&path);
    let t = io::open(&path, None).unwrap();
    assert_eq!(t.topology().len(), 3 * 1631);
    assert!(t.read_frame(0).unwrap().cell.is_some());
}

#[test]
fn xyz_files_read_the_same_both_ways() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8]); 5] = [
        ("plain.xyz", b"3\nwater\nO 0.0 0.0 0.0\nH 0.9572 0.0 0.0\nH -0.24 0.9266 0.0\n"),
        (
            "crlf.xyz",
            b"4\r\nions and names\r\nNA 1 2 3\r\nCl\t-1.5e1 2.25 3\r\nCA 0.001 0 0 extra\r\nOW 1 1 1\r\n\r\n",
        ),
        ("latin1.xyz", b"2\ncaf\xe9\nC\xe9 0 0 0\nC 1.5 0 0\n"),
        ("utf8.xyz", "2\nÅ\nCé 0 0 0\nFe 1.5 0 0\n".as_bytes()),
        ("no_newline.xyz", b"1\nlast line\nAr 3 4 5"),
    ];
    for (name, text) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        assert!(io::reads_fast(&path).unwrap(), "{name} takes the fast path");
        same_both_ways(&path);
    }
    // A water box large enough for the untyped-radius fit, written by chemfiles itself.
    let mut frame = chemfiles::Frame::new();
    for i in 0..600 {
        let p = [
            (i % 10) as f64 * 3.1,
            ((i / 10) % 10) as f64 * 3.1,
            (i / 100) as f64 * 3.1,
        ];
        frame.add_atom(
            &chemfiles::Atom::new(if i % 3 == 0 { "OW" } else { "X1" }),
            p,
            None,
        );
    }
    let path = dir.path().join("box.xyz");
    chemfiles::Trajectory::open(&path, 'w')
        .unwrap()
        .write(&frame)
        .unwrap();
    same_both_ways(&path);
}

#[test]
fn several_frames_and_extended_xyz_go_through_chemfiles() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8]); 3] = [
        ("two.xyz", b"1\na\nO 0 0 0\n1\nb\nO 0 0 1\n"),
        ("ext.xyz", b"1\nProperties=species:S:1:pos:R:3 Lattice=\"9 0 0 0 9 0 0 0 9\"\nO 0 0 0\n"),
        (
            "models.pdb",
            b"MODEL        1\nATOM      1  CA  ALA A   1       1.000   2.000   3.000  1.00  0.00           C\nENDMDL\nMODEL        2\nATOM      1  CA  ALA A   1       1.500   2.000   3.000  1.00  0.00           C\nENDMDL\nEND\n",
        ),
    ];
    for (name, text) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        assert!(!io::reads_fast(&path).unwrap(), "{name} goes to chemfiles");
        let t = io::open(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!t.is_empty());
    }
}

/// wwPDB files end a model by ENDMDL, then CONECT and MASTER records, then END: chemfiles
/// counts the END as one more frame, which has no atoms. One model is one frame, and two models
/// two frames, each with its atoms (tests/data/2beg.pdb.gz is such a one-model NMR entry).
#[test]
fn wwpdb_models_followed_by_master_and_end_have_no_empty_last_frame() {
    let dir = tempfile::tempdir().unwrap();
    let atom = |x: &str| {
        format!("ATOM      1  CA  ALA A   1     {x:>7}   2.000   3.000  1.00  0.00           C\n")
    };
    let tail = "CONECT    1    1\nMASTER        0    0    0    0    0    0    0    0    1    0    1    0\nEND\n";
    let one = format!("MODEL        1\n{}ENDMDL\n{tail}", atom("1.000"));
    let two = format!(
        "MODEL        1\n{}ENDMDL\nMODEL        2\n{}ENDMDL\n{tail}",
        atom("1.000"),
        atom("1.500")
    );
    for (name, text, frames) in [("one.pdb", one, 1), ("two.pdb", two, 2)] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let t = io::open(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(t.len(), frames, "{name}");
        for i in 0..frames {
            let f = t
                .read_frame(i)
                .unwrap_or_else(|e| panic!("{name} frame {i}: {e}"));
            assert_eq!(f.positions.len(), 1, "{name} frame {i}");
        }
    }
    let nmr = io::open(&data("2beg.pdb.gz"), None).expect("2beg");
    assert_eq!(nmr.len(), 1);
    assert_eq!(nmr.read_frame(0).expect("frame 0").positions.len(), 1855);
}

/// A compressed wwPDB multi-model file whose models differ in size, with CONECT records after
/// the last ENDMDL (1lcd: 1,137 atoms in model 1, 1,125 in model 3), crashed chemfiles when
/// it read those records with the last model (a segmentation fault, not an error). The
/// decompressed copy is cleaned as an uncompressed file is: every model reads, and the one
/// whose atom count differs says so in the CLI (tests/it/cli_errors.rs checks that message).
#[test]
fn compressed_wwpdb_with_models_of_different_sizes_reads_every_model() {
    // Per frame: its atom count, or the error's text.
    let frames = |t: &io::Trajectory| -> Vec<Result<usize, String>> {
        (0..t.len())
            .map(|i| {
                t.read_frame(i)
                    .map(|f| f.positions.len())
                    .map_err(|e| e.to_string())
            })
            .collect()
    };
    let t = io::open(&data("1lcd.pdb.gz"), None).expect("1lcd");
    assert_eq!(t.len(), 3);
    let gz = frames(&t);
    assert_eq!(gz[0], Ok(1137));
    assert!(
        gz.iter().any(|r| r
            .as_ref()
            .is_err_and(|e| e.contains("1125") && e.contains("1137"))),
        "{gz:?}"
    );
    let plain = tempfile::tempdir().unwrap();
    let copy = plain.path().join("1lcd.pdb");
    std::fs::write(&copy, crate::data_support::gunzipped("1lcd.pdb.gz")).unwrap();
    let p = io::open(&copy, None).expect("uncompressed 1lcd");
    let counts = |v: &[Result<usize, String>]| -> Vec<Option<usize>> {
        v.iter().map(|r| r.as_ref().ok().copied()).collect()
    };
    assert_eq!(counts(&frames(&p)), counts(&gz));
}

/// The error of opening `path`: one line naming the file.
fn one_line_error(path: &Path) -> String {
    let e = io::open(path, None).expect_err("damaged").to_string();
    let name = path.file_name().unwrap().to_string_lossy();
    assert!(e.contains(name.as_ref()), "{e}");
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
fn damaged_files_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = std::fs::read(data("1hpv.pdb")).unwrap();
    let cut_at = pdb.windows(4).position(|w| w == b"ATOM").unwrap() + 40;
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("cut.pdb", pdb[..cut_at].to_vec()),
        (
            "bad_number.pdb",
            b"ATOM      1  CA  ALA A   1       1.000   x.000   3.000  1.00  0.00           C\nEND\n"
                .to_vec(),
        ),
        ("short.xyz", b"3\ntwo lines only\nO 0 0 0\nH 1 0 0\n".to_vec()),
        ("bad.xyz", b"2\nbad number\nO 0 0 0\nH 1 zero 0\n".to_vec()),
        ("count.xyz", b"two\natoms\nO 0 0 0\nH 1 0 0\n".to_vec()),
        ("bytes.xyz", vec![0xff, 0xfe, b'\n', 0x80, 0x00, b'\n', 0xc3]),
    ];
    for (name, bytes) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        one_line_error(&path);
    }
}
