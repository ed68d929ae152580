//! The interface takes its complex from the frame's own surface (issue 32: "interface costs the
//! two extra surfaces, no more"): on the HIV protease dimer 1hpv, [`Interface::measure_on`]
//! with the scene's surface of both chains gives what [`Interface::measure`] computes itself,
//! bitwise when A's atoms come before B's in the file, to rounding when they do not, at the
//! default parameters and under the SES preset (radii that follow exposure, refined vertices);
//! a surface of other atoms, radii or parameters is not taken.

use std::sync::Arc;

use mdsurf::measure::{CONTACT_THRESHOLD, InterfaceResult};
use mdsurf::model::{Frame, Particles, RadiusOverrides, Topology};
use mdsurf::scene::interface::{Interface, InterfaceFrame, ShownSurface};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{LayerResult, RepRequest, SceneBackend, SceneEngine};
use mdsurf::surface::{CpuEngine, Preset, RadiusSet, SurfaceEngine, SurfaceParams};

use crate::data_support::data;

const CHAIN_A: &str = "protein and chain A";
const CHAIN_B: &str = "protein and chain B";

fn dimer() -> (Topology, Arc<Frame>) {
    let traj = mdsurf::io::open(&data("1hpv.pdb"), None).expect("open 1hpv");
    let frame = traj.read_frame(0).expect("frame 0");
    (traj.topology().clone(), Arc::new(frame))
}

/// The surface representation `selection` with the defaults, or under the SES preset.
fn rep(selection: &str, ses: bool) -> Representation {
    let mut rep = Representation::new("shown", selection, RepStyle::Surface);
    if ses {
        rep.set_params(&Preset::Ses.apply(SurfaceParams::default()));
        rep.radii = RadiusSet::Ses;
        rep.vertices = Preset::Ses.vertices();
    }
    rep
}

/// A scene's layer on frame 0, with its topology atoms and particles.
struct Shown {
    layer: Arc<LayerResult>,
    atoms: Vec<u32>,
    particles: Particles,
}

impl Shown {
    /// The surface as offered to the interface, with its particles or without them (then the
    /// complex's radii are counted to check its own).
    fn offer(&self, with_particles: bool) -> ShownSurface<'_> {
        ShownSurface {
            layer: &self.layer,
            atoms: &self.atoms,
            particles: with_particles.then_some(&self.particles),
        }
    }
}

/// The scene's layer of `rep` on frame 0 (radii overridden by `overrides`), its sampled
/// density kept when `keep_density` (as `mdsurf surface --interface` keeps it).
fn shown_with(
    topology: &Topology,
    frame: &Arc<Frame>,
    rep: Representation,
    overrides: &RadiusOverrides,
    keep_density: bool,
) -> Shown {
    let mut engine = CpuEngine::new();
    engine.set_keep_density(keep_density);
    let mut scene = SceneEngine::new(SceneBackend::Host(Box::new(engine)));
    scene.reset(topology, overrides);
    let reps = [RepRequest { id: 1, rep }];
    let computed = scene
        .frame(topology, 0, frame, &reps)
        .expect("the frame computes");
    let bound = scene.layer(1).expect("bound");
    Shown {
        layer: computed.layers[0].clone(),
        atoms: bound.atoms(frame),
        particles: bound.particles().expect("built").clone(),
    }
}

/// The scene's layer of `rep` on frame 0.
fn shown_layer(topology: &Topology, frame: &Arc<Frame>, rep: Representation) -> Shown {
    shown_with(topology, frame, rep, &RadiusOverrides::default(), true)
}

/// The interface of `sides` measured on its own and with `shown` offered.
fn both_ways(
    topology: &Topology,
    frame: &Frame,
    sides: [&str; 2],
    base: &Representation,
    shown: ShownSurface<'_>,
) -> (InterfaceFrame, InterfaceFrame) {
    let overrides = RadiusOverrides::default();
    let mut own = Interface::new(topology, sides, base, &overrides, None).expect("sides bind");
    let alone = own
        .measure(topology, frame, CONTACT_THRESHOLD)
        .expect("measured");
    let offered = [shown];
    let mut taking = Interface::new(topology, sides, base, &overrides, None).expect("sides bind");
    let taken = taking
        .measure_on(topology, frame, Some(CONTACT_THRESHOLD), &offered)
        .expect("measured");
    (alone, taken)
}

/// Every number of `got` within `rel` of `want` (relative to the largest area of its kind).
fn close(want: &InterfaceResult, got: &InterfaceResult, rel: f64, what: &str) {
    let totals = [
        (want.area_a, got.area_a),
        (want.area_b, got.area_b),
        (want.area_complex, got.area_complex),
        (want.buried, got.buried),
    ];
    for (k, (w, g)) in totals.into_iter().enumerate() {
        assert!(
            (w - g).abs() <= rel * want.area_complex,
            "{what}: total {k}: {g} vs {w}"
        );
    }
    for (w, g) in [
        (&want.atoms_a_alone, &got.atoms_a_alone),
        (&want.atoms_b_alone, &got.atoms_b_alone),
        (&want.atoms_a_complex, &got.atoms_a_complex),
        (&want.atoms_b_complex, &got.atoms_b_complex),
    ] {
        assert_eq!(w.len(), g.len(), "{what}");
        let largest = w.iter().fold(0.0f64, |m, &x| m.max(x));
        for (i, (w, g)) in w.iter().zip(g).enumerate() {
            assert!(
                (w - g).abs() <= rel * largest,
                "{what}: atom {i}: {g} vs {w}"
            );
        }
    }
}

#[test]
fn the_frames_surface_of_both_chains_is_the_complex() {
    let (topology, frame) = dimer();
    for (ses, with_particles) in [(false, false), (false, true), (true, false), (true, true)] {
        let what = format!("ses {ses}, particles {with_particles}");
        let base = rep("all", ses);
        let shown = shown_layer(&topology, &frame, rep("protein", ses));
        // Chain A's atoms come first in the file: the complex is the same sum, bit for bit.
        let sides = [CHAIN_A, CHAIN_B];
        let offered = shown.offer(with_particles);
        let (alone, taken) = both_ways(&topology, &frame, sides, &base, offered);
        assert!(!alone.complex_shown);
        assert!(taken.complex_shown, "{what}: the shown surface is taken");
        assert_eq!(alone.result, taken.result, "{what}");
        assert_eq!(alone.contacts, taken.contacts, "{what}");
        assert!(
            alone.result.buried > 500.0,
            "{what}: {}",
            alone.result.buried
        );
        // B first: the same surfaces, A's per-atom areas now in another order of the sum.
        let sides = [CHAIN_B, CHAIN_A];
        let offered = shown.offer(with_particles);
        let (alone, taken) = both_ways(&topology, &frame, sides, &base, offered);
        assert!(taken.complex_shown, "{what}: B first");
        close(
            &alone.result,
            &taken.result,
            1e-6,
            &format!("{what}, B first"),
        );
    }
}

#[test]
fn a_complex_without_its_density_gives_the_same_areas_to_rounding() {
    // With the complex's density the larger side is the complex less the smaller (at the
    // defaults; the preset's radii differ between a side and the complex at the contact, so
    // there both sides are sampled either way); without it both sides are sampled.
    let (topology, frame) = dimer();
    let base = rep("all", false);
    let plain = RadiusOverrides::default();
    let kept = shown_with(&topology, &frame, rep("protein", false), &plain, true);
    let sampled = shown_with(&topology, &frame, rep("protein", false), &plain, false);
    assert!(kept.layer.output.density.is_some());
    assert!(sampled.layer.output.density.is_none());
    let (_, by_difference) = both_ways(
        &topology,
        &frame,
        [CHAIN_A, CHAIN_B],
        &base,
        kept.offer(true),
    );
    let (_, by_sampling) = both_ways(
        &topology,
        &frame,
        [CHAIN_A, CHAIN_B],
        &base,
        sampled.offer(true),
    );
    assert!(by_difference.complex_shown && by_sampling.complex_shown);
    let (d, s) = (&by_difference.result, &by_sampling.result);
    // The side that was sampled either way is the same bits; the other differs in rounding.
    let same = [d.area_a == s.area_a, d.area_b == s.area_b];
    assert_eq!(same.iter().filter(|&&x| x).count(), 1, "{same:?}");
    assert!(d != s, "the difference is not the sampled side's bits");
    close(s, d, 1e-6, "by difference");
    let residues = |f: &InterfaceFrame| -> Vec<(String, u32)> {
        f.contacts
            .iter()
            .map(|c| (format!("{:?}", c.side), c.residue.residue))
            .collect()
    };
    assert_eq!(residues(&by_difference), residues(&by_sampling));
}

#[test]
fn a_surface_of_other_atoms_radii_or_parameters_is_not_taken() {
    let (topology, frame) = dimer();
    let sides = [CHAIN_A, CHAIN_B];
    // One atom short of the complex.
    let fewer = rep("protein and not (chain B and resid 99 and name O)", false);
    // The complex's atoms, but the SES preset's radii and parameters.
    let other_params = rep("protein", true);
    // The complex under another spacing.
    let spacing = Representation {
        spacing: 0.8,
        ..rep("protein", false)
    };
    let complex_atoms = shown_layer(&topology, &frame, rep("protein", false))
        .atoms
        .len();
    let plain = RadiusOverrides::default();
    // Under the preset, the complex with its own radius for N: radii that follow exposure from
    // other radii (the particles' own radii differ from the sides').
    let own_n = RadiusOverrides::parse_all(&["N=1.4"]).expect("an override");
    for (what, shown, ses, overrides) in [
        ("fewer atoms", fewer, false, &plain),
        ("ses", other_params, false, &plain),
        ("spacing", spacing, false, &plain),
        ("other radii", rep("protein", true), true, &own_n),
    ] {
        let base = rep("all", ses);
        let shown = shown_with(&topology, &frame, shown, overrides, true);
        let missing = if what == "fewer atoms" { 1 } else { 0 };
        assert_eq!(shown.atoms.len() + missing, complex_atoms, "{what}");
        for with_particles in [false, true] {
            let offered = shown.offer(with_particles);
            let (alone, taken) = both_ways(&topology, &frame, sides, &base, offered);
            assert!(
                !taken.complex_shown,
                "{what}, particles {with_particles}: not taken"
            );
            assert_eq!(alone.result, taken.result, "{what}");
        }
    }
}

#[test]
fn without_contacts_the_areas_are_the_same_and_no_atom_is_weighed() {
    let (topology, frame) = dimer();
    let base = rep("all", false);
    let shown = shown_layer(&topology, &frame, rep("protein", false));
    let offered = [shown.offer(true)];
    let overrides = RadiusOverrides::default();
    let mut sides =
        Interface::new(&topology, [CHAIN_A, CHAIN_B], &base, &overrides, None).expect("bind");
    let with = sides
        .measure_on(&topology, &frame, Some(CONTACT_THRESHOLD), &offered)
        .expect("with contacts");
    let without = sides
        .measure_on(&topology, &frame, None, &offered)
        .expect("without contacts");
    assert!(with.complex_shown && without.complex_shown);
    assert!(!with.contacts.is_empty() && without.contacts.is_empty());
    let (w, o) = (&with.result, &without.result);
    assert_eq!(
        [w.area_a, w.area_b, w.area_complex, w.buried],
        [o.area_a, o.area_b, o.area_complex, o.buried]
    );
    assert_eq!(w.atoms_a_alone.len(), atoms_of(&topology, CHAIN_A));
    for v in [
        &o.atoms_a_alone,
        &o.atoms_b_alone,
        &o.atoms_a_complex,
        &o.atoms_b_complex,
    ] {
        assert!(v.is_empty());
    }
}

/// The number of atoms `selection` picks.
fn atoms_of(topology: &Topology, selection: &str) -> usize {
    let (_, frame) = dimer();
    let rep = rep(selection, false);
    shown_layer(topology, &frame, rep).atoms.len()
}
