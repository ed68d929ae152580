//! The Rust XTC (molly) and TRR readers against chemfiles' C decoder on the same files: every
//! frame's positions (Å), box and time agree.

use chemfiles::Trajectory as ChemTrajectory;
use glam::Vec3;
use mdsurf::io;

use crate::data_support::data;

/// Positions (Å), box lengths (Å) and time (ps) of every frame, read by chemfiles.
fn chemfiles_frames(path: &std::path::Path) -> Vec<(Vec<Vec3>, [f64; 3], f64)> {
    let mut t = ChemTrajectory::open(path, 'r').expect("chemfiles opens it");
    let mut frame = chemfiles::Frame::new();
    let mut out = Vec::new();
    for step in 0..t.nsteps() {
        t.read_step(step, &mut frame).unwrap();
        let positions = frame
            .positions()
            .iter()
            .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect();
        let time = match frame.get("time") {
            Some(chemfiles::Property::Double(t)) => t,
            _ => f64::NAN,
        };
        out.push((positions, frame.cell().lengths(), time));
    }
    out
}

fn assert_same_frames(top: &str, traj: &std::path::Path, reference: &std::path::Path) {
    let ours = io::open(&data(top), Some(traj)).expect("opens");
    let theirs = chemfiles_frames(reference);
    assert_eq!(ours.len(), theirs.len());
    for (k, (positions, lengths, time)) in theirs.iter().enumerate() {
        let f = ours.read_frame(k).unwrap();
        let worst = f
            .positions
            .iter()
            .zip(positions)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "frame {k}: positions differ by {worst} Å");
        let cell = f.cell.expect("a box");
        for axis in 0..3 {
            assert!(
                (cell[axis].length() as f64 - lengths[axis]).abs() < 1e-3,
                "frame {k}"
            );
        }
        assert!((f.time_ps.unwrap() - time).abs() < 1e-3, "frame {k}: time");
    }
}

#[test]
fn xtc_frames_equal_chemfiles() {
    let xtc = data("md_1u19.xtc");
    assert_same_frames("md_1u19.gro", &xtc, &xtc);
}

#[test]
fn gzipped_xtc_reads_the_same_frames() {
    let dir = tempfile::tempdir().unwrap();
    let gz = dir.path().join("md.xtc.gz");
    let mut encoder = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::fast(),
    );
    std::io::Write::write_all(&mut encoder, &std::fs::read(data("md_1u19.xtc")).unwrap()).unwrap();
    encoder.finish().unwrap();
    assert_same_frames("md_1u19.gro", &gz, &data("md_1u19.xtc"));
}

#[test]
fn trr_frames_equal_chemfiles() {
    // A TRR written by chemfiles from the XTC's frames (single precision, box and positions).
    let dir = tempfile::tempdir().unwrap();
    let trr = dir.path().join("md.trr");
    {
        let mut input = ChemTrajectory::open(data("md_1u19.xtc"), 'r').unwrap();
        let mut output = ChemTrajectory::open(&trr, 'w').unwrap();
        let mut frame = chemfiles::Frame::new();
        for step in 0..5 {
            input.read_step(step, &mut frame).unwrap();
            output.write(&frame).unwrap();
        }
    }
    assert_same_frames("md_1u19.gro", &trr, &trr);
    let read = io::open(&data("md_1u19.gro"), Some(&trr)).unwrap();
    assert_eq!(read.len(), 5);
}
