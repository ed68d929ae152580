//! `--preset ses` against an independent SES program (issue 13 section 2): the Gaussian surface
//! area of every row of `tests/data/ses_reference.csv` (written by `scripts/ses_reference.py`
//! with MSMS 2.6.1: analytical solvent-excluded surface of the external surface, probe 1.4 Å,
//! Bondi radii), computed here with the whole preset (R, I, quality, refined vertices and its
//! radii) at H = 1 Å and at H = 0.5 Å on the same atoms (the count is checked), against the
//! SES area.
//!
//! The target, 2 %, is what every row is held to at both spacings. The preset was
//! fitted on the eighteen `fit` rows at both spacings, its radii following exposure within
//! 16 Å (`scripts/ses_models.py --model exposure16`): worst 1.84 % (1osm at 1 Å). The four
//! `check` rows (proteins never in the fit) come within 1.81 % (1gbt at 0.5 Å); they were
//! printed for each model screened, so the choice of the model's form saw them, its fitted
//! values did not. A change that moves the areas by a few tenths of a per cent can fail here.
//! The Gaussian areas must also match the table's own `preset_area` columns within 0.3 %, so the
//! table (and the README's copy of it) says what the preset gives now.

use glam::Vec3;
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::selection::Selection;
use mdsurf::surface::{AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceParams};

use crate::data_support::{DATA, data};

/// Positions (Å) and radii (Å, the SES preset's radius set, exposed atoms shrunk in this frame
/// as the representation's particles get them) of the atoms of `file` (in tests/data) that
/// `selection` picks.
fn atoms(file: &str, selection: &str) -> (Vec<Vec3>, Vec<f32>) {
    let traj = mdsurf::io::open(&data(file), None).expect("open test structure");
    let frame = traj.read_frame(0).expect("frame 0");
    let options = Preset::Ses
        .radius_set()
        .particle_options(ParticleOptions::default());
    let sel = Selection::parse(selection).expect("selection");
    let idx = sel.bind(traj.topology()).indices(&frame);
    let particles =
        Particles::new_subset(traj.topology(), &frame, &options, Some(&idx)).expect("particles");
    let pos = particles.positions(&frame).expect("positions");
    let radii = particles
        .frame_radii(&pos)
        .expect("the preset's radii follow exposure");
    (pos, radii)
}

/// The target: the preset's area within 2 % of the SES area.
const TARGET: f64 = 0.02;

#[test]
fn ses_preset_area_is_near_the_msms_ses_area_on_every_protein() {
    let text = std::fs::read_to_string(format!("{DATA}ses_reference.csv"))
        .expect("tests/data/ses_reference.csv (scripts/ses_reference.py writes it)");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (c_name, c_file, c_sel) = (col("protein"), col("file"), col("selection"));
    let (c_atoms, c_ses, c_role) = (col("atoms"), col("ses_area_A2"), col("role"));
    // (spacing in Å, the table's column of the preset's area there)
    let spacings = [
        (1.0f32, col("preset_area_A2")),
        (0.5, col("preset_area_h05_A2")),
    ];
    let mut failures = Vec::new();
    let (mut rows, mut checks) = (0, 0);
    let (mut smallest, mut largest) = (usize::MAX, 0);
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let name = f[c_name];
        let (pos, radii) = atoms(f[c_file], f[c_sel]);
        let expected: usize = f[c_atoms].parse().expect("atom count");
        assert_eq!(pos.len(), expected, "{name}: selection picks other atoms");
        smallest = smallest.min(expected);
        largest = largest.max(expected);
        let ses: f64 = f[c_ses].parse().expect("SES area");
        match f[c_role] {
            "fit" => {}
            "check" => checks += 1,
            other => panic!("{name}: unknown role '{other}'"),
        }
        let set = AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        };
        for (spacing, c_preset) in spacings {
            let params = Preset::Ses.apply(SurfaceParams {
                spacing,
                ..SurfaceParams::default()
            });
            let out = CpuEngine::new()
                .with_vertices(Preset::Ses.vertices())
                .compute(&set, &params)
                .expect("surface");
            let dev = out.area / ses - 1.0;
            if dev.abs() > TARGET {
                failures.push(format!(
                    "{name} ({}, H = {spacing} Å): {:.1} Å² vs SES {ses:.1} Å² ({:+.2} %, limit {} %)",
                    f[c_role],
                    out.area,
                    100.0 * dev,
                    100.0 * TARGET
                ));
            }
            let tabled: f64 = f[c_preset].parse().expect("preset area");
            if (out.area / tabled - 1.0).abs() > 0.003 {
                failures.push(format!(
                    "{name}, H = {spacing} Å: {:.1} Å² where the table says {tabled:.1} Å² \
                     (rerun scripts/ses_reference.py)",
                    out.area
                ));
            }
        }
        rows += 1;
    }
    assert!(rows >= 7, "only {rows} proteins in the table");
    assert!(checks >= 2, "only {checks} rows checked after the fit");
    assert!(
        smallest < 1000 && largest > 8000,
        "sizes {smallest} to {largest} atoms"
    );
    assert!(failures.is_empty(), "{}", failures.join("; "));
}
