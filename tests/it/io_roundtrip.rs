//! Files the test writes itself with chemfiles (XTC, TRR, DCD, Amber NetCDF trajectories; PDB,
//! mmCIF, GRO, XYZ topologies, a gzipped GRO, a PDB past 99,999 atoms) read back through
//! `mdsurf::io::open` with the positions, box and counts that were written.

use std::path::Path;

use mdsurf::io;

/// A deterministic spread of `n` atoms in a 40 Å cube, shifted per frame (Å).
fn positions(n: usize, frame: usize) -> Vec<[f64; 3]> {
    let mut state = 12345u64 + frame as u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            [
                40.0 * next() + 5.0,
                40.0 * next() + 5.0,
                40.0 * next() + 5.0,
            ]
        })
        .collect()
}

const NAMES: [&str; 5] = ["N", "CA", "C", "O", "CB"];
const BOX: f64 = 50.0;

/// A chemfiles frame of `n` atoms in 5-atom ALA residues, with a cubic box.
fn chem_frame(n: usize, frame: usize) -> chemfiles::Frame {
    let mut f = chemfiles::Frame::new();
    for (i, p) in positions(n, frame).into_iter().enumerate() {
        let mut atom = chemfiles::Atom::new(NAMES[i % 5]);
        atom.set_atomic_type(&NAMES[i % 5][..1]);
        f.add_atom(&atom, p, None);
    }
    for r in 0..n.div_ceil(5) {
        let mut residue = chemfiles::Residue::with_id("ALA", r as i64 + 1);
        (5 * r..(5 * r + 5).min(n)).for_each(|a| residue.add_atom(a));
        f.add_residue(&residue).expect("residue");
    }
    f.set_cell(&chemfiles::UnitCell::new([BOX; 3]));
    f.set_step(frame);
    f
}

fn write(path: &Path, format: &str, atoms: usize, frames: usize) {
    let mut t =
        chemfiles::Trajectory::open_with_format(path, 'w', format).expect("open for writing");
    for k in 0..frames {
        t.write(&chem_frame(atoms, k)).expect("write frame");
    }
}

/// Opens `top` + `traj` and checks every frame against what was written, to `tolerance` Å.
fn check(top: &Path, traj: Option<&Path>, atoms: usize, frames: usize, tolerance: f32) {
    let t = io::open(top, traj).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.topology().len(), atoms, "{top:?}");
    assert_eq!(t.len(), frames, "{traj:?}");
    assert!(t.damage().is_none());
    assert_eq!(&t.topology().names[1], "CA");
    assert_eq!(&t.topology().elements[1], "C");
    for k in 0..frames {
        let f = t.read_frame(k).unwrap_or_else(|e| panic!("{e}"));
        let want = positions(atoms, k);
        let worst = f
            .positions
            .iter()
            .zip(&want)
            .map(|(p, w)| {
                (0..3)
                    .map(|d| (p[d] - w[d] as f32).abs())
                    .fold(0.0f32, f32::max)
            })
            .fold(0.0f32, f32::max);
        assert!(
            worst <= tolerance,
            "{traj:?} frame {k}: off by {worst} Å (allowed {tolerance})"
        );
        if let Some(cell) = f.cell {
            assert!(
                (cell[0].x - BOX as f32).abs() < 0.01 && (cell[2].z - BOX as f32).abs() < 0.01,
                "{cell:?}"
            );
        }
    }
}

#[test]
fn trajectories_read_back_equal_to_file_precision() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (atoms, frames) = (103, 6);
    let top = dir.path().join("top.pdb");
    write(&top, "PDB", atoms, 1);
    check(&top, None, atoms, 1, 0.0005 + 1e-4); // PDB: 3 decimals
    // XTC keeps 3 decimals in nm: 0.005 Å at most.
    let cases = [
        ("xtc", "XTC", 0.0051),
        ("trr", "TRR", 1e-4),
        ("dcd", "DCD", 1e-4),
        ("nc", "Amber NetCDF", 1e-4),
    ];
    for (ext, format, tolerance) in cases {
        let path = dir.path().join(format!("traj.{ext}"));
        write(&path, format, atoms, frames);
        check(&top, Some(&path), atoms, frames, tolerance);
    }
    let xtc = io::open(&top, Some(&dir.path().join("traj.xtc"))).expect("xtc");
    assert!(
        xtc.read_frame(0).expect("frame").cell.is_some(),
        "XTC keeps the box"
    );
}

#[test]
fn topologies_in_other_formats() {
    let dir = tempfile::tempdir().expect("tempdir");
    let atoms = 57;
    // GRO keeps 3 decimals in nm (0.005 Å); mmCIF and XYZ as chemfiles prints them.
    for (name, format, tolerance) in [
        ("t.gro", "GRO", 0.0051),
        ("t.cif", "mmCIF", 0.0051),
        ("t.xyz", "XYZ", 1e-3),
    ] {
        let path = dir.path().join(name);
        write(&path, format, atoms, 2);
        check(&path, None, atoms, 2, tolerance);
    }
    let gz = dir.path().join("t.gro.gz");
    write(&gz, "GRO / GZ", atoms, 1);
    check(&gz, None, atoms, 1, 0.0051);
}

#[test]
fn pdb_past_99999_atoms() {
    let dir = tempfile::tempdir().expect("tempdir");
    let atoms = 100_010;
    let path = dir.path().join("big.pdb");
    write(&path, "PDB", atoms, 1);
    let t = io::open(&path, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.topology().len(), atoms);
    let f = t.read_frame(0).expect("frame 0");
    let want = positions(atoms, 0);
    let last = atoms - 1;
    assert!((f.positions[last].x - want[last][0] as f32).abs() < 0.001);
}
