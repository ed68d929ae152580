//! The CPU surface of a real protein (adenylate kinase, `tests/data/adk_open.pdb`, 3,341
//! atoms): a closed, outward mesh whose area and volume converge as H shrinks.

use crate::surface_common::surface;
use glam::Vec3;
use mdsurf::surface::{Quality, SurfaceParams};

use crate::data_support::DATA;

/// Positions (Å) and radii by element (DESIGN section 2) of the ATOM records of a PDB file.
fn read_pdb(name: &str) -> (Vec<Vec3>, Vec<f32>) {
    let path = format!("{DATA}{name}");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("test data {path} is missing ({e}); see tests/data/README.md"));
    let mut pos = Vec::new();
    let mut radii = Vec::new();
    for line in text
        .lines()
        .filter(|l| l.starts_with("ATOM") && l.len() >= 54)
    {
        let f = |a: usize, b: usize| line[a..b].trim().parse::<f32>().expect("coordinate");
        pos.push(Vec3::new(f(30, 38), f(38, 46), f(46, 54)));
        let name = line[12..16]
            .trim()
            .trim_start_matches(|c: char| c.is_ascii_digit());
        radii.push(match name.chars().next() {
            Some('H') => 1.0,
            Some('C') => 1.5,
            Some('N') => 1.4,
            Some('O') => 1.3,
            Some('S') => 1.9,
            _ => 1.5,
        });
    }
    (pos, radii)
}

#[test]
fn adk_surface_is_closed_and_converges_with_h() {
    let (pos, radii) = read_pdb("adk_open.pdb");
    assert_eq!(pos.len(), 3341);
    let mut results = Vec::new();
    for spacing in [1.0, 0.5] {
        let params = SurfaceParams {
            spacing,
            quality: Quality::High,
            ..SurfaceParams::default()
        };
        let out = surface(&pos, &radii, None, &params);
        assert!(out.mesh.is_closed(), "H = {spacing}: mesh not closed");
        // Components minus handles: a protein surface at I = 0.5 has at least one component.
        assert_eq!(out.mesh.euler_characteristic() % 2, 0);
        // The surface lies within the atoms' bounding box grown by the largest sphere radius.
        let (lo, hi) = out.mesh.bounds().expect("non-empty mesh");
        let (alo, ahi) = pos
            .iter()
            .fold((pos[0], pos[0]), |(l, h), p| (l.min(*p), h.max(*p)));
        assert!(lo.cmpge(alo - Vec3::splat(3.0)).all() && hi.cmple(ahi + Vec3::splat(3.0)).all());
        assert!(
            out.mesh
                .normals
                .iter()
                .all(|n| (n.length() - 1.0).abs() < 1e-3)
        );
        results.push((out.area, out.volume));
    }
    let (a1, v1) = results[0];
    let (a2, v2) = results[1];
    // A protein of 3,341 atoms (about half hydrogens) encloses roughly 25-45 kÅ^3.
    assert!(v2 > 20_000.0 && v2 < 60_000.0, "volume {v2}");
    assert!(
        (a1 / a2 - 1.0).abs() < 0.08,
        "area {a1} at H = 1 vs {a2} at H = 0.5"
    );
    assert!(
        (v1 / v2 - 1.0).abs() < 0.05,
        "volume {v1} at H = 1 vs {v2} at H = 0.5"
    );
}
