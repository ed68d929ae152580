//! Valid files as real tools write them are read (issue #29 §3): a `.gz` followed by zero
//! padding (`gzip -d` accepts it), CR-only line ends (old Mac tools) in PDB and mmCIF, also
//! compressed, a cut `.xz` trajectory that keeps its whole frames as a cut `.gz` does, and a
//! `--color data:` CSV with Latin-1 comments. Each is compared with the plain file.

use std::io::Write;
use std::path::{Path, PathBuf};

use mdsurf::io;

use crate::cli_common::mdsurf;
use crate::data_support::data;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn cr_only(bytes: &[u8]) -> Vec<u8> {
    bytes
        .iter()
        .map(|&b| if b == b'\n' { b'\r' } else { b })
        .collect()
}

/// Positions of every frame of `top` (+ `traj`).
fn frames(top: &Path, traj: Option<&Path>) -> Vec<Vec<glam::Vec3>> {
    let t = io::open(top, traj).unwrap_or_else(|e| panic!("{e}"));
    (0..t.len())
        .map(|i| t.read_frame(i).unwrap().positions)
        .collect()
}

#[test]
fn gzip_with_zero_padding_reads_like_the_plain_file() {
    let dir = tempfile::tempdir().unwrap();
    let plain = std::fs::read(data("1hpv.pdb")).unwrap();
    let mut padded = gzip(&plain);
    padded.extend([0u8; 10_000]);
    let path = write(dir.path(), "padded.pdb.gz", &padded);
    assert_eq!(frames(&path, None), frames(&data("1hpv.pdb"), None));
    // Padding followed by other bytes is damage, in one line naming the file.
    padded.extend(b"junk");
    let path = write(dir.path(), "junk.pdb.gz", &padded);
    let error = io::open(&path, None).unwrap_err().to_string();
    assert!(
        error.starts_with(&format!("{}:", path.display())) && error.contains("zero padding"),
        "{error}"
    );
}

#[test]
fn cr_only_line_ends_read_like_lf() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = std::fs::read(data("1hpv.pdb")).unwrap();
    let cif = crate::data_support::gunzipped("1gbt.cif.gz").into_bytes();
    let cases = [
        ("cr.pdb", cr_only(&pdb), data("1hpv.pdb")),
        ("cr.pdb.gz", gzip(&cr_only(&pdb)), data("1hpv.pdb")),
        ("cr.cif", cr_only(&cif), data("1gbt.cif.gz")),
    ];
    for (name, bytes, reference) in cases {
        let path = write(dir.path(), name, &bytes);
        let got = io::open(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        let want = io::open(&reference, None).unwrap();
        assert_eq!(got.topology().len(), want.topology().len(), "{name}");
        assert_eq!(got.topology().names, want.topology().names, "{name}");
        assert_eq!(frames(&path, None), frames(&reference, None), "{name}");
    }
}

#[test]
fn a_cut_xz_trajectory_keeps_its_whole_frames() {
    let dir = tempfile::tempdir().unwrap();
    let top = data("md_1u19.gro");
    let xtc = std::fs::read(data("md_1u19.xtc")).unwrap();
    let mut xz = Vec::new();
    let mut w = lzma_rust2::XzWriter::new(&mut xz, lzma_rust2::XzOptions::with_preset(1)).unwrap();
    w.write_all(&xtc).unwrap();
    w.finish().unwrap();
    let cut_at = xz.len() * 2 / 5;
    let xz_path = write(dir.path(), "cut.xtc.xz", &xz[..cut_at]);
    let gz = gzip(&xtc);
    let gz_path = write(dir.path(), "cut.xtc.gz", &gz[..gz.len() * 2 / 5]);
    let from_xz = io::open(&top, Some(&xz_path)).expect("a cut .xz opens");
    let from_gz = io::open(&top, Some(&gz_path)).expect("a cut .gz opens");
    assert!(from_xz.len() >= 5, "only {} frames kept", from_xz.len());
    let damage = from_xz.damage().expect("the cut is damage");
    assert_eq!(damage.frame, from_xz.len());
    let whole = frames(&top, Some(&data("md_1u19.xtc")));
    for (i, frame) in frames(&top, Some(&xz_path)).iter().enumerate() {
        assert_eq!(frame, &whole[i], "frame {i}");
    }
    // Both decoders keep about the same share of the file (the cut is at 40 % of each).
    let (x, g) = (from_xz.len() as i64, from_gz.len() as i64);
    assert!((x - g).abs() <= whole.len() as i64 / 4, "xz {x}, gz {g}");
}

#[test]
fn a_data_csv_with_latin1_comments_colours() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "data.csv",
        b"# r\xe9sidus expos\xe9s (Latin-1)\n0,1.5\n1,2.5\n",
    );
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &data("1hpv.pdb").to_string_lossy(),
            "-q",
            "--backend",
            "cpu",
            "--color",
            "data:data.csv",
            "--stats",
            "s.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(dir.path().join("s.csv").is_file());
}
