//! The measurements on the GPU engine's read-back mesh against the CPU engine's (issue 32,
//! "CPU and GPU agree to 1e-6 relative on every quantity"): the area, each atom's and each
//! residue's area, each cavity's volume, area and centroid, and the buried interface area, on
//! 1hpv's protein and 1a28's two chains, at the defaults and under the SES preset (radii that
//! follow exposure, refined vertices). Each kind of quantity is held to the bound it meets
//! (measured on lavapipe, docs/measure.md "CPU and GPU"): 1e-6 relative at the defaults except
//! the cavities' volumes (2e-6); under the preset the whole area to 1e-6, but per atom only to
//! 3e-5, per residue 1e-5, a cavity's volume 5e-6 and area 2e-6, where one refined vertex in a
//! crevice lands 3.5e-3 Å apart. The vertices themselves agree to 1e-4 Å but for at most two
//! per surface.

use std::collections::BTreeMap;

use mdsurf::measure::{CavityOptions, atom_areas_of, cavities, interface, residue_areas};
use mdsurf::surface::{AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceOutput, SurfaceParams};

use crate::measure_areas::selected_atoms;

/// The largest relative deviation of each kind of quantity, GPU against CPU.
#[derive(Default)]
struct Worst(BTreeMap<&'static str, (f64, String)>);

impl Worst {
    /// Records `got` against `want`, relative to `scale` (the largest value of its kind, so that
    /// values near 0 are held to the same absolute bound as the rest) or to `want`.
    fn add(&mut self, kind: &'static str, want: f64, got: f64, scale: f64, what: String) {
        let rel = (want - got).abs() / scale.max(want.abs());
        let entry = self.0.entry(kind).or_insert((0.0, String::new()));
        if rel >= entry.0 {
            *entry = (rel, what);
        }
    }

    /// Fails when a kind deviates by more than its bound (kinds not listed: `default`).
    fn hold(&self, default: f64, bounds: &[(&str, f64)], setting: &str) {
        for (kind, (rel, what)) in &self.0 {
            let bound = bounds
                .iter()
                .find(|(k, _)| k == kind)
                .map_or(default, |(_, b)| *b);
            assert!(
                *rel <= bound,
                "{setting}: {kind} deviates by {rel:.2e} (bound {bound:.0e}) at {what}"
            );
        }
    }
}

/// The surface of `atoms` on `engine`, its mesh kept.
fn surface(
    engine: &mut dyn SurfaceEngine,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> SurfaceOutput {
    engine.set_keep_mesh(true);
    engine.compute(atoms, params).expect("the surface computes")
}

/// Both engines write a surface's vertices in the same order (cell by cell, x, y, z edge): the
/// GPU's must lie within 1e-4 Å of the CPU's but for at most [`VERTICES_APART`] (interpolated
/// ones come within 2.3e-5 Å, a few f32 steps at 50 Å). Refined vertices in crevices had come
/// out up to 4e-3 Å apart (4 per structure beyond 1e-4 Å, 15 and 25 beyond 1e-5 Å),
/// where the Newton search on the edge stopped unconverged and each engine moved its vertex
/// along the gradient from wherever rounding had left it.
fn assert_vertices_agree(cpu: &SurfaceOutput, gpu: &SurfaceOutput, what: &str) {
    let (c, g) = (&cpu.mesh.positions, &gpu.mesh.positions);
    assert_eq!(c.len(), g.len(), "{what}: vertex count");
    let apart: Vec<(usize, f32)> = c
        .iter()
        .zip(g)
        .map(|(a, b)| a.distance(*b))
        .enumerate()
        .filter(|(_, d)| *d > 1e-4)
        .collect();
    assert!(
        apart.len() <= VERTICES_APART,
        "{what}: {} of {} vertices more than 1e-4 Å apart: {apart:?}",
        apart.len(),
        c.len()
    );
}

/// Vertices per surface allowed more than 1e-4 Å apart between the engines: where a term's step
/// at its cutoff sphere and the smooth root lie closer than rounding tells apart (one on 1hpv
/// under the preset, 3.5e-3 Å).
const VERTICES_APART: usize = 2;

/// Compares the measurements of `selection` in `file` on both engines under `preset`.
fn compare(
    gpu: &mut dyn SurfaceEngine,
    file: &str,
    selection: &str,
    preset: Option<Preset>,
    worst: &mut Worst,
) -> usize {
    let what = format!("{file} {preset:?}");
    let (topology, idx, positions, radii) = selected_atoms(file, selection, preset);
    let atoms = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let params = preset.map_or(SurfaceParams::default(), |p| {
        p.apply(SurfaceParams::default())
    });
    let vertices = preset.map_or(Default::default(), |p| p.vertices());
    let mut cpu = CpuEngine::new().with_vertices(vertices);
    gpu.set_vertices(vertices);
    let measured = vertices.effective(&params);
    let (c, g) = (
        surface(&mut cpu, &atoms, &params),
        surface(gpu, &atoms, &params),
    );
    worst.add("area", c.area, g.area, c.area, what.clone());
    assert_vertices_agree(&c, &g, &what);
    let (ca, ga) = (
        atom_areas_of(&c, &atoms, &measured).expect("CPU atom areas"),
        atom_areas_of(&g, &atoms, &measured).expect("GPU atom areas"),
    );
    let largest = ca.iter().fold(0.0f64, |m, &a| m.max(a));
    for (i, (w, h)) in ca.iter().zip(&ga).enumerate() {
        worst.add("atom area", *w, *h, largest, format!("{what} atom {i}"));
    }
    let (cr, gr) = (
        residue_areas(&topology, Some(&idx), &ca).expect("CPU residues"),
        residue_areas(&topology, Some(&idx), &ga).expect("GPU residues"),
    );
    assert_eq!(cr.len(), gr.len(), "{what}");
    let largest = cr.iter().fold(0.0f64, |m, r| m.max(r.area));
    for (w, h) in cr.iter().zip(&gr) {
        assert_eq!(w.residue, h.residue, "{what}");
        let it = format!("{what} residue {}", w.residue);
        worst.add("residue area", w.area, h.area, largest, it);
    }
    // The cavities `--cavities` reports (1 Å³ or more).
    let options = CavityOptions {
        min_volume: 1.0,
        ..CavityOptions::default()
    };
    let (cc, gc) = (
        cavities(&c.mesh, &atoms, &measured, &options).expect("CPU cavities"),
        cavities(&g.mesh, &atoms, &measured, &options).expect("GPU cavities"),
    );
    assert_eq!(cc.len(), gc.len(), "{what}: cavities");
    for (k, (w, h)) in cc.iter().zip(&gc).enumerate() {
        let it = format!("{what} cavity {k} of {:.1} Å³", w.volume);
        worst.add("cavity volume", w.volume, h.volume, w.volume, it.clone());
        worst.add("cavity area", w.area, h.area, w.area, it.clone());
        for axis in 0..3 {
            // Centroids relative to the structure's size (100 Å).
            let (a, b) = (w.centroid[axis], h.centroid[axis]);
            worst.add("cavity centroid", a, b, 100.0, it.clone());
        }
        assert_eq!(w.lining_atoms, h.lining_atoms, "{it}: lining");
    }
    cc.len()
}

/// [`compare`] on 1hpv's protein and 1a28's two chains under `preset`: the worst deviations and
/// the number of cavities compared; `None` without a GPU adapter (`gpu_support::engine`
/// panics instead under `REQUIRE_GPU=1`).
fn compare_proteins(preset: Option<Preset>) -> Option<(Worst, usize)> {
    let mut gpu = crate::gpu_support::engine()?;
    let mut worst = Worst::default();
    let mut compared = 0;
    for (file, selection) in [("1hpv.pdb", "protein"), ("1a28.pdb.gz", "protein")] {
        compared += compare(&mut gpu, file, selection, preset, &mut worst);
    }
    Some((worst, compared))
}

#[test]
fn measurements_agree_between_engines_at_the_defaults() {
    let Some((worst, compared)) = compare_proteins(None) else {
        return;
    };
    assert!(compared >= 3, "{compared} cavities compared");
    worst.hold(1e-6, &[("cavity volume", 2e-6)], "defaults");
}

#[test]
fn measurements_agree_between_engines_under_the_ses_preset() {
    let Some((worst, compared)) = compare_proteins(Some(Preset::Ses)) else {
        return;
    };
    assert!(compared >= 10, "{compared} cavities compared");
    let bounds = [
        ("atom area", 3e-5),
        ("residue area", 1e-5),
        ("cavity volume", 5e-6),
        ("cavity area", 2e-6),
    ];
    worst.hold(1e-6, &bounds, "SES preset");
}

#[test]
fn the_buried_area_is_the_same_with_either_engine() {
    let Some(mut gpu) = crate::gpu_support::engine() else {
        return;
    };
    let (_, _, pa, ra) = selected_atoms("1hpv.pdb", "protein and chain A", None);
    let (_, _, pb, rb) = selected_atoms("1hpv.pdb", "protein and chain B", None);
    let set = |positions, radii| AtomSet {
        positions,
        radii,
        colours: None,
    };
    let (a, b) = (set(&pa, &ra), set(&pb, &rb));
    let params = SurfaceParams::default();
    let on_cpu = interface(&mut CpuEngine::new(), &a, &b, &params).expect("CPU");
    let on_gpu = interface(&mut gpu, &a, &b, &params).expect("GPU");
    let mut worst = Worst::default();
    let scale = on_cpu.area_complex;
    worst.add("buried", on_cpu.buried, on_gpu.buried, scale, "1hpv".into());
    worst.hold(1e-6, &[], "interface");
    assert!(on_cpu.buried > 500.0, "{}", on_cpu.buried);
}
