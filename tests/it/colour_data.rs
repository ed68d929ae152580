//! `--color data:FILE.csv` end to end through `mdsurf surface`: values per atom and per frame
//! through the colour maps (and grey where an atom has no value), the B-factors of each model of
//! a multi-model PDB per frame, and bad files refused with one line naming the file and line.

use std::fs;
use std::path::Path;

use mdsurf::model::ColourMap;
use mdsurf::model::colour_map::NO_VALUE_GREY;

use crate::cli_common::mdsurf;

/// A PDB atom record at `x` Å with B-factor `b`.
fn atom(serial: usize, x: f32, b: f32) -> String {
    format!(
        "ATOM  {serial:>5}  O   HOH A{serial:>4}    {x:>8.3}{:>8.3}{:>8.3}  1.00{b:>6.2}           O",
        0.0, 0.0
    )
}

/// Two oxygen atoms 20 Å apart, in `models` models (B-factors 10 then 90 for atom 0).
fn write_pdb(path: &Path, models: usize) {
    let mut text = String::new();
    for m in 0..models {
        text += &format!("MODEL     {:>4}\n", m + 1);
        text += &atom(1, 0.0, if m == 0 { 10.0 } else { 90.0 });
        text += "\n";
        text += &atom(2, 20.0, 50.0);
        text += "\nENDMDL\n";
    }
    text += "END\n";
    fs::write(path, text).unwrap();
}

/// Vertex x and sRGB colour of a binary PLY written by mdsurf (x y z nx ny nz f32, r g b u8).
fn ply_colours(path: &Path) -> Vec<(f32, [u8; 3])> {
    let bytes = fs::read(path).unwrap();
    let end = b"end_header\n";
    let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&bytes[..at]);
    let n: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    (0..n)
        .map(|i| {
            let v = &bytes[at + i * 27..at + (i + 1) * 27];
            let x = f32::from_le_bytes(v[0..4].try_into().unwrap());
            (x, [v[24], v[25], v[26]])
        })
        .collect()
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(&x, y)| (x as i32 - y as i32).abs() <= 3)
}

fn srgb(linear: [f32; 3]) -> [u8; 3] {
    linear.map(mdsurf::export::linear_to_srgb8)
}

#[test]
fn values_per_atom_and_per_frame_colour_the_surface_and_missing_atoms_are_grey() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_pdb(&d.join("two.pdb"), 1);
    fs::write(d.join("q.csv"), "index,value\n0,1.0\n").unwrap();
    let run = mdsurf(
        d,
        &[
            "surface",
            "two.pdb",
            "--backend",
            "cpu",
            "--spacing",
            "0.5",
            "--color",
            "data:q.csv",
            "--color-map",
            "bwr",
            "--color-range",
            "-1:1",
            "-q",
            "-o",
            "a.ply",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let red = ColourMap::BlueWhiteRed.srgb8(1.0);
    let grey = srgb(NO_VALUE_GREY);
    let verts = ply_colours(&d.join("a.ply"));
    assert!(
        verts.iter().filter(|v| v.0 < 10.0).all(|v| close(v.1, red)),
        "{red:?}"
    );
    assert!(
        verts
            .iter()
            .filter(|v| v.0 > 10.0)
            .all(|v| close(v.1, grey))
    );

    // Per frame: a 2-model file, atom 0 low (0) in frame 0 and high (1) in frame 1, viridis.
    write_pdb(&d.join("two2.pdb"), 2);
    fs::write(
        d.join("f.csv"),
        "frame,index,value\n0,0,0\n0,1,0.5\n1,0,1\n1,1,0.5\n",
    )
    .unwrap();
    let run = mdsurf(
        d,
        &[
            "surface",
            "two2.pdb",
            "--backend",
            "cpu",
            "--spacing",
            "0.5",
            "--color",
            "data:f.csv",
            "-q",
            "-o",
            "f_{frame}.ply",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    for (f, t) in [(0, 0.0), (1, 1.0)] {
        let verts = ply_colours(&d.join(format!("f_{f}.ply")));
        let want = ColourMap::Viridis.srgb8(t);
        assert!(
            verts
                .iter()
                .filter(|v| v.0 < 10.0)
                .all(|v| close(v.1, want)),
            "frame {f}: {:?} vs {want:?}",
            verts[0].1
        );
    }
}

#[test]
fn b_factor_of_each_model_colours_its_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_pdb(&d.join("m.pdb"), 2);
    let run = mdsurf(
        d,
        &[
            "surface",
            "m.pdb",
            "--backend",
            "cpu",
            "--spacing",
            "0.5",
            "--color",
            "b-factor",
            "-q",
            "-o",
            "b_{frame}.ply",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    // Range 10..90 over both models, blue-white-red: atom 0 is blue in model 1, red in model 2.
    let atom0 = |f: usize| ply_colours(&d.join(format!("b_{f}.ply")))[0].1;
    assert!(
        close(atom0(0), ColourMap::BlueWhiteRed.srgb8(0.0)),
        "{:?}",
        atom0(0)
    );
    assert!(
        close(atom0(1), ColourMap::BlueWhiteRed.srgb8(1.0)),
        "{:?}",
        atom0(1)
    );
}

#[test]
fn bad_data_files_give_one_line_naming_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_pdb(&d.join("m.pdb"), 2);
    let cases = [
        (
            "index,value\n0,1\n7,2\n",
            "bad.csv:3: atom index 7 is not in the topology",
        ),
        (
            "index,value\n0,1\n1,high\n",
            "bad.csv:3: value 'high' is not a finite number",
        ),
        (
            "frame,index,value\n0,0,1\n2,0,1\n",
            "bad.csv:3: frame 2 follows frame 0: frame 1 is missing",
        ),
        (
            "frame,index,value\n0,0,1\n0,1,1\n",
            "bad.csv: no values for frame 1",
        ),
    ];
    for (text, want) in cases {
        fs::write(d.join("bad.csv"), text).unwrap();
        let run = mdsurf(
            d,
            &[
                "surface",
                "m.pdb",
                "--backend",
                "cpu",
                "--color",
                "data:bad.csv",
                "-q",
            ],
        );
        assert_eq!(run.code, 2, "{text:?}: {}", run.stderr);
        assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
        assert!(run.stderr.contains(want), "{text:?}: {}", run.stderr);
    }
    let run = mdsurf(d, &["surface", "m.pdb", "--color", "data:nope.csv", "-q"]);
    assert!(
        run.last_line().contains("nope.csv: cannot read"),
        "{}",
        run.stderr
    );
}
