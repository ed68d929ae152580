//! `--preset ses` against an independent SES program (issue 13 section 2): the Gaussian surface
//! area of every row of `tests/data/ses_reference.csv` (written by `scripts/ses_reference.py`
//! with MSMS 2.6.1: analytical solvent-excluded surface of the external surface, probe 1.4 Å,
//! Bondi radii), computed here with the whole preset (R, I, quality, refined vertices and its
//! radii) at H = 1 Å on the same atoms (the count is checked), against the SES area.
//!
//! The target, 2 % on every row, is what every row is held to. The preset was fitted on
//! the seven `fit` rows (worst 1.96 %: 5a7u +1.96 %, 1osm -1.96 %); the nine `check` rows, never
//! used in a fit (four of them added after it), come within 1.85 %. The margin is thin, so a change that moves the areas by a
//! few tenths of a per cent fails here (the previous preset, R 0.83, I 0.39, quality high with
//! mdsurf's radii, puts 5a7u at +2.9 % and 1osm at -3.0 %). The Gaussian area must also match
//! the table's own `preset_area` within 0.3 %, so the table (and the README's copy of it) says
//! what the preset gives now.

use glam::Vec3;
use mdsurf::model::{ParticleOptions, Particles, RadiusOverrides};
use mdsurf::scene::Selection;
use mdsurf::surface::{AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceParams};

use crate::data_support::{DATA, data};

/// Positions (Å) and radii (Å, the SES preset's radius set) of the atoms of `file` (in
/// tests/data) that `selection` picks.
fn atoms(file: &str, selection: &str) -> (Vec<Vec3>, Vec<f32>) {
    let traj = mdsurf::io::open(&data(file), None).expect("open test structure");
    let frame = traj.read_frame(0).expect("frame 0");
    let options = ParticleOptions {
        radius_overrides: Preset::Ses
            .radius_set()
            .with_overrides(&RadiusOverrides::default()),
        ..ParticleOptions::default()
    };
    let particles = Particles::new(traj.topology(), &frame, &options).expect("particles");
    let pos = particles.positions(&frame).expect("positions");
    let sel = Selection::parse(selection).expect("selection");
    let idx = sel.bind(traj.topology()).indices(&frame);
    let radii = particles.radii();
    (
        idx.iter().map(|&i| pos[i as usize]).collect(),
        idx.iter().map(|&i| radii[i as usize]).collect(),
    )
}

/// The target: the preset's area within 2 % of the SES area.
const TARGET: f64 = 0.02;
/// What every row is held to: the target.
const LIMIT: f64 = TARGET;

#[test]
fn ses_preset_area_is_near_the_msms_ses_area_on_every_protein() {
    let text = std::fs::read_to_string(format!("{DATA}ses_reference.csv"))
        .expect("tests/data/ses_reference.csv (scripts/ses_reference.py writes it)");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (c_name, c_file, c_sel) = (col("protein"), col("file"), col("selection"));
    let (c_atoms, c_ses, c_role) = (col("atoms"), col("ses_area_A2"), col("role"));
    let c_preset = col("preset_area_A2");
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut failures = Vec::new();
    let (mut rows, mut checks, mut within_target) = (0, 0, 0);
    let (mut smallest, mut largest) = (usize::MAX, 0);
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let (pos, radii) = atoms(f[c_file], f[c_sel]);
        let expected: usize = f[c_atoms].parse().expect("atom count");
        assert_eq!(
            pos.len(),
            expected,
            "{}: selection picks other atoms",
            f[c_name]
        );
        smallest = smallest.min(expected);
        largest = largest.max(expected);
        let ses: f64 = f[c_ses].parse().expect("SES area");
        let tabled: f64 = f[c_preset].parse().expect("preset area");
        let set = AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        };
        let out = CpuEngine::new()
            .with_vertices(Preset::Ses.vertices())
            .compute(&set, &params)
            .expect("surface");
        let dev = out.area / ses - 1.0;
        match f[c_role] {
            "fit" => {}
            "check" => checks += 1,
            other => panic!("{}: unknown role '{other}'", f[c_name]),
        }
        within_target += usize::from(dev.abs() <= TARGET);
        if dev.abs() > LIMIT {
            failures.push(format!(
                "{} ({}): {:.1} Å² vs SES {ses:.1} Å² ({:+.2} %, limit {} %)",
                f[c_name],
                f[c_role],
                out.area,
                100.0 * dev,
                100.0 * LIMIT
            ));
        }
        if (out.area / tabled - 1.0).abs() > 0.003 {
            failures.push(format!(
                "{}: {:.1} Å² where the table says {tabled:.1} Å² (rerun scripts/ses_reference.py)",
                f[c_name], out.area
            ));
        }
        rows += 1;
    }
    assert!(rows >= 7, "only {rows} proteins in the table");
    assert!(checks >= 2, "only {checks} held-out rows");
    assert!(
        smallest < 1000 && largest > 8000,
        "sizes {smallest} to {largest} atoms"
    );
    assert_eq!(
        within_target,
        rows,
        "only {within_target} of {rows} rows within {} %",
        100.0 * TARGET
    );
    assert!(failures.is_empty(), "{}", failures.join("; "));
}
