//! Analytic checks of the CPU surface (issue 2 section 6, DESIGN section 2): one atom gives the
//! sphere of radius `alpha sqrt(2 ln(1/I))` with area and volume within the linear-interpolation
//! error bounds, meshes are closed with the right Euler characteristic, normals and winding
//! point outward, and raising I never grows the volume.

use std::f64::consts::PI;

use crate::surface_common::{cluster, sphere_radius, surface};
use glam::Vec3;
use mdsurf::surface::{Quality, SurfaceParams};

fn one_atom_errors(alpha_over_h: f32, iso: f32) -> (f64, f64) {
    let r = 1.5f32;
    let params = SurfaceParams {
        spacing: r / alpha_over_h,
        radius_scale: 1.0,
        isovalue: iso,
        quality: Quality::Medium,
    };
    let out = surface(&[Vec3::new(3.3, -1.2, 7.9)], &[r], None, &params);
    assert!(out.mesh.is_closed(), "one-atom mesh is not closed");
    assert_eq!(out.mesh.euler_characteristic(), 2);
    let rs = sphere_radius(r, iso);
    let area = 4.0 * PI * rs * rs;
    let volume = 4.0 / 3.0 * PI * rs.powi(3);
    assert!((out.area - out.mesh.area()).abs() < 1e-9 * area);
    assert!((out.volume - out.mesh.volume()).abs() < 1e-9 * volume);
    (out.area / area - 1.0, out.volume / volume - 1.0)
}

#[test]
fn one_atom_is_a_sphere_at_h_alpha_over_4() {
    for iso in [0.5, 0.3] {
        let (da, dv) = one_atom_errors(4.0, iso);
        assert!(
            da.abs() < 0.015,
            "I = {iso}: area off by {:.3} %",
            da * 100.0
        );
        assert!(
            dv.abs() < 0.03,
            "I = {iso}: volume off by {:.3} %",
            dv * 100.0
        );
    }
}

#[test]
fn one_atom_is_a_sphere_at_h_alpha_over_8() {
    let (da, dv) = one_atom_errors(8.0, 0.5);
    assert!(da.abs() < 0.005, "area off by {:.3} %", da * 100.0);
    assert!(dv.abs() < 0.01, "volume off by {:.3} %", dv * 100.0);
}

#[test]
fn vertices_lie_near_the_sphere_and_normals_point_outward() {
    let centre = Vec3::new(-4.0, 2.0, 1.0);
    let params = SurfaceParams {
        spacing: 0.25,
        ..SurfaceParams::default()
    };
    let out = surface(&[centre], &[1.6], None, &params);
    let rs = sphere_radius(1.6, 0.5) as f32;
    assert!(out.mesh.vertex_count() > 100);
    for (p, n) in out.mesh.positions.iter().zip(&out.mesh.normals) {
        let d = *p - centre;
        // Linear interpolation places vertices slightly inside, never outside.
        assert!(
            d.length() < rs * 1.001 && d.length() > rs * 0.97,
            "{}",
            d.length()
        );
        assert!((n.length() - 1.0).abs() < 1e-4);
        assert!(n.dot(d.normalize()) > 0.99, "normal {n} at {d}");
    }
    assert_triangles_face_their_normals(&out.mesh);
}

/// Every triangle's geometric normal (counter-clockwise winding) agrees with its vertex normals
/// where those agree among themselves (at sharp saddles they may point all ways).
fn assert_triangles_face_their_normals(mesh: &mdsurf::surface::Mesh) {
    let mut checked = 0;
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
        let geo = (b - a).cross(c - a);
        let n: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
        if n.length() < 1.5 {
            continue;
        }
        checked += 1;
        assert!(
            geo.dot(n) > 0.0,
            "triangle {t:?} winds inward: {a} {b} {c} geo {geo} n {n} {:?}",
            t.iter()
                .map(|&i| mesh.normals[i as usize])
                .collect::<Vec<_>>()
        );
    }
    assert!(
        checked * 10 > mesh.triangle_count() * 9,
        "too few triangles checked"
    );
}

#[test]
fn cluster_mesh_is_closed_outward_and_positive() {
    let (pos, radii) = cluster(120, 14.0, Vec3::new(5.0, 6.0, -3.0), 7);
    let params = SurfaceParams {
        spacing: 0.7,
        ..SurfaceParams::default()
    };
    let out = surface(&pos, &radii, None, &params);
    assert!(out.mesh.is_closed());
    assert!(out.volume > 0.0 && out.area > 0.0);
    assert_eq!(out.mesh.normals.len(), out.mesh.vertex_count());
    assert_eq!(out.mesh.colours.len(), out.mesh.vertex_count());
    assert!(out.mesh.colours.iter().all(|c| *c == [1.0; 3]));
    assert_triangles_face_their_normals(&out.mesh);
    // Every vertex is referenced (one vertex per crossed edge, no orphans).
    let mut used = vec![false; out.mesh.vertex_count()];
    for &i in &out.mesh.indices {
        used[i as usize] = true;
    }
    assert!(used.iter().all(|&u| u));
}

#[test]
fn euler_characteristic_counts_blobs() {
    let params = SurfaceParams::default();
    let one = surface(&[Vec3::ZERO], &[1.5], None, &params);
    assert_eq!(one.mesh.euler_characteristic(), 2);
    let two = surface(
        &[Vec3::ZERO, Vec3::new(20.0, 3.0, -2.0)],
        &[1.5, 1.8],
        None,
        &params,
    );
    assert!(two.mesh.is_closed());
    assert_eq!(two.mesh.euler_characteristic(), 4);
}

#[test]
fn raising_the_isovalue_never_grows_the_volume() {
    let (pos, radii) = cluster(60, 10.0, Vec3::ZERO, 11);
    let mut last = f64::INFINITY;
    for step in 1..=18 {
        let iso = 0.05 * step as f32;
        let params = SurfaceParams {
            spacing: 0.8,
            isovalue: iso,
            ..SurfaceParams::default()
        };
        let out = surface(&pos, &radii, None, &params);
        assert!(out.mesh.is_closed(), "I = {iso}: not closed");
        assert!(
            out.volume <= last,
            "I = {iso}: volume {} > {last}",
            out.volume
        );
        last = out.volume;
    }
    assert!(last > 0.0);
}
