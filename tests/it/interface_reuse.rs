//! The sides of an interface under refined vertices take the complex's vertices and sharp
//! triangles where no atom that differs between the side and the complex reaches
//! ([`mdsurf::surface::analytic::RefinedReuse`], issue 32: "interface costs the two extra
//! surfaces, no more"): each side then measures what it measures computed alone on the
//! complex's grid, its total area to 1e-7 (measured 2e-8) and every atom's area to 1e-6 of the
//! largest, on the HIV protease dimer (1hpv, chains A and B) and adenylate kinase's two
//! domains, under the SES preset (radii that follow exposure, counted over each side and over
//! the complex). Two groups apart take almost every vertex from the complex and bury nothing.

use glam::Vec3;
use mdsurf::measure::{InterfaceResult, atom_areas_of, interface_with};
use mdsurf::surface::{
    AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode,
};

use crate::measure_areas::selected_atoms;

fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

/// The complex, then A and B computed on its grid as surfaces of their own, by an engine that
/// is given nothing to take.
fn plain_sides(
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    complex_radii: &[f32],
    params: &SurfaceParams,
    mode: VertexMode,
) -> [SurfaceOutput; 2] {
    let positions: Vec<Vec3> = a.positions.iter().chain(b.positions).copied().collect();
    let mut engine = CpuEngine::new().with_vertices(mode);
    let complex = engine
        .compute(&set(&positions, complex_radii), params)
        .expect("complex");
    engine.set_grid(Some(complex.grid));
    [a, b].map(|side| engine.compute(side, params).expect("side"))
}

/// Every per-atom area of `got` within `rel` of the largest of `want`.
fn atoms_close(want: &[f64], got: &[f64], rel: f64, what: &str) {
    assert_eq!(want.len(), got.len(), "{what}");
    let largest = want.iter().fold(0.0f64, |m, &x| m.max(x));
    for (i, (w, g)) in want.iter().zip(got).enumerate() {
        assert!(
            (w - g).abs() <= rel * largest,
            "{what}: atom {i}: {g} vs {w}"
        );
    }
}

/// The interface of `sel_a` and `sel_b` in `file` under the SES preset, the sides' radii
/// counted over each side and the complex's over both, against the sides computed alone.
fn check(file: &str, sel_a: &str, sel_b: &str) -> InterfaceResult {
    let preset = Some(Preset::Ses);
    let (_, ia, pa, ra) = selected_atoms(file, sel_a, preset);
    let (_, ib, pb, rb) = selected_atoms(file, sel_b, preset);
    let both = format!("({sel_a}) or ({sel_b})");
    let (_, iab, _, rab) = selected_atoms(file, &both, preset);
    let in_complex: std::collections::HashMap<u32, f32> = iab.into_iter().zip(rab).collect();
    let complex_radii: Vec<f32> = ia.iter().chain(&ib).map(|i| in_complex[i]).collect();
    let (a, b) = (set(&pa, &ra), set(&pb, &rb));
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mode = VertexMode::Refined;
    let mut engine = CpuEngine::new().with_vertices(mode);
    let r = interface_with(&mut engine, &a, &b, Some(&complex_radii), &params, true)
        .expect("interface");
    let [alone_a, alone_b] = plain_sides(&a, &b, &complex_radii, &params, mode);
    assert_eq!(alone_a.grid, r.grid, "{file}: the complex's grid");
    for (side, want, got) in [("A", alone_a.area, r.area_a), ("B", alone_b.area, r.area_b)] {
        assert!(
            (got / want - 1.0).abs() < 1e-7,
            "{file} side {side}: {got} Å² taking from the complex, {want} Å² alone"
        );
    }
    let measure = mode.effective(&params);
    let atoms_a = atom_areas_of(&alone_a, &a, &measure).expect("weighed");
    let atoms_b = atom_areas_of(&alone_b, &b, &measure).expect("weighed");
    atoms_close(&atoms_a, &r.atoms_a_alone, 1e-6, &format!("{file} A"));
    atoms_close(&atoms_b, &r.atoms_b_alone, 1e-6, &format!("{file} B"));
    let sharp = |o: &SurfaceOutput| o.sharp.as_ref().map_or(0, |s| s.triangles.len());
    eprintln!(
        "{file}: taken A {:?} of ({} vertices, {} sharp), B {:?} of ({}, {})",
        r.taken[0],
        alone_a.mesh.vertex_count(),
        sharp(&alone_a),
        r.taken[1],
        alone_b.mesh.vertex_count(),
        sharp(&alone_b)
    );
    r
}

#[test]
fn sides_taking_the_complexs_vertices_measure_what_they_measure_alone() {
    let dimer = check("1hpv.pdb", "protein and chain A", "protein and chain B");
    let domains = check(
        "adk_open.pdb",
        "protein and resid 1:59",
        "protein and resid 60:214",
    );
    // Adenylate kinase's larger domain lies mostly away from the other: it takes about 65 %
    // of its vertices (measured 8,745 of 13,470) and 58 % of its sharp triangles.
    let taken = domains.taken[1];
    assert!(
        taken.vertices > 5_000 && taken.sharp_triangles > 300,
        "adk B took {taken:?}"
    );
    assert!(
        dimer.taken.iter().all(|t| t.vertices > 0),
        "{:?}",
        dimer.taken
    );
}

/// Two groups of atoms 40 Å apart: no vertex of one is reached by the other, so each side
/// takes every vertex of the complex on its part but those on a sample, and buries nothing.
#[test]
fn sides_apart_take_their_vertices_from_the_complex_and_bury_nothing() {
    let mut rng = crate::surface_common::Rng(0x0a11_7a4e);
    let mut blob = |corner: Vec3| -> (Vec<Vec3>, Vec<f32>) {
        let p = (0..40)
            .map(|_| corner + 8.0 * Vec3::new(rng.next(), rng.next(), rng.next()))
            .collect();
        let r = (0..40).map(|_| 1.4 + 0.5 * rng.next()).collect();
        (p, r)
    };
    let (pa, ra) = blob(Vec3::ZERO);
    let (pb, rb) = blob(Vec3::new(40.0, 3.0, -2.0));
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut engine = CpuEngine::new().with_vertices(VertexMode::Refined);
    let (a, b) = (set(&pa, &ra), set(&pb, &rb));
    let r = interface_with(&mut engine, &a, &b, None, &params, false).expect("interface");
    assert!(r.buried.abs() < 1e-6, "buried {} Å²", r.buried);
    let complex_radii: Vec<f32> = ra.iter().chain(&rb).copied().collect();
    let alone = plain_sides(&a, &b, &complex_radii, &params, VertexMode::Refined);
    for (side, out) in alone.iter().enumerate() {
        let taken = r.taken[side].vertices;
        let all = out.mesh.vertex_count();
        assert!(
            taken as f64 >= 0.99 * all as f64,
            "side {side}: {taken} of {all} vertices taken"
        );
    }
}
