//! `--color exposure` (issue 32): the picture `render` draws must be the one it draws when each
//! atom is coloured by its residue's exposure as `surface --per-residue` writes it (through
//! `--color data:FILE` with the same map and range 0 to 1), on the CPU and GPU engines, for two
//! frames of a trajectory whose exposure changes, and on a periodic membrane; and bad options
//! give one line.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Output};

use mdsurf::render::RgbaImage;

use crate::cli_common::have_gpu;
use crate::data_support::data;

fn mdsurf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(args)
        .output()
        .expect("run mdsurf")
}

fn ok(r: &Output) {
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// Writes `index,value` rows: each atom of `top` takes the exposure of its residue in frame
/// `frame` of `per_residue` (a `--per-residue` CSV).
fn atom_exposure_csv(top: &Path, per_residue: &Path, frame: &str, out: &Path) {
    let traj = mdsurf::io::open(top, None).expect("open");
    let t = traj.topology();
    let text = std::fs::read_to_string(per_residue).expect("per-residue csv");
    let mut exposure: HashMap<(String, i64, String), f64> = HashMap::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f[0] == frame {
            let key = (
                f[2].to_string(),
                f[3].parse().expect("resid"),
                f[4].to_string(),
            );
            exposure.insert(key, f[6].parse().expect("exposure"));
        }
    }
    assert!(
        exposure.len() > 100,
        "frame {frame}: {} residues",
        exposure.len()
    );
    let mut rows = String::from("index,value\n");
    for i in 0..t.len() {
        // The CSV's chain column holds the segment when there is no chain.
        let chain = match t.chains.get(i).unwrap_or("").trim() {
            "" => t.segments.get(i).unwrap_or("").trim(),
            c => c,
        };
        let key = (
            chain.to_string(),
            t.residue_ids[i],
            t.residue_names.get(i).unwrap_or("").trim().to_string(),
        );
        if let Some(e) = exposure.get(&key) {
            writeln!(rows, "{i},{e}").expect("write");
        }
    }
    std::fs::write(out, rows).expect("write atoms csv");
}

/// Pixels whose channels differ by more than 3 (of 255) between `a` and `b`.
fn differing_pixels(a: &RgbaImage, b: &RgbaImage) -> usize {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.pixels
        .chunks_exact(4)
        .zip(b.pixels.chunks_exact(4))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 3))
        .count()
}

#[test]
fn exposure_colours_are_the_per_residue_exposure_of_each_frame() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = |name: &str| dir.path().join(name).display().to_string();
    // adenylate kinase opening: the lids move, so residues' exposure changes between frames.
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let (top_s, traj_s) = (top.display().to_string(), traj.display().to_string());
    let common = ["--select", "protein", "--spacing", "1.2"];
    let mut args = vec!["surface", &top_s, &traj_s, "--frames", "0:98:97"];
    args.extend(common);
    let res = d("res.csv");
    args.extend(["--per-residue", &res, "-q"]);
    ok(&mdsurf(&args));
    let mut pictures = Vec::new();
    for frame in ["0", "97"] {
        let atoms = d(&format!("atoms{frame}.csv"));
        atom_exposure_csv(&top, Path::new(&res), frame, Path::new(&atoms));
        let data_scheme = format!("data:{atoms};range=0:1");
        for backend in ["cpu", "gpu"] {
            let mut pair = Vec::new();
            for scheme in ["exposure", data_scheme.as_str()] {
                let out = d(&format!("f{frame}_{backend}_{}.png", pair.len()));
                let mut args = vec![
                    "render",
                    &top_s,
                    &traj_s,
                    "--frame",
                    frame,
                    "--color",
                    scheme,
                    "--size",
                    "320x240",
                    "--backend",
                    backend,
                    "-o",
                    &out,
                    "-q",
                ];
                args.extend(common);
                ok(&mdsurf(&args));
                pair.push(RgbaImage::read_png(Path::new(&out)).expect("png"));
            }
            let differ = differing_pixels(&pair[0], &pair[1]);
            eprintln!("frame {frame}, {backend}: {differ} pixels differ (exposure vs data)");
            assert!(
                differ < 30,
                "frame {frame}, {backend}: exposure colours differ from the per-residue exposure in {differ} pixels"
            );
            pictures.push(pair.swap_remove(0));
        }
    }
    // The colours follow the frame: the two frames' exposure pictures differ.
    let between = differing_pixels(&pictures[0], &pictures[2]);
    assert!(between > 2000, "frames 0 and 97 differ in {between} pixels");
}

#[test]
fn periodic_exposure_colours_are_the_periodic_per_residue_exposure() {
    // The Martini bilayer, periodic: each lipid's exposure from its area over the images across
    // the faces (before, a periodic surface stayed grey).
    let dir = tempfile::tempdir().expect("tempdir");
    let d = |name: &str| dir.path().join(name).display().to_string();
    let top = data("martini_dppc_chol_bilayer.gro");
    let top_s = top.display().to_string();
    let common = [
        "--periodic",
        "--select",
        "resname DPPC CHOL",
        "--spacing",
        "2",
    ];
    let res = d("res.csv");
    let mut args = vec!["surface", &top_s, "--per-residue", &res, "-q"];
    args.extend(common);
    ok(&mdsurf(&args));
    let atoms = d("atoms.csv");
    atom_exposure_csv(&top, Path::new(&res), "0", Path::new(&atoms));
    let data_scheme = format!("data:{atoms};range=0:1");
    let mut pair = Vec::new();
    for scheme in ["exposure", data_scheme.as_str()] {
        let out = d(&format!("{}.png", pair.len()));
        let mut args = vec!["render", &top_s, "--color", scheme, "--size", "240x200"];
        args.extend(["--view", "0,0", "-o", &out, "-q"]);
        args.extend(common);
        ok(&mdsurf(&args));
        pair.push(RgbaImage::read_png(Path::new(&out)).expect("png"));
    }
    let differ = differing_pixels(&pair[0], &pair[1]);
    assert!(differ < 30, "{differ} pixels differ (exposure vs data)");
    // Coloured, not grey: the membrane seen from above has channels far apart.
    let coloured = pair[0]
        .pixels
        .chunks_exact(4)
        .filter(|p| p[..3].iter().max().unwrap_or(&0) - p[..3].iter().min().unwrap_or(&0) > 40)
        .count();
    assert!(coloured > 5000, "{coloured} coloured pixels");
}

#[test]
fn exposure_option_errors_are_one_line() {
    let pdb = data("1hpv.pdb").display().to_string();
    for (extra, expect) in [
        (vec!["--color", "exposure;range=0:1"], "exposure;range=0:1"),
        (
            vec!["--color", "exposure", "--color-range", "0:2"],
            "--color-range",
        ),
        (vec!["--color", "exposure", "--color-map", "plaid"], "plaid"),
    ] {
        let mut args = vec!["surface", pdb.as_str(), "-q"];
        args.extend(extra.iter().copied());
        let r = mdsurf(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{extra:?}: {err}");
        assert!(err.contains(expect), "{extra:?}: {err}");
    }
}
