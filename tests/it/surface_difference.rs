//! A surface computed from a kept density less another ([`SurfaceEngine::compute_difference`],
//! which spares the interface sampling one side), on the dense path and on sparse bricks: it is
//! the surface sampled from its own atoms to rounding, bit for bit where the subtracted atoms
//! do not reach, and the engine declines densities of another grid, other parameters, another
//! storage or atoms with colours; a mesh kept with positions only (for weighing) has the whole
//! mesh's positions and triangles.

use glam::Vec3;
use mdsurf::surface::{
    AtomSet, CpuEngine, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode,
};

use crate::surface_common::Rng;

/// `count` atoms of radius 1.2 to 2 Å scattered in a 12 Å cube whose corner is at `corner`.
fn blob(count: usize, corner: Vec3, rng: &mut Rng) -> (Vec<Vec3>, Vec<f32>) {
    let positions = (0..count)
        .map(|_| corner + Vec3::new(rng.next(), rng.next(), rng.next()) * 12.0)
        .collect();
    let radii = (0..count).map(|_| 1.2 + 0.8 * rng.next()).collect();
    (positions, radii)
}

/// Side A, side B and both together (A's atoms first), B's corner at `offset` from A's.
fn two_blobs(offset: Vec3) -> [(Vec<Vec3>, Vec<f32>); 3] {
    let mut rng = Rng(0x5eed_d1ff);
    let a = blob(60, Vec3::ZERO, &mut rng);
    let b = blob(90, offset, &mut rng);
    let both = (
        a.0.iter().chain(&b.0).copied().collect(),
        a.1.iter().chain(&b.1).copied().collect(),
    );
    [a, b, both]
}

fn set(atoms: &(Vec<Vec3>, Vec<f32>)) -> AtomSet<'_> {
    AtomSet {
        positions: &atoms.0,
        radii: &atoms.1,
        colours: None,
    }
}

/// The default engine (dense on these small grids) or one on sparse bricks.
fn engine(bricks: bool) -> CpuEngine {
    match bricks {
        true => CpuEngine::bricks(),
        false => CpuEngine::new(),
    }
}

/// B's surface on the complex's grid, sampled and by difference (complex less A).
fn b_both_ways(
    offset: Vec3,
    params: &SurfaceParams,
    mode: VertexMode,
    bricks: bool,
) -> (SurfaceOutput, SurfaceOutput) {
    let [a, b, both] = two_blobs(offset);
    let mut engine = engine(bricks).with_vertices(mode);
    engine.set_keep_density(true);
    let complex = engine.compute(&set(&both), params).expect("complex");
    engine.set_grid(Some(complex.grid));
    let side_a = engine.compute(&set(&a), params).expect("side A");
    engine.set_keep_density(false);
    let sampled = engine.compute(&set(&b), params).expect("side B");
    let whole = complex
        .density
        .as_deref()
        .expect("the complex keeps its density");
    let minus = side_a.density.as_deref().expect("side A keeps its density");
    let by_difference = engine
        .compute_difference(&set(&b), params, whole, minus)
        .expect("a dense grid takes the difference")
        .expect("side B by difference");
    assert!(sampled.density.is_none(), "not kept once switched off");
    (sampled, by_difference)
}

#[test]
fn a_side_by_difference_is_the_side_sampled_to_rounding() {
    for (mode, bricks) in [
        (VertexMode::Interpolated, false),
        (VertexMode::Refined, false),
        (VertexMode::Interpolated, true),
        (VertexMode::Refined, true),
    ] {
        let params = SurfaceParams::default();
        let mode_bricks = format!("{mode:?}, bricks {bricks}");
        // Overlapping blobs: B's density is the complex's less A's where both reach.
        let (sampled, by_difference) = b_both_ways(Vec3::new(8.0, 2.0, 0.0), &params, mode, bricks);
        assert_eq!(sampled.grid, by_difference.grid);
        let rel = (sampled.area - by_difference.area).abs() / sampled.area;
        assert!(
            rel < 1e-6,
            "{mode_bricks}: area {} vs {}",
            by_difference.area,
            sampled.area
        );
        let rel = (sampled.volume - by_difference.volume).abs() / sampled.volume;
        assert!(rel < 1e-6, "{mode_bricks}: volume {rel}");
        assert_eq!(
            sampled.triangle_count(),
            by_difference.triangle_count(),
            "{mode_bricks}"
        );
        // Blobs farther apart than the Gaussians reach: A's density is exactly 0 at B.
        let (sampled, by_difference) =
            b_both_ways(Vec3::new(40.0, 0.0, 0.0), &params, mode, bricks);
        assert_eq!(
            sampled.area.to_bits(),
            by_difference.area.to_bits(),
            "{mode_bricks}"
        );
        assert_eq!(sampled.mesh, by_difference.mesh, "{mode_bricks}");
    }
}

#[test]
fn a_density_kept_dense_is_declined_by_an_engine_on_bricks() {
    let params = SurfaceParams::default();
    let [a, b, both] = two_blobs(Vec3::new(8.0, 2.0, 0.0));
    let mut dense = CpuEngine::new();
    dense.set_keep_density(true);
    let complex = dense.compute(&set(&both), &params).expect("complex");
    dense.set_grid(Some(complex.grid));
    let side_a = dense.compute(&set(&a), &params).expect("A");
    let mut on_bricks = CpuEngine::bricks();
    on_bricks.set_grid(Some(complex.grid));
    let (whole, minus) = (
        complex.density.expect("kept"),
        side_a.density.expect("kept"),
    );
    assert!(
        on_bricks
            .compute_difference(&set(&b), &params, &whole, &minus)
            .is_none()
    );
    assert!(
        dense
            .compute_difference(&set(&b), &params, &whole, &minus)
            .is_some()
    );
}

#[test]
fn densities_of_another_grid_parameters_or_coloured_atoms_are_declined() {
    let params = SurfaceParams::default();
    let [a, b, both] = two_blobs(Vec3::new(8.0, 2.0, 0.0));
    let mut engine = CpuEngine::new();
    engine.set_keep_density(true);
    let complex = engine.compute(&set(&both), &params).expect("complex");
    let whole = complex.density.as_deref().expect("kept");
    // A on its own grid, not the complex's.
    let own_grid = engine.compute(&set(&a), &params).expect("A");
    engine.set_grid(Some(complex.grid));
    let minus = engine
        .compute(&set(&a), &params)
        .expect("A on the complex's grid");
    let minus = minus.density.as_deref().expect("kept");
    let other_grid = own_grid.density.as_deref().expect("kept");
    assert!(
        engine
            .compute_difference(&set(&b), &params, whole, other_grid)
            .is_none(),
        "another grid"
    );
    let coarser = SurfaceParams {
        isovalue: 0.6,
        ..params
    };
    assert!(
        engine
            .compute_difference(&set(&b), &coarser, whole, minus)
            .is_none(),
        "other parameters"
    );
    let colours = vec![[0.5f32; 3]; b.0.len()];
    let coloured = AtomSet {
        colours: Some(&colours),
        ..set(&b)
    };
    assert!(
        engine
            .compute_difference(&coloured, &params, whole, minus)
            .is_none(),
        "colours"
    );
    assert!(
        engine
            .compute_difference(&set(&b), &params, whole, minus)
            .is_some(),
        "the complex's grid and parameters"
    );
}

#[test]
fn an_engine_short_of_memory_keeps_no_density_and_the_interface_samples_both_sides() {
    let params = SurfaceParams::default();
    let [a, b, both] = two_blobs(Vec3::new(8.0, 2.0, 0.0));
    let grid = CpuEngine::new()
        .compute(&set(&both), &params)
        .expect("complex")
        .grid;
    // Enough to compute this grid (5 bytes a sample), not to keep a 4-byte copy as well.
    let mut short = CpuEngine::with_memory_limit(grid.voxel_count() * 8);
    short.set_keep_density(true);
    let complex = short.compute(&set(&both), &params).expect("complex");
    assert!(complex.density.is_none(), "a copy is not kept");
    let mut roomy = CpuEngine::new();
    roomy.set_keep_density(true);
    assert!(
        roomy
            .compute(&set(&both), &params)
            .expect("complex")
            .density
            .is_some()
    );
    // The buried area without the complex's density is the one with both sides sampled.
    let on_short = mdsurf::measure::interface(&mut short, &set(&a), &set(&b), &params)
        .expect("the interface computes without a kept density");
    let on_roomy = mdsurf::measure::interface(&mut roomy, &set(&a), &set(&b), &params)
        .expect("the interface computes by difference");
    assert!(on_roomy.buried > 10.0, "{}", on_roomy.buried);
    let rel = (on_short.buried - on_roomy.buried).abs() / on_roomy.area_complex;
    assert!(rel < 1e-6, "{} vs {}", on_short.buried, on_roomy.buried);
}

#[test]
fn a_mesh_kept_with_positions_only_has_the_whole_meshs_positions_and_triangles() {
    // The interface's sides keep their meshes only to weigh them per atom.
    let params = SurfaceParams::default();
    let [_, _, both] = two_blobs(Vec3::new(8.0, 2.0, 0.0));
    for bricks in [false, true] {
        let whole = engine(bricks).compute(&set(&both), &params).expect("whole");
        let mut lean = engine(bricks);
        lean.set_mesh_positions_only(true);
        let lean = lean.compute(&set(&both), &params).expect("positions only");
        assert_eq!(whole.mesh.positions, lean.mesh.positions, "bricks {bricks}");
        assert_eq!(whole.mesh.indices, lean.mesh.indices, "bricks {bricks}");
        assert_eq!(whole.area.to_bits(), lean.area.to_bits(), "bricks {bricks}");
        assert!(!whole.mesh.normals.is_empty() && lean.mesh.normals.is_empty());
    }
}
