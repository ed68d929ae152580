//! Our DCD and Amber NetCDF readers against chemfiles: every DCD of `tests/data`, DCD variants
//! written here (both byte orders, with and without a cell, fixed atoms, X-PLOR header), NetCDF
//! files written by chemfiles and by hand (CDF-1 and CDF-2, with time, streaming record
//! count), frame by frame (positions, box, time); and damaged files: a cut or damaged frame k
//! keeps frames 0..k and names frame k, hostile headers are one-line errors.

use std::path::{Path, PathBuf};

use mdsurf::io::{self, IoError};

use crate::data_support::data;

/// Opens `traj` (with topology `top`) through our reader and through chemfiles, and checks
/// they agree on the frame count and every frame; returns the frame count.
fn same_as_chemfiles(top: &Path, traj: &Path) -> usize {
    let ours = io::open(top, Some(traj)).expect("ours opens");
    let theirs = io::open_via_chemfiles(top, Some(traj)).expect("chemfiles opens");
    assert_eq!(ours.len(), theirs.len(), "{}", traj.display());
    for k in 0..ours.len() {
        let (a, b) = (ours.read_frame(k).unwrap(), theirs.read_frame(k).unwrap());
        assert_eq!(a.positions, b.positions, "{} frame {k}", traj.display());
        assert_eq!(a.cell, b.cell, "{} frame {k}", traj.display());
        assert_eq!(a.time_ps, b.time_ps, "{} frame {k}", traj.display());
    }
    ours.len()
}

fn one_line(e: &IoError, needles: &[&str]) {
    let text = e.to_string();
    assert!(!text.contains('\n'), "{text}");
    for n in needles {
        assert!(text.contains(n), "'{n}' missing from: {text}");
    }
}

/// A PDB topology of `atoms` atoms in `dir`.
fn topology(dir: &Path, atoms: usize) -> PathBuf {
    let path = dir.join(format!("top{atoms}.pdb"));
    let mut frame = chemfiles::Frame::new();
    for i in 0..atoms {
        frame.add_atom(&chemfiles::Atom::new("C"), [i as f64, 0.0, 0.0], None);
    }
    chemfiles::Trajectory::open(&path, 'w')
        .unwrap()
        .write(&frame)
        .unwrap();
    path
}

/// How to write a DCD by hand.
#[derive(Clone, Copy)]
struct Dcd {
    big: bool,
    cell: Option<[f64; 6]>,
    /// CHARMM version in the header (0: X-PLOR).
    version: i32,
    fixed: usize,
    four_d: bool,
}

/// A DCD of `frames` frames of `atoms` atoms (coordinates that differ per atom and frame).
fn write_dcd(spec: Dcd, atoms: usize, frames: usize) -> Vec<u8> {
    let mut out = Vec::new();
    let int = |v: i32| {
        if spec.big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let rec = |out: &mut Vec<u8>, data: &[u8]| {
        out.extend_from_slice(&int(data.len() as i32));
        out.extend_from_slice(data);
        out.extend_from_slice(&int(data.len() as i32));
    };
    let mut header = b"CORD".to_vec();
    let mut control = [0i32; 20];
    control[0] = frames as i32;
    control[1] = 10;
    control[2] = 5;
    control[8] = spec.fixed as i32;
    control[19] = spec.version;
    for (k, c) in control.iter().enumerate() {
        match k {
            9 if spec.version != 0 => header.extend_from_slice(&if spec.big {
                2.0f32.to_be_bytes()
            } else {
                2.0f32.to_le_bytes()
            }),
            9 => header.extend_from_slice(&if spec.big {
                2.0f64.to_be_bytes()
            } else {
                2.0f64.to_le_bytes()
            }),
            10 if spec.version == 0 => {}
            10 => header.extend_from_slice(&int(spec.cell.is_some() as i32)),
            11 => header.extend_from_slice(&int(spec.four_d as i32)),
            _ => header.extend_from_slice(&int(*c)),
        }
    }
    rec(&mut out, &header);
    let mut title = int(2).to_vec();
    title.extend_from_slice(&[b'T'; 160]);
    rec(&mut out, &title);
    rec(&mut out, &int(atoms as i32));
    let free: Vec<usize> = (spec.fixed..atoms).collect();
    if spec.fixed > 0 {
        let list: Vec<u8> = free.iter().flat_map(|&i| int(i as i32 + 1)).collect();
        rec(&mut out, &list);
    }
    for k in 0..frames {
        if let Some(cell) = spec.cell {
            let bytes: Vec<u8> = cell
                .iter()
                .flat_map(|v| {
                    if spec.big {
                        v.to_be_bytes()
                    } else {
                        v.to_le_bytes()
                    }
                })
                .collect();
            rec(&mut out, &bytes);
        }
        let stored: Vec<usize> = if k == 0 {
            (0..atoms).collect()
        } else {
            free.clone()
        };
        for axis in 0..if spec.four_d { 4 } else { 3 } {
            let values: Vec<u8> = stored
                .iter()
                .flat_map(|&i| {
                    let v = i as f32 * 1.5 + axis as f32 * 0.25 + k as f32 * 0.125;
                    if spec.big {
                        v.to_be_bytes()
                    } else {
                        v.to_le_bytes()
                    }
                })
                .collect();
            rec(&mut out, &values);
        }
    }
    out
}

#[test]
fn dcd_in_tests_data_reads_as_chemfiles_reads_it() {
    let frames = same_as_chemfiles(&data("adk_open.pdb"), &data("adk_dims.dcd"));
    assert_eq!(frames, 98);
}

#[test]
fn dcd_variants_read_as_chemfiles_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let top = topology(dir.path(), 7);
    let base = Dcd {
        big: false,
        cell: Some([30.0, 0.0, 40.0, 0.0, 0.0, 50.0]),
        version: 24,
        fixed: 0,
        four_d: false,
    };
    let variants = [
        ("le_cell", base),
        ("be_cell", Dcd { big: true, ..base }),
        ("no_cell", Dcd { cell: None, ..base }),
        (
            "angles",
            Dcd {
                cell: Some([30.0, 100.0, 40.0, 80.0, 70.0, 50.0]),
                ..base
            },
        ),
        (
            "cosines",
            Dcd {
                cell: Some([30.0, 0.2, 40.0, -0.1, 0.3, 50.0]),
                ..base
            },
        ),
        (
            "matrix",
            Dcd {
                cell: Some([30.0, 1.0, 40.0, 2.0, 3.0, 50.0]),
                version: 36,
                ..base
            },
        ),
        ("fixed", Dcd { fixed: 3, ..base }),
        (
            "fixed_be",
            Dcd {
                fixed: 2,
                big: true,
                cell: None,
                ..base
            },
        ),
        (
            "four_d",
            Dcd {
                four_d: true,
                ..base
            },
        ),
        (
            "xplor",
            Dcd {
                version: 0,
                cell: None,
                ..base
            },
        ),
    ];
    for (name, spec) in variants {
        let path = dir.path().join(format!("{name}.dcd"));
        std::fs::write(&path, write_dcd(spec, 7, 4)).unwrap();
        assert_eq!(same_as_chemfiles(&top, &path), 4, "{name}");
        let t = io::open(&top, Some(&path)).unwrap();
        let f = t.read_frame(3).unwrap();
        assert_eq!(f.positions[6].x, 6.0 * 1.5 + 3.0 * 0.125, "{name}");
        assert!(f.time_ps.is_some_and(|t| t > 0.0), "{name}");
    }
}

#[test]
fn dcd_cut_or_damaged_in_frame_k_keeps_frames_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let top = data("adk_open.pdb");
    let bytes = std::fs::read(data("adk_dims.dcd")).unwrap();
    let t = io::open(&top, Some(&data("adk_dims.dcd"))).unwrap();
    // adk_dims.dcd: 3341 atoms, no cell record; frame k starts at header + k × frame bytes.
    let frame_bytes = 3 * (8 + 4 * 3341);
    let header = bytes.len() - t.len() * frame_bytes;
    let cut = dir.path().join("cut.dcd");
    std::fs::write(&cut, &bytes[..header + 5 * frame_bytes + 1000]).unwrap();
    let t = io::open(&top, Some(&cut)).unwrap();
    assert_eq!(t.len(), 5);
    let damage = t.damage().expect("damage");
    assert_eq!(damage.frame, 5);
    one_line(&damage.error, &["cut.dcd", "frame 5"]);
    one_line(&t.read_frame(5).unwrap_err(), &["cut.dcd", "frame 5"]);
    t.read_frame(4).unwrap();
    // A record marker of frame 3 overwritten.
    let mut damaged = bytes.clone();
    let at = header + 3 * frame_bytes;
    damaged[at..at + 4].copy_from_slice(&7i32.to_le_bytes());
    let bad = dir.path().join("marker.dcd");
    std::fs::write(&bad, &damaged).unwrap();
    let t = io::open(&top, Some(&bad)).unwrap();
    assert_eq!(t.len(), 3);
    one_line(
        &t.damage().unwrap().error,
        &["marker.dcd", "frame 3", "x record"],
    );
    // Cut inside frame 0: an error, no frames.
    let first = dir.path().join("first.dcd");
    std::fs::write(&first, &bytes[..header + 100]).unwrap();
    one_line(
        &io::open(&top, Some(&first)).unwrap_err(),
        &["first.dcd", "frame 0"],
    );
}

#[test]
fn dcd_hostile_headers_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let top = data("adk_open.pdb");
    let bytes = std::fs::read(data("adk_dims.dcd")).unwrap();
    let write = |name: &str, b: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, b).unwrap();
        p
    };
    let mut title = bytes.clone();
    title[96..100].copy_from_slice(&0x7fff_ffffi32.to_le_bytes());
    // A title line count of 2^31 - 1 (chemfiles: SIGSEGV): the lines are never read.
    let t = io::open(&top, Some(&write("title.dcd", &title))).unwrap();
    assert_eq!(t.len(), 98);
    // The title record's size: huge.
    let mut size = bytes.clone();
    size[92..96].copy_from_slice(&0x7fff_fff0i32.to_le_bytes());
    one_line(
        &io::open(&top, Some(&write("size.dcd", &size))).unwrap_err(),
        &["size.dcd", "title"],
    );
    // An atom count of 2^31 - 1.
    let title_len = i32::from_le_bytes(bytes[92..96].try_into().unwrap()) as usize;
    let mut atoms = bytes.clone();
    let at = 96 + title_len + 4 + 4;
    atoms[at..at + 4].copy_from_slice(&0x7fff_ffffi32.to_le_bytes());
    one_line(
        &io::open(&top, Some(&write("atoms.dcd", &atoms))).unwrap_err(),
        &["atoms.dcd", "frame 0"],
    );
    // 64-bit record markers: a clear refusal.
    let mut wide = vec![84u8, 0, 0, 0, 0, 0, 0, 0];
    wide.extend_from_slice(b"CORD");
    wide.resize(200, 0);
    one_line(
        &io::open(&top, Some(&write("wide.dcd", &wide))).unwrap_err(),
        &["wide.dcd", "64-bit"],
    );
}

/// How to write an Amber NetCDF by hand.
struct Nc {
    /// 1 (classic) or 2 (64-bit offsets).
    version: u8,
    /// Record count in the header; `None` writes the streaming value (-1).
    numrecs: Option<i32>,
    coordinates: bool,
    atoms: u32,
}

/// Writes an Amber NetCDF with `frames` frames: time (ps), coordinates, cell lengths/angles.
fn write_nc(spec: &Nc, frames: usize) -> Vec<u8> {
    fn name(out: &mut Vec<u8>, s: &str) {
        out.extend_from_slice(&(s.len() as u32).to_be_bytes());
        out.extend_from_slice(s.as_bytes());
        out.resize(out.len().div_ceil(4) * 4, 0);
    }
    fn text_attr(out: &mut Vec<u8>, key: &str, value: &str) {
        name(out, key);
        out.extend_from_slice(&2u32.to_be_bytes());
        name(out, value);
    }
    let atoms = spec.atoms;
    let mut vars: Vec<(&str, Vec<u32>, u32, u32)> = vec![
        ("time", vec![0], 5, 4),
        ("cell_lengths", vec![0, 3], 6, 24),
        ("cell_angles", vec![0, 4], 6, 24),
    ];
    if spec.coordinates {
        vars.insert(1, ("coordinates", vec![0, 2, 1], 5, 12 * atoms));
    } else {
        vars.insert(1, ("velocities", vec![0, 2, 1], 5, 12 * atoms));
    }
    let build = |begins: &[u64]| {
        let mut out = vec![b'C', b'D', b'F', spec.version];
        out.extend_from_slice(&spec.numrecs.unwrap_or(-1).to_be_bytes());
        out.extend_from_slice(&10u32.to_be_bytes());
        out.extend_from_slice(&5u32.to_be_bytes());
        for (n, len) in [
            ("frame", 0),
            ("spatial", 3),
            ("atom", atoms),
            ("cell_spatial", 3),
            ("cell_angular", 3),
        ] {
            name(&mut out, n);
            out.extend_from_slice(&len.to_be_bytes());
        }
        out.extend_from_slice(&12u32.to_be_bytes());
        out.extend_from_slice(&2u32.to_be_bytes());
        text_attr(&mut out, "Conventions", "AMBER");
        text_attr(&mut out, "ConventionVersion", "1.0");
        out.extend_from_slice(&11u32.to_be_bytes());
        out.extend_from_slice(&(vars.len() as u32).to_be_bytes());
        for (k, (n, dims, kind, size)) in vars.iter().enumerate() {
            name(&mut out, n);
            out.extend_from_slice(&(dims.len() as u32).to_be_bytes());
            dims.iter()
                .for_each(|d| out.extend_from_slice(&d.to_be_bytes()));
            out.extend_from_slice(&12u32.to_be_bytes());
            out.extend_from_slice(&1u32.to_be_bytes());
            let unit = if *n == "time" {
                "picosecond"
            } else if *n == "cell_angles" {
                "degree"
            } else {
                "angstrom"
            };
            text_attr(&mut out, "units", unit);
            out.extend_from_slice(&kind.to_be_bytes());
            out.extend_from_slice(&size.to_be_bytes());
            if spec.version == 2 {
                out.extend_from_slice(&begins[k].to_be_bytes());
            } else {
                out.extend_from_slice(&(begins[k] as u32).to_be_bytes());
            }
        }
        out
    };
    let header_len = build(&[0; 4]).len() as u64;
    let mut begins = Vec::new();
    let mut at = header_len;
    for v in &vars {
        begins.push(at);
        at += u64::from(v.3);
    }
    let record = at - header_len;
    let mut out = build(&begins);
    for k in 0..frames {
        out.extend_from_slice(&(k as f32 * 2.5 + 1.0).to_be_bytes());
        for i in 0..atoms * 3 {
            out.extend_from_slice(&(i as f32 * 0.5 - k as f32).to_be_bytes());
        }
        for v in [20.0f64 + k as f64, 30.0, 40.0, 90.0, 90.0, 120.0] {
            out.extend_from_slice(&v.to_be_bytes());
        }
    }
    assert_eq!(out.len() as u64, header_len + frames as u64 * record);
    out
}

#[test]
fn netcdf_written_by_chemfiles_reads_as_chemfiles_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let top = topology(dir.path(), 9);
    let path = dir.path().join("chem.nc");
    let mut traj = chemfiles::Trajectory::open_with_format(&path, 'w', "Amber NetCDF").unwrap();
    for k in 0..5 {
        let mut frame = chemfiles::Frame::new();
        for i in 0..9 {
            let p = [i as f64 * 1.25, k as f64 * 0.5, -(i as f64)];
            frame.add_atom(&chemfiles::Atom::new("C"), p, None);
        }
        let cell = if k == 2 {
            chemfiles::UnitCell::triclinic([20.0, 21.0, 22.0], [80.0, 95.0, 100.0])
        } else {
            chemfiles::UnitCell::new([20.0 + k as f64, 30.0, 40.0])
        };
        frame.set_cell(&cell);
        traj.write(&frame).unwrap();
    }
    drop(traj);
    assert_eq!(same_as_chemfiles(&top, &path), 5);
    let f = io::open(&top, Some(&path)).unwrap().read_frame(3).unwrap();
    assert_eq!(f.positions[8], glam::Vec3::new(10.0, 1.5, -8.0));
}

#[test]
fn netcdf_written_by_hand_cdf1_and_cdf2() {
    let dir = tempfile::tempdir().unwrap();
    let top = topology(dir.path(), 4);
    for version in [1u8, 2] {
        let spec = Nc {
            version,
            numrecs: Some(3),
            coordinates: true,
            atoms: 4,
        };
        let path = dir.path().join(format!("v{version}.nc"));
        std::fs::write(&path, write_nc(&spec, 3)).unwrap();
        let ours = io::open(&top, Some(&path)).unwrap();
        // chemfiles refuses classic (CDF-1) files ("only 64-bit netcdf3 files are supported"):
        // ours reads them, and must give what chemfiles gives for the same data as CDF-2.
        let cdf2 = dir.path().join("v2_reference.nc");
        std::fs::write(&cdf2, write_nc(&Nc { version: 2, ..spec }, 3)).unwrap();
        let theirs = io::open_via_chemfiles(&top, Some(&cdf2)).unwrap();
        assert_eq!((ours.len(), theirs.len()), (3, 3));
        for k in 0..3 {
            let (a, b) = (ours.read_frame(k).unwrap(), theirs.read_frame(k).unwrap());
            assert_eq!(a.positions, b.positions);
            assert_eq!(a.cell, b.cell);
            // chemfiles gives no time for NetCDF; ours reads the `time` variable (ps).
            assert_eq!(a.time_ps, Some(k as f64 * 2.5 + 1.0));
        }
    }
}

#[test]
fn netcdf_streaming_cut_and_hostile_files() {
    let dir = tempfile::tempdir().unwrap();
    let top = topology(dir.path(), 4);
    let write = |name: &str, b: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, b).unwrap();
        p
    };
    // numrecs = -1 (streaming): frames counted from the file size.
    let streaming = Nc {
        version: 1,
        numrecs: None,
        coordinates: true,
        atoms: 4,
    };
    let t = io::open(&top, Some(&write("stream.nc", &write_nc(&streaming, 6)))).unwrap();
    assert_eq!((t.len(), t.damage()), (6, None));
    // Cut inside frame 4 (the header announces 6).
    let full = write_nc(
        &Nc {
            numrecs: Some(6),
            ..streaming
        },
        6,
    );
    let record = 4 + 48 + 48;
    let cut = write("cut.nc", &full[..full.len() - record - 30]);
    let t = io::open(&top, Some(&cut)).unwrap();
    assert_eq!(t.len(), 4);
    one_line(&t.damage().unwrap().error, &["cut.nc", "frame 4"]);
    let stream_cut = write_nc(&streaming, 6);
    let t = io::open(
        &top,
        Some(&write("scut.nc", &stream_cut[..stream_cut.len() - 10])),
    )
    .unwrap();
    assert_eq!(t.len(), 5);
    one_line(&t.damage().unwrap().error, &["scut.nc", "frame 5"]);
    // Velocities only (sander's mdvel): refused, not atoms at the origin.
    let vel = Nc {
        coordinates: false,
        ..streaming
    };
    let e = io::open(&top, Some(&write("mdvel.nc", &write_nc(&vel, 2)))).unwrap_err();
    one_line(&e, &["mdvel.nc", "no coordinates"]);
    // Absurd atom dimension: an error, no huge allocation.
    let mut absurd = full.clone();
    let at = absurd
        .windows(8)
        .position(|w| w == b"atom\0\0\0\x04")
        .unwrap()
        + 4;
    absurd[at..at + 4].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
    one_line(
        &io::open(&top, Some(&write("absurd.nc", &absurd))).unwrap_err(),
        &["absurd.nc"],
    );
    // Absurd counts in the header lists, and every one-byte cut of the header.
    let header_len = full.len() - 6 * record;
    for at in (4..header_len).step_by(4) {
        let mut b = full.clone();
        b[at..at + 4].copy_from_slice(&0x7fff_fff0u32.to_be_bytes());
        if let Err(e) = io::open(&top, Some(&write("count.nc", &b))) {
            one_line(&e, &["count.nc"]);
        }
    }
    for len in [0, 3, 8, 40, header_len - 1] {
        let e = io::open(&top, Some(&write("short.nc", &full[..len]))).unwrap_err();
        one_line(&e, &["short.nc"]);
    }
}

/// A cut inside frame 0 names frame 0, as cuts in later frames do: where one record is larger
/// than the whole cut file, the header check called it "damaged header" and named no frame.
#[test]
fn netcdf_cut_inside_frame_0_names_frame_0() {
    let dir = tempfile::tempdir().unwrap();
    for atoms in [4, 300] {
        let top = topology(dir.path(), atoms as usize);
        let spec = Nc {
            version: 1,
            numrecs: Some(3),
            coordinates: true,
            atoms,
        };
        let full = write_nc(&spec, 3);
        let record = 4 + 12 * atoms as usize + 48;
        let cut = &full[..full.len() - 3 * record + record / 2];
        let path = dir.path().join(format!("cut{atoms}.nc"));
        std::fs::write(&path, cut).unwrap();
        let e = io::open(&top, Some(&path)).unwrap_err();
        one_line(
            &e,
            &[
                &format!("cut{atoms}.nc"),
                "frame 0",
                "ends inside this frame",
            ],
        );
    }
}

/// Opening adk_dims.dcd and reading every frame: our reader against chemfiles in this process
/// (faster than chemfiles in the reader process that `open` used before). Medians of 5,
/// printed (`--nocapture`); ours must not be more than 3× slower even on a loaded machine.
#[test]
fn dcd_reading_speed_against_chemfiles() {
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let time = |open: &dyn Fn() -> mdsurf::io::Trajectory| {
        let mut runs: Vec<f64> = (0..5)
            .map(|_| {
                let start = std::time::Instant::now();
                let t = open();
                for k in 0..t.len() {
                    std::hint::black_box(t.read_frame(k).unwrap());
                }
                start.elapsed().as_secs_f64()
            })
            .collect();
        runs.sort_by(f64::total_cmp);
        runs[2]
    };
    let ours = time(&|| io::open(&top, Some(&traj)).unwrap());
    let theirs = time(&|| io::open_via_chemfiles(&top, Some(&traj)).unwrap());
    println!(
        "adk_dims.dcd, open + 98 frames, median of 5: ours {ours:.4} s, chemfiles {theirs:.4} s"
    );
    assert!(ours < 3.0 * theirs, "ours {ours} s, chemfiles {theirs} s");
}
