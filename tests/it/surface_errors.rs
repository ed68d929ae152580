//! Bad inputs to the CPU engine give typed one-line errors, never panics (issue 2 section 5).

use glam::Vec3;
use mdsurf::surface::{
    AtomSet, CpuEngine, GridSpec, SurfaceEngine, SurfaceError, SurfaceParams, density,
    estimate_grid_bytes,
};

fn run(
    positions: &[Vec3],
    radii: &[f32],
    colours: Option<&[[f32; 3]]>,
    params: &SurfaceParams,
    engine: &mut CpuEngine,
) -> SurfaceError {
    let atoms = AtomSet {
        positions,
        radii,
        colours,
    };
    let err = engine
        .compute(&atoms, params)
        .expect_err("bad input must be refused");
    let text = err.to_string();
    assert!(!text.contains('\n') && !text.is_empty(), "{text:?}");
    err
}

#[test]
fn bad_parameters_are_refused() {
    let pos = [Vec3::ZERO];
    let radii = [1.5];
    let base = SurfaceParams::default();
    let cases = [
        SurfaceParams {
            spacing: 0.0,
            ..base
        },
        SurfaceParams {
            spacing: -1.0,
            ..base
        },
        SurfaceParams {
            radius_scale: f32::NAN,
            ..base
        },
        SurfaceParams {
            isovalue: 0.0,
            ..base
        },
        SurfaceParams {
            isovalue: f32::INFINITY,
            ..base
        },
    ];
    for params in cases {
        let err = run(&pos, &radii, None, &params, &mut CpuEngine::new());
        assert!(
            matches!(err, SurfaceError::InvalidParameter { .. }),
            "{err}"
        );
    }
}

#[test]
fn bad_atoms_are_refused() {
    let params = SurfaceParams::default();
    let mut e = CpuEngine::new();
    let err = run(&[], &[], None, &params, &mut e);
    assert!(matches!(err, SurfaceError::EmptySystem));
    let pos = [Vec3::ZERO, Vec3::new(1.0, f32::NAN, 0.0)];
    let err = run(&pos, &[1.0, 1.0], None, &params, &mut e);
    assert!(matches!(err, SurfaceError::NonFiniteCoordinate { atom: 1 }));
    let pos = [Vec3::ZERO, Vec3::X];
    let err = run(&pos, &[1.0, 0.0], None, &params, &mut e);
    assert!(matches!(err, SurfaceError::InvalidRadius { atom: 1, .. }));
    let err = run(&pos, &[-1.0, 1.0], None, &params, &mut e);
    assert!(matches!(err, SurfaceError::InvalidRadius { atom: 0, .. }));
    let err = run(&pos, &[1.0], None, &params, &mut e);
    assert!(matches!(
        err,
        SurfaceError::LengthMismatch { what: "radii", .. }
    ));
    let err = run(&pos, &[1.0, 1.0], Some(&[[1.0; 3]]), &params, &mut e);
    assert!(matches!(
        err,
        SurfaceError::LengthMismatch {
            what: "colours",
            ..
        }
    ));
    let bad = [[1.0; 3], [0.0, f32::NAN, 0.0]];
    let err = run(&pos, &[1.0, 1.0], Some(&bad), &params, &mut e);
    assert!(matches!(err, SurfaceError::NonFiniteColour { atom: 1 }));
}

#[test]
fn stage_functions_refuse_bad_atoms_too() {
    let params = SurfaceParams::default();
    let pos = [Vec3::ZERO, Vec3::X];
    let grid = GridSpec::for_atoms(&pos, &[1.0, 1.0], &params).expect("grid");
    let atoms = AtomSet {
        positions: &pos,
        radii: &[1.0],
        colours: None,
    };
    assert!(density::compute(&atoms, &params, &grid).is_err());
}

#[test]
fn a_grid_too_large_for_memory_says_what_it_needs() {
    let pos = [Vec3::ZERO, Vec3::new(100.0, 100.0, 100.0)];
    let radii = [1.5, 1.5];
    let params = SurfaceParams {
        spacing: 0.1,
        ..SurfaceParams::default()
    };
    let mut small = CpuEngine::with_memory_limit(100_000_000);
    let err = run(&pos, &radii, None, &params, &mut small);
    let SurfaceError::GridTooLarge {
        dims, bytes_needed, ..
    } = err
    else {
        panic!("expected GridTooLarge, got {err}");
    };
    assert_eq!(bytes_needed, estimate_grid_bytes(dims, false));
    assert!(bytes_needed > 100_000_000);
    let text = err.to_string();
    assert!(
        text.contains("GB") && text.contains("grid spacing H"),
        "{text}"
    );
    // With colours the estimate is larger.
    assert!(estimate_grid_bytes(dims, true) > bytes_needed);
    // The same system at a coarse spacing fits.
    let coarse = SurfaceParams {
        spacing: 2.0,
        ..params
    };
    let atoms = AtomSet {
        positions: &pos,
        radii: &radii,
        colours: None,
    };
    assert!(small.compute(&atoms, &coarse).is_ok());
}

#[test]
fn an_absurd_grid_is_refused_without_allocating() {
    let pos = [Vec3::ZERO, Vec3::splat(1.0e6)];
    let params = SurfaceParams {
        spacing: 0.01,
        ..SurfaceParams::default()
    };
    let err = run(&pos, &[1.0, 1.0], None, &params, &mut CpuEngine::new());
    assert!(matches!(err, SurfaceError::GridTooLarge { .. }), "{err}");
}
