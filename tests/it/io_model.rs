//! The model layer on real files: element guessing and radii (DESIGN section 2), residue beads,
//! colour schemes and user radius overrides, as the surface engines receive them.

use crate::data_support::data;

use mdsurf::io::{self, Trajectory};
use mdsurf::model::{ColorScheme, ParticleOptions, Particles, RadiusOverrides};

fn open(top: &str) -> Trajectory {
    io::open(&data(top), None).unwrap_or_else(|e| panic!("{e}"))
}

fn particles(t: &Trajectory, options: &ParticleOptions) -> Particles {
    let first = t.read_frame(0).expect("frame 0");
    Particles::new(t.topology(), &first, options).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn protein_radii_follow_the_element_table() {
    let t = open("adk_open.pdb");
    let top = t.topology();
    let expected = |e: &str| match e {
        "H" => 1.0,
        "C" => 1.5,
        "N" => 1.4,
        "O" => 1.3,
        "S" => 1.9,
        _ => panic!("unexpected element {e} in adk"),
    };
    for i in 0..top.len() {
        assert_eq!(
            top.radii[i],
            expected(&top.elements[i]),
            "atom {} {}",
            i,
            &top.names[i]
        );
        let first = top.names[i]
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .chars()
            .next();
        assert_eq!(
            first.map(String::from),
            Some(top.elements[i].to_string()),
            "{}",
            &top.names[i]
        );
    }
    assert!(top.elements.iter().any(|e| e == "S"), "MET/CYS sulphur");
}

#[test]
fn martini_bilayer_is_beads() {
    let t = open("martini_dppc_chol_bilayer.gro");
    let p = particles(&t, &ParticleOptions::default());
    assert_eq!(p.len(), 5040);
    assert!(p.radii().iter().all(|&r| (r - 2.35).abs() < 1e-6));
}

#[test]
fn beads_cut_a_protein_by_an_order_of_magnitude() {
    let t = open("adk_open.pdb");
    let atoms = t.topology().len();
    let options = ParticleOptions {
        beads: true,
        ..Default::default()
    };
    let p = particles(&t, &options);
    assert!(p.is_beads());
    assert_eq!(p.len(), t.topology().residue_count());
    let ratio = atoms as f64 / p.len() as f64;
    assert!(
        (8.0..25.0).contains(&ratio),
        "{atoms} atoms -> {} beads",
        p.len()
    );
    // Each bead sits at its residue's mean and reaches its farthest atom plus 1 Å.
    let frame = t.read_frame(0).expect("frame");
    let centres = p.positions(&frame).expect("bead positions");
    let model = p.bead_model().expect("beads");
    for b in [0, p.len() / 2, p.len() - 1] {
        let group = model.atoms_of(b);
        let mean = group
            .iter()
            .map(|&i| frame.positions[i as usize])
            .sum::<glam::Vec3>()
            / group.len() as f32;
        assert!((centres[b] - mean).length() < 1e-3, "bead {b}");
        let reach = group
            .iter()
            .map(|&i| (frame.positions[i as usize] - mean).length())
            .fold(0.0, f32::max);
        assert!((p.radii()[b] - (reach + 1.0)).abs() < 1e-3, "bead {b}");
    }
    // Beads follow the trajectory.
    let later = io::open(&data("adk_open.pdb"), Some(&data("adk_dims.dcd"))).expect("dcd");
    let f = later.read_frame(97).expect("last frame");
    assert_eq!(p.positions(&f).expect("positions").len(), p.len());
}

#[test]
fn radius_overrides_by_element_and_by_type() {
    let t = open("adk_open.pdb");
    let overrides = RadiusOverrides::parse_all(&["C=1.7"]).expect("parse");
    let p = particles(
        &t,
        &ParticleOptions {
            radius_overrides: overrides,
            ..Default::default()
        },
    );
    let top = t.topology();
    for i in 0..top.len() {
        let want = if &top.elements[i] == "C" {
            1.7
        } else {
            top.radii[i]
        };
        assert_eq!(p.radii()[i], want, "atom {i}");
    }
    let t = open("spce_all_coords.lammpstrj.bz2");
    let overrides = RadiusOverrides::parse_all(&["2=1.2"]).expect("parse");
    let p = particles(
        &t,
        &ParticleOptions {
            radius_overrides: overrides,
            ..Default::default()
        },
    );
    let names = &t.topology().names;
    let type2 = names.iter().filter(|n| *n == "2").count();
    assert!(
        type2 > 0 && type2 < names.len(),
        "LAMMPS types: {type2} of type 2"
    );
    for (i, name) in names.iter().enumerate() {
        let want = if name == "2" {
            1.2
        } else {
            t.topology().radii[i]
        };
        assert_eq!(p.radii()[i], want);
    }
    assert!(RadiusOverrides::parse_all(&["C=1.7", "C=-2"]).is_err());
}

fn distinct(colours: &[[f32; 3]]) -> usize {
    let mut keys: Vec<[u32; 3]> = colours.iter().map(|c| c.map(f32::to_bits)).collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

#[test]
fn colour_schemes_on_a_real_protein() {
    let t = open("1hpv.pdb");
    let top = t.topology();
    let colours = |s: &str| s.parse::<ColorScheme>().expect(s).atom_colours(top);
    let n = top.len();
    // Chains A and B (and the ligand) get different colours.
    let chain = colours("chain");
    let a = top.chains.iter().position(|c| c == "A").expect("chain A");
    let b = top.chains.iter().position(|c| c == "B").expect("chain B");
    assert_ne!(chain[a], chain[b]);
    // Element: carbon and oxygen differ; every carbon looks the same.
    let element = colours("element");
    let c = top.elements.iter().position(|e| e == "C").expect("carbon");
    let o = top.elements.iter().position(|e| e == "O").expect("oxygen");
    assert_ne!(element[c], element[o]);
    assert!(
        (0..n)
            .filter(|&i| &top.elements[i] == "C")
            .all(|i| element[i] == element[c])
    );
    // Residue type: acids are red, bases blue.
    let restype = colours("residue-type");
    let asp = top
        .residue_names
        .iter()
        .position(|r| r == "ASP")
        .expect("ASP");
    let lys = top
        .residue_names
        .iter()
        .position(|r| r == "LYS")
        .expect("LYS");
    assert!(restype[asp][0] > restype[asp][2] && restype[lys][2] > restype[lys][0]);
    // Rainbow: first residue blue, last residue red.
    let rainbow = colours("rainbow");
    assert!(rainbow[0][2] > rainbow[0][0] && rainbow[n - 1][0] > rainbow[n - 1][2]);
    // B-factor: many distinct shades; single: one.
    assert!(distinct(&colours("b-factor")) > 20);
    assert_eq!(distinct(&colours("single:#336699")), 1);
    assert!(colours("#ffffff").iter().all(|c| *c == [1.0, 1.0, 1.0]));
    for c in chain.iter().chain(&element).chain(&restype).chain(&rainbow) {
        assert!(c.iter().all(|v| (0.0..=1.0).contains(v)), "{c:?}");
    }
    // Recolouring particles keeps radii and count.
    let mut p = particles(&t, &ParticleOptions::default());
    let radii = p.radii().to_vec();
    p.set_colours(top, ColorScheme::Chain);
    assert_eq!(p.colours(), chain.as_slice());
    assert_eq!(p.radii(), radii.as_slice());
    let frame = t.read_frame(0).expect("frame");
    let positions = p.positions(&frame).expect("positions");
    let set = p.atom_set(&positions);
    assert_eq!(set.positions.len(), set.radii.len());
    assert_eq!(set.colours.map(<[_]>::len), Some(n));
}

#[test]
fn untyped_particles_get_a_radius_from_their_spacing() {
    // SPC/E water as LAMMPS types: type 1 (oxygen) sits about 2.8 Å from the next oxygen.
    let t = open("spce_all_coords.lammpstrj.bz2");
    let top = t.topology();
    let radius_of = |name: &str| top.radii[top.names.iter().position(|n| n == name).expect(name)];
    let (r1, r2) = (radius_of("1"), radius_of("2"));
    println!("LAMMPS SPC/E fitted radii: type 1 {r1} Å, type 2 {r2} Å");
    assert!((1.2..1.6).contains(&r1), "type 1 (water oxygen): {r1} Å");
    assert!(r2 < r1, "type 2 (hydrogen) packs closer: {r2} Å");
    assert!(
        (0..top.len()).all(|i| top.radii[i] == radius_of(&top.names[i])),
        "one radius per type"
    );
}
