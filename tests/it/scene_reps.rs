//! Representations as a user meets them: the default representations of real systems (the
//! protein of adk in water, not its water box), `--select`, `--state`, the `rep` column and
//! `{rep}` outputs of `mdsurf surface`, state files written by the viewer's code and read by
//! the headless commands, sticks that draw only real bonds, and the viewer core recomputing
//! only the representation that changed.

use std::fs;
use std::sync::Arc;
use std::time::Duration;

use mdsurf::app::source::helix_source;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Command};
use mdsurf::io;
use mdsurf::model::{ColorScheme, RadiusOverrides};
use mdsurf::scene::defaults::default_representations;
use mdsurf::scene::layer::{Layer, MAX_FILE_BOND};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;
use mdsurf::surface::CpuEngine;

use crate::cli_common::{Csv, mdsurf};
use crate::data_support::data;

fn path(name: &str) -> String {
    data(name).to_string_lossy().into_owned()
}

/// The default view of adk in a water box computes the protein, not the box: its area is that
/// of the protein alone (written to a file of its own and surfaced whole) within 1 %, the
/// water and ions exist as a hidden representation, and stderr lists the representations.
#[test]
fn adk_in_water_shows_the_protein_not_the_box() {
    let dir = tempfile::tempdir().unwrap();
    let gro = path("adk_oplsaa.gro");
    let r = mdsurf(
        dir.path(),
        &[
            "surface",
            &gro,
            "--stats",
            "default.csv",
            "--backend",
            "cpu",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("rep macromolecule: surface of 'protein or nucleic' (3341 atoms)"),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr.contains("rep solvent:") && r.stderr.contains("hidden"),
        "{}",
        r.stderr
    );
    let csv = Csv::read(&dir.path().join("default.csv"));
    assert_eq!(
        csv.text_col("rep"),
        ["macromolecule"],
        "only visible surfaces are computed"
    );
    assert_eq!(csv.col("atoms"), [3341.0]);
    let area = csv.col("area_A2")[0];

    // The protein alone, in its own file, as a surface of everything.
    let trajectory = io::open(&data("adk_oplsaa.gro"), None).unwrap();
    let top = trajectory.topology();
    let mut frame = trajectory.read_frame(0).unwrap();
    // The default view makes molecules whole (the protein is split across the box here).
    mdsurf::transform::TransformChain::new(&Default::default(), top, &frame.clone(), None, "adk")
        .unwrap()
        .apply(&mut frame)
        .unwrap();
    let protein = mdsurf::selection::Selection::parse("protein")
        .unwrap()
        .bind(top)
        .indices(&frame);
    let mut f = chemfiles::Frame::new();
    for &i in &protein {
        let p = frame.positions[i as usize];
        let mut atom = chemfiles::Atom::new(&top.names[i as usize]);
        atom.set_atomic_type(&top.elements[i as usize]);
        f.add_atom(&atom, [p.x as f64, p.y as f64, p.z as f64], None);
    }
    let alone = dir.path().join("protein.xyz");
    chemfiles::Trajectory::open(&alone, 'w')
        .unwrap()
        .write(&f)
        .unwrap();
    let r = mdsurf(
        dir.path(),
        &[
            "surface",
            "protein.xyz",
            "--select",
            "all",
            "--stats",
            "alone.csv",
            "--backend",
            "cpu",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let alone = Csv::read(&dir.path().join("alone.csv")).col("area_A2")[0];
    assert!(
        (area - alone).abs() / alone < 0.01,
        "default view area {area} vs protein alone {alone}"
    );
}

#[test]
fn select_gives_one_rep_per_frame_row_and_state_gives_its_reps() {
    let dir = tempfile::tempdir().unwrap();
    let (top, traj) = (path("adk_open.pdb"), path("adk_dims.dcd"));
    let r = mdsurf(
        dir.path(),
        &[
            "surface",
            &top,
            &traj,
            "--frames",
            "0:2",
            "--select",
            "resid 1 to 50",
            "--stats",
            "sel.csv",
            "--spacing",
            "1.5",
            "-q",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let csv = Csv::read(&dir.path().join("sel.csv"));
    assert_eq!(csv.columns[..3], ["frame", "rep", "time_ps"]);
    assert_eq!(csv.text_col("rep"), ["selection", "selection"]);
    let atoms = csv.col("atoms");
    assert!(atoms[0] > 500.0 && atoms[0] < 1000.0, "{atoms:?}");

    // A state file with two surfaces and a hidden one: one row per frame and visible surface,
    // one mesh per frame and surface through {rep}.
    let state = StateFile::new(vec![
        Representation::new("core", "resid 1 to 50", RepStyle::Surface),
        Representation {
            spacing: 2.0,
            ..Representation::new("lid", "resid 122 to 159", RepStyle::Beads)
        },
        Representation {
            visible: false,
            ..Representation::new("rest", "all", RepStyle::Surface)
        },
        Representation::new("sticks", "resid 10", RepStyle::Sticks),
    ]);
    state.save(&dir.path().join("view.toml")).unwrap();
    let r = mdsurf(
        dir.path(),
        &[
            "surface",
            &top,
            &traj,
            "--frames",
            "0:2",
            "--state",
            "view.toml",
            "--stats",
            "state.csv",
            "-o",
            "m_{rep}_{frame}.ply",
            "-q",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let csv = Csv::read(&dir.path().join("state.csv"));
    assert_eq!(csv.text_col("rep"), ["core", "lid", "core", "lid"]);
    assert_eq!(csv.col("frame"), [0.0, 0.0, 1.0, 1.0]);
    let lid_beads = csv.col("atoms")[1];
    assert_eq!(lid_beads, 38.0, "one bead per residue of 122..159");
    for name in ["m_core_0.ply", "m_lid_0.ply", "m_core_1.ply", "m_lid_1.ply"] {
        assert!(dir.path().join(name).is_file(), "{name} missing");
    }
    // Without {rep}, two surfaces cannot share one output name.
    let r = mdsurf(
        dir.path(),
        &["surface", &top, "--state", "view.toml", "-o", "one.ply"],
    );
    assert_eq!(r.code, 2);
    assert!(r.last_line().contains("{rep}"), "{}", r.stderr);
}

#[test]
fn bad_selections_and_states_fail_in_one_line_and_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let top = path("adk_open.pdb");
    fs::write(dir.path().join("keep.csv"), "old").unwrap();
    let r = mdsurf(
        dir.path(),
        &[
            "surface",
            &top,
            "--select",
            "resid 1 to",
            "--stats",
            "keep.csv",
        ],
    );
    assert_eq!(r.code, 2);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(r.stderr.contains("column"), "{}", r.stderr);
    assert_eq!(
        fs::read_to_string(dir.path().join("keep.csv")).unwrap(),
        "old"
    );

    let r = mdsurf(dir.path(), &["surface", &top, "--select", "resname XYZ"]);
    assert_eq!(r.code, 2);
    assert!(r.last_line().contains("matches no atom"), "{}", r.stderr);

    fs::write(
        dir.path().join("bad.toml"),
        "version = 1\n[[representation]]\nname = \"p\"\nselection = \"protein and (\"\n",
    )
    .unwrap();
    let r = mdsurf(
        dir.path(),
        &["render", &top, "--state", "bad.toml", "-o", "x.png"],
    );
    assert_eq!(r.code, 2);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(
        r.stderr.contains("bad.toml") && r.stderr.contains("representation 'p'"),
        "{}",
        r.stderr
    );
    assert!(!dir.path().join("x.png").exists());
}

/// Sticks draw only bonds a chemist would: 1hpv's CONECT records and bonds the topology
/// lists are kept only between atoms that are bonded in space (no fan of nanometre-long
/// sticks through the protein).
#[test]
fn sticks_draw_only_real_bonds() {
    let trajectory = io::open(&data("1hpv.pdb"), None).unwrap();
    let top = trajectory.topology();
    let frame = trajectory.read_frame(0).unwrap();
    let rep = Representation::new("sticks", "all", RepStyle::Sticks);
    let mut layer = Layer::new(rep, top, &RadiusOverrides::default()).unwrap();
    let lf = layer.frame(top, &frame).unwrap();
    assert!(lf.bonds.len() > 1000, "only {} bonds", lf.bonds.len());
    let longest = lf
        .bonds
        .iter()
        .map(|&[a, b]| lf.positions[a as usize].distance(lf.positions[b as usize]))
        .fold(0.0f32, f32::max);
    assert!(longest <= MAX_FILE_BOND, "a {longest} Å bond is drawn");
    // The ligand's own bonds are there (it is what ball-and-stick shows by default).
    let mut ligand = Layer::new(
        Representation::new("ligand", "ligand", RepStyle::BallAndStick),
        top,
        &RadiusOverrides::default(),
    )
    .unwrap();
    let lf = ligand.frame(top, &frame).unwrap();
    assert!(lf.positions.len() > 20 && lf.bonds.len() >= lf.positions.len() - 1);
}

/// Every CONECT record of 1hpv (serials mapped to atoms through the ATOM/HETATM serial column,
/// past the TER records that take serials of their own) is a bond of the topology, and every
/// topology bond touching the inhibitor is one of its CONECT bonds.
#[test]
fn conect_records_join_the_atoms_they_name() {
    let text = fs::read_to_string(data("1hpv.pdb")).unwrap();
    let mut serial_to_index = std::collections::HashMap::new();
    let mut conect = std::collections::HashSet::new();
    for line in text.lines() {
        if line.starts_with("ATOM") || line.starts_with("HETATM") {
            let serial: i64 = line[6..11].trim().parse().unwrap();
            let n = serial_to_index.len() as u32;
            serial_to_index.insert(serial, n);
        }
    }
    for line in text.lines().filter(|l| l.starts_with("CONECT")) {
        let field = |k: usize| -> Option<u32> {
            let f = line.get(6 + 5 * k..11 + 5 * k)?.trim();
            serial_to_index.get(&f.parse::<i64>().ok()?).copied()
        };
        let a = field(0).unwrap();
        for k in 1..5 {
            if let Some(b) = field(k) {
                conect.insert([a.min(b), a.max(b)]);
            }
        }
    }
    assert!(conect.len() > 30);
    let trajectory = io::open(&data("1hpv.pdb"), None).unwrap();
    let bonds: std::collections::HashSet<[u32; 2]> = trajectory
        .topology()
        .bonds
        .iter()
        .map(|&[a, b]| [a.min(b), a.max(b)])
        .collect();
    let missing: Vec<_> = conect.iter().filter(|b| !bonds.contains(*b)).collect();
    assert!(missing.is_empty(), "CONECT bonds missing: {missing:?}");
    let ligand_start = serial_to_index[&1519];
    let stray: Vec<_> = bonds
        .iter()
        .filter(|b| b[1] >= ligand_start && !conect.contains(*b))
        .collect();
    assert!(
        stray.is_empty(),
        "bonds to the inhibitor not in its CONECT records: {stray:?}"
    );
}

#[test]
fn defaults_fit_the_system() {
    let base = Representation::default();
    let names = |file: &str| -> Vec<(String, RepStyle, bool)> {
        let t = io::open(&data(file), None).unwrap();
        let f = t.read_frame(0).unwrap();
        default_representations(t.topology(), &f, &base)
            .into_iter()
            .map(|r| (r.name, r.style, r.visible))
            .collect()
    };
    use RepStyle::*;
    assert_eq!(
        names("1hpv.pdb"),
        [
            ("macromolecule".into(), Surface, true),
            ("ligand".into(), BallAndStick, true),
            ("solvent".into(), Surface, false)
        ]
    );
    let yiip = names("YiiP_lipids.gro.gz");
    assert_eq!(yiip[0], ("macromolecule".into(), Surface, true));
    assert_eq!(yiip[1], ("lipids".into(), Surface, true));
    assert_eq!(yiip.last().unwrap().0, "solvent");
    assert_eq!(
        names("martini_dppc_chol_bilayer.gro")[0],
        ("lipids".into(), Surface, true)
    );
    // No class at all: one surface of everything.
    assert_eq!(
        names("argon_npt_compressed.tng"),
        [("all".into(), Surface, true)]
    );
}

/// The viewer core: a colour change to one representation recomputes that one only; the
/// other is reused; a deleted representation disappears from the next frame.
#[test]
fn viewer_recomputes_only_the_changed_representation() {
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.set_source(Arc::new(helix_source(20, 3)));
    assert_eq!(core.reps.len(), 1, "{:?}", core.reps);
    core.apply(Command::AddRep);
    let mut second = core.reps[1].clone();
    second.selection = "resid 1 to 5".into();
    core.apply(Command::UpdateRep(1, Box::new(second)));
    assert!(core.wait_idle(Duration::from_secs(60)));
    let c = &core.shown.as_ref().unwrap().computed;
    assert_eq!(c.layers.len(), 2);
    assert_eq!(c.layers[1].particles.positions.len(), 15);
    let first_area = c.layers[0].output.area;

    core.apply(Command::SelectRep(1));
    core.apply(Command::SetColours(ColorScheme::ResidueIndex));
    assert!(core.wait_idle(Duration::from_secs(60)));
    let c = &core.shown.as_ref().unwrap().computed;
    assert!(
        c.layers[0].reused,
        "the unchanged representation was recomputed"
    );
    assert!(!c.layers[1].reused, "the changed one was not recomputed");
    assert_eq!(c.layers[0].output.area, first_area);
    assert_eq!(core.history.reps().len(), 2);

    core.apply(Command::DeleteRep(0));
    assert!(core.wait_idle(Duration::from_secs(60)));
    let c = &core.shown.as_ref().unwrap().computed;
    assert_eq!(c.layers.len(), 1);
    assert_eq!(c.layers[0].particles.positions.len(), 15);
}

/// `-q` prints nothing on success: no engine choice, no representation list, no summary.
#[test]
fn quiet_surface_prints_nothing_on_success() {
    let dir = tempfile::tempdir().unwrap();
    let gro = path("md_1u19.gro");
    let r = mdsurf(dir.path(), &["surface", &gro, "--spacing", "2", "-q"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stderr, "", "-q printed something");
}
