//! Refined vertices and curvature-aware measurement (issue 13 section 1): vertices on the exact
//! Gaussian sum, analytic normals, same triangles as linear interpolation, and an area and
//! volume that hold at any grid spacing H; refined surfaces run at quality max, grid included,
//! so refined and interpolated vertices find the level set of one function (issue 33).

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
    // Asked at quality high, refined vertices run at max (issue 33): the triangles are those
    // of the interpolated surface at max.
    let lin = run(
        CpuEngine::new(),
        &pos,
        &radii,
        &VertexMode::Refined.effective(&params),
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
    // Along the vertex's own grid edge, except where the sum has no root on the edge (a sample
    // within rounding of I) and the vertex moves along the gradient.
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
/// quality max (the quality refined surfaces run at, `mdsurf::surface::analytic::REFINED_QUALITY`),
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

/// Refined surfaces asked at quality high (computed at max) hold the converged area and volume
/// at coarse H.
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

/// Issue 33: refined and interpolated vertices find the level set of the same function, so on
/// 1hpv (I = 0.5, R = 1, CPU) their areas approach each other as H shrinks, whatever quality is
/// asked for. Refined surfaces run at quality max (grid and refinement,
/// `VertexMode::effective`), so for every asked quality the refined area is the one at max,
/// and the interpolated surface of that function is the one at max. Measured: refined 7468.4,
/// 7472.0, 7472.2, 7472.3 Å² and interpolated 7421.9, 7459.8, 7466.1, 7469.1 Å² at H = 1, 0.5,
/// 0.35, 0.25 Å, 0.63, 0.16, 0.083, 0.043 % apart (about as H²). Before the change (grid at the
/// asked cutoff, refinement at 4 alpha) they were 0.41 % apart at quality high and H = 0.25
/// (refined 7500.1 Å²) and 14 % at medium (8514.1 Å²), and the gap grew from H = 0.35 to 0.25.
/// Why not refine at the asked cutoff instead (each term then jumps by exp(-q²/2) at its
/// cutoff sphere, and the sum's level set has steps about 0.1 Å high at medium, 0.03 Å at high,
/// whose area comes in only as H approaches them): both modes then grow with no end in sight,
/// 7648 to 8032 Å² interpolated and 7791 to 8154 Å² refined at medium from H = 1 to 0.125 Å,
/// about 1.3 % apart throughout (`mdsurf::surface::analytic`'s module docs).
#[test]
fn hpv_refined_and_interpolated_areas_converge_together_at_every_quality() {
    let (pos, radii) = load("1hpv.pdb");
    let spacings = [1.0f32, 0.5, 0.35, 0.25];
    let area = |quality: Quality, spacing: f32, mode: VertexMode| {
        let params = SurfaceParams {
            spacing,
            quality,
            ..SurfaceParams::default()
        };
        let out = run(CpuEngine::new(), &pos, &radii, &params, mode);
        assert!(out.mesh.is_closed(), "{quality:?} H = {spacing} {mode}");
        out.area
    };
    // The interpolated surface of the function refined surfaces sample (quality max).
    let lin: Vec<f64> = spacings
        .iter()
        .map(|&h| area(Quality::Max, h, VertexMode::Interpolated))
        .collect();
    let qualities = [Quality::Medium, Quality::High, Quality::Max];
    let refined: Vec<Vec<f64>> = qualities
        .iter()
        .map(|&q| {
            spacings
                .iter()
                .map(|&h| area(q, h, VertexMode::Refined))
                .collect()
        })
        .collect();
    // All qualities shown first, then checked.
    let rows: Vec<(Vec<f64>, String)> = qualities
        .iter()
        .zip(&refined)
        .map(|(q, row)| {
            let gaps: Vec<f64> = row.iter().zip(&lin).map(|(r, l)| r / l - 1.0).collect();
            let shown: Vec<String> = spacings
                .iter()
                .zip(row.iter().zip(&gaps))
                .map(|(h, (r, g))| format!("H = {h}: {r:.1} Å² ({:+.3} %)", 100.0 * g))
                .collect();
            let what = format!(
                "{q:?}: refined vs interpolated {lin:.1?}: {}",
                shown.join(", ")
            );
            eprintln!("{what}");
            (gaps, what)
        })
        .collect();
    for (gaps, what) in &rows {
        assert!(
            gaps.windows(2).all(|w| w[1].abs() < w[0].abs()),
            "gap does not shrink with H: {what}"
        );
        assert!(
            gaps.last().is_some_and(|g| g.abs() < 0.001),
            "more than 0.1 % apart at H = 0.25: {what}"
        );
    }
    // The asked quality does not matter to a refined surface.
    assert_eq!(refined[0], refined[2], "medium vs max");
    assert_eq!(refined[1], refined[2], "high vs max");
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
    let protein = mdsurf::selection::Selection::parse("protein").expect("selection");
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
