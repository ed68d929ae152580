//! Refined vertices and curvature-aware measurement (issue 13 section 1): vertices on the exact
//! Gaussian sum, analytic normals, same triangles as linear interpolation, and an area and
//! volume that hold at any grid spacing H.

use std::f64::consts::PI;

use crate::data_support::data;
use crate::surface_common::{cluster, sphere_radius};
use glam::Vec3;
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::surface::{
    AtomSet, CpuEngine, Quality, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode,
};

/// Positions (Å) and radii (Å, DESIGN section 2, as the command line reads them) of a file in
/// tests/data.
pub fn load(name: &str) -> (Vec<Vec3>, Vec<f32>) {
    let traj = mdsurf::io::open(&data(name), None).expect("open test structure");
    let frame = traj.read_frame(0).expect("frame 0");
    let particles =
        Particles::new(traj.topology(), &frame, &ParticleOptions::default()).expect("particles");
    let pos = particles.positions(&frame).expect("positions");
    (pos, particles.radii().to_vec())
}

fn run(
    engine: CpuEngine,
    pos: &[Vec3],
    radii: &[f32],
    params: &SurfaceParams,
    mode: VertexMode,
) -> SurfaceOutput {
    let atoms = AtomSet {
        positions: pos,
        radii,
        colours: None,
    };
    engine
        .with_vertices(mode)
        .compute(&atoms, params)
        .expect("surface")
}

fn high(spacing: f32) -> SurfaceParams {
    SurfaceParams {
        spacing,
        quality: Quality::High,
        ..SurfaceParams::default()
    }
}

#[test]
fn one_atom_sphere_within_0_3_percent_at_h_alpha_over_2() {
    let (alpha, centre) = (1.5f32, Vec3::new(0.31, -0.2, 0.77));
    let rs = sphere_radius(alpha, 0.5);
    let (area, volume) = (4.0 * PI * rs * rs, 4.0 / 3.0 * PI * rs.powi(3));
    let params = high(alpha / 2.0);
    let out = run(
        CpuEngine::new(),
        &[centre],
        &[alpha],
        &params,
        VertexMode::Refined,
    );
    let (da, dv) = (out.area / area - 1.0, out.volume / volume - 1.0);
    assert!(da.abs() < 0.003, "area off by {:.3} %", 100.0 * da);
    assert!(dv.abs() < 0.003, "volume off by {:.3} %", 100.0 * dv);
    // The flat triangles alone fall short (chords): the correction is doing the work.
    assert!(out.mesh.area() / area - 1.0 < -0.02);
    // Every vertex on the sphere, every normal radial.
    for (p, n) in out.mesh.positions.iter().zip(&out.mesh.normals) {
        let d = *p - centre;
        assert!(
            (d.length() as f64 - rs).abs() < 1e-4,
            "vertex {p} off the sphere"
        );
        assert!(
            n.dot(d.normalize()) > 0.99999,
            "normal {n} at {p} not radial"
        );
    }
}

#[test]
fn refining_moves_vertices_along_their_edges_and_keeps_the_triangles() {
    let (pos, radii) = cluster(60, 9.0, Vec3::new(1.0, 2.0, -3.0), 7);
    let params = high(0.8);
    let lin = run(
        CpuEngine::new(),
        &pos,
        &radii,
        &params,
        VertexMode::Interpolated,
    );
    let fine = run(CpuEngine::new(), &pos, &radii, &params, VertexMode::Refined);
    let dense = run(
        CpuEngine::dense(),
        &pos,
        &radii,
        &params,
        VertexMode::Refined,
    );
    assert_eq!(lin.mesh.indices, fine.mesh.indices);
    assert_eq!(lin.mesh.colours, fine.mesh.colours);
    assert!(fine.mesh.is_closed());
    assert_eq!(fine.mesh, dense.mesh, "sparse and dense engines differ");
    // Along the vertex's own grid edge, except where the 4-alpha sum has no root on the edge
    // (the samples stop at the quality's cutoff, here 3 alpha) and the vertex moves along the
    // gradient.
    let h = params.spacing;
    let mut on_edge = 0;
    for (a, b) in lin.mesh.positions.iter().zip(&fine.mesh.positions) {
        let d = (*b - *a).abs();
        on_edge += usize::from(d.cmpgt(Vec3::splat(1e-5)).bitmask().count_ones() <= 1);
        assert!(d.length() <= 1.5 * h, "{a} -> {b} moves more than 1.5 H");
    }
    let n = fine.mesh.vertex_count();
    assert!(
        on_edge * 10 > n * 9,
        "only {on_edge} of {n} vertices on their edges"
    );
    for n in &fine.mesh.normals {
        assert!((n.length() - 1.0).abs() < 1e-5);
    }
}

/// Reference area (Å²) and volume (Å³) of 1hpv's Gaussian surface (I = 0.5, R = 1), computed
/// independently of the refinement: linear interpolation and flat triangles on fine grids,
/// quality max (the 4 alpha reach the refined vertices use, see `mdsurf::surface::analytic`),
/// H = 0.35 and 0.25 Å, extrapolated to H -> 0 assuming the error goes as H²:
/// `A0 = A(0.25) + (A(0.25) - A(0.35)) * 0.25² / (0.35² - 0.25²)`.
fn hpv_reference(pos: &[Vec3], radii: &[f32]) -> (f64, f64) {
    let at = |h: f32| {
        let params = SurfaceParams {
            spacing: h,
            quality: Quality::Max,
            ..SurfaceParams::default()
        };
        let out = run(
            CpuEngine::new(),
            pos,
            radii,
            &params,
            VertexMode::Interpolated,
        );
        (out.mesh.area(), out.mesh.volume())
    };
    let ((a1, v1), (a2, v2)) = (at(0.35), at(0.25));
    let w = 0.25f64.powi(2) / (0.35f64.powi(2) - 0.25f64.powi(2));
    (a2 + (a2 - a1) * w, v2 + (v2 - v1) * w)
}

#[test]
fn hpv_area_and_volume_hold_at_coarse_h() {
    let (pos, radii) = load("1hpv.pdb");
    let (area, volume) = hpv_reference(&pos, &radii);
    for (h, tol) in [(2.0f32, 0.01), (1.0, 0.003)] {
        let out = run(
            CpuEngine::new(),
            &pos,
            &radii,
            &high(h),
            VertexMode::Refined,
        );
        assert!(out.mesh.is_closed());
        let (da, dv) = (out.area / area - 1.0, out.volume / volume - 1.0);
        assert!(
            da.abs() < tol && dv.abs() < tol,
            "H = {h}: area {:.1} vs {area:.1} ({:+.3} %), volume {:.1} vs {volume:.1} ({:+.3} %)",
            out.area,
            100.0 * da,
            out.volume,
            100.0 * dv
        );
    }
    // Interpolated vertices miss the H = 2 target: the refinement is what holds it.
    let lin = run(
        CpuEngine::new(),
        &pos,
        &radii,
        &high(2.0),
        VertexMode::Interpolated,
    );
    assert!((lin.area / area - 1.0).abs() > 0.01 || (lin.volume / volume - 1.0).abs() > 0.01);
}

/// The SES preset's surface (its R, I and radii at quality max) is sharper than the
/// default one: narrow creases between atoms, where a triangle's normals turn by more than 60°
/// (9 % of the triangles of 1hpv's protein at H = 1 Å). Measured by the curved correction alone
/// those triangles come out 12 % short (the lift from the normals is capped across a crease)
/// and the whole surface 1.2 % short of its converged area; measured on the Gaussian sum itself
/// they bring H = 1 Å within 0.6 % of it (-0.50 % when this was written; -1.16 % without). Reference: as [`hpv_reference`] (linear interpolation, flat
/// triangles, H = 0.35 and 0.25 Å, extrapolated to H -> 0), independent of the refinement.
#[test]
fn ses_preset_surface_of_1hpv_holds_at_h_1_with_its_sharp_triangles_measured_on_the_sum() {
    use mdsurf::surface::{Preset, curved};
    let traj = mdsurf::io::open(&data("1hpv.pdb"), None).expect("open test structure");
    let frame = traj.read_frame(0).expect("frame 0");
    let options = ParticleOptions {
        radius_overrides: Preset::Ses.radius_set().with_overrides(&Default::default()),
        ..ParticleOptions::default()
    };
    let particles = Particles::new(traj.topology(), &frame, &options).expect("particles");
    let all = particles.positions(&frame).expect("positions");
    let protein = mdsurf::scene::Selection::parse("protein").expect("selection");
    let picked = protein.bind(traj.topology()).indices(&frame);
    let pos: Vec<Vec3> = picked.iter().map(|&i| all[i as usize]).collect();
    let radii: Vec<f32> = picked
        .iter()
        .map(|&i| particles.radii()[i as usize])
        .collect();
    let preset = |spacing: f32| {
        Preset::Ses.apply(SurfaceParams {
            spacing,
            ..SurfaceParams::default()
        })
    };
    let flat = |h: f32| {
        let out = run(
            CpuEngine::new(),
            &pos,
            &radii,
            &preset(h),
            VertexMode::Interpolated,
        );
        out.mesh.area()
    };
    let (a1, a2) = (flat(0.35), flat(0.25));
    let reference = a2 + (a2 - a1) * 0.25f64.powi(2) / (0.35f64.powi(2) - 0.25f64.powi(2));
    let out = run(
        CpuEngine::new(),
        &pos,
        &radii,
        &preset(1.0),
        VertexMode::Refined,
    );
    let curved_only = curved::curved_area_volume(&out.mesh, None).0;
    let (d, d_curved) = (out.area / reference - 1.0, curved_only / reference - 1.0);
    assert!(
        d.abs() < 0.006,
        "H = 1: {:.1} Å² vs {reference:.1} Å² ({:+.2} %)",
        out.area,
        100.0 * d
    );
    assert!(
        d_curved < -0.01,
        "without the sharp triangles on the sum: {curved_only:.1} Å² ({:+.2} %)",
        100.0 * d_curved
    );
}
