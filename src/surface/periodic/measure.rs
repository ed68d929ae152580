//! The volume per box of a periodic surface: the mesh from [`super::mc`] is open at the box
//! faces, so `sum v0 . (v1 x v2) / 6` does not apply. Instead, with `u` one axis and `v`, `w`
//! the next two (cyclically), the divergence theorem with `F = (x_u, 0, 0)` over the region
//! `rho >= I` inside the box gives
//!
//! `V = sum_triangles mean(x_u) n_u A + L_u * A_face`,
//!
//! where `n_u A` is the u-component of the triangle's area vector and `A_face` the area of the
//! region on the face `x_u = L_u` (F vanishes on `x_u = 0` and is parallel to the other faces).
//! That area follows from Green's theorem in the face with `G = (x_v, 0)`:
//!
//! `A_face = - sum_{mesh edges a->b on the face} mean(x_v) (x_w(b) - x_w(a)) + L_v * len`,
//!
//! the mesh edges on the face traversed by their triangles (so in the reverse of the face
//! region's positive orientation), and `len` the inside length of the box edge line
//! `x_u = L_u, x_v = L_v`, read from the samples on that line with the same linear
//! interpolation Marching Cubes uses. Every term is exact for the piecewise-linear surface, so
//! the result is the volume that mesh bounds in the box. Edges inside the face shared by two
//! triangles cancel, so only the open boundary counts.
//!
//! Triclinic cells ([`super::triclinic`]) use the same rule in index space, where the cell is
//! the box `[0, N_a] x [0, N_b] x [0, N_c]` with spacing 1, and multiply by `|det J|` (Å³ per
//! index-space unit volume, `J = [a/N_a, b/N_b, c/N_c]`): the affine map to Cartesian scales
//! every volume by it and maps the piecewise-linear surface onto the Cartesian mesh, so the
//! volume per cell is still exactly the region `rho >= I` inside the cell bounded by the mesh.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::density::PeriodicGrid;
use crate::surface::Mesh;
use crate::surface::mc_vertex::edge_t;

/// Volume (Å³) of the region `rho >= iso` inside one box, bounded by `mesh` (local positions,
/// as [`super::mc::extract`] returns them) and the box faces; `values` is the density on
/// `grid`. `axis` (0, 1, 2) picks the direction of the divergence-theorem field: every axis
/// gives the same volume up to rounding.
pub fn box_volume(mesh: &Mesh, grid: &PeriodicGrid, values: &[f32], iso: f32, axis: usize) -> f64 {
    let (u, v, w) = (axis % 3, (axis + 1) % 3, (axis + 2) % 3);
    let extent = grid.extent();
    let face = extent[u];
    const CHUNK: usize = 3 * 16384;
    let partial: Vec<(f64, f64)> = mesh
        .indices
        .par_chunks(CHUNK)
        .map(|chunk| {
            let (mut flux, mut green) = (0.0f64, 0.0f64);
            for t in chunk.chunks_exact(3) {
                let p: [Vec3; 3] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
                let d: [DVec3; 3] = p.map(|q| q.as_dvec3());
                let area_vector = 0.5 * (d[1] - d[0]).cross(d[2] - d[0]);
                flux += (d[0][u] + d[1][u] + d[2][u]) / 3.0 * area_vector[u];
                for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                    if p[a][u] == face && p[b][u] == face {
                        green -= 0.5 * (d[a][v] + d[b][v]) * (d[b][w] - d[a][w]);
                    }
                }
            }
            (flux, green)
        })
        .collect();
    let (flux, green) = partial
        .iter()
        .fold((0.0, 0.0), |(f, g), (pf, pg)| (f + pf, g + pg));
    let len = inside_length(grid, values, iso, w);
    let face_area = green + extent[v] as f64 * len;
    flux + face as f64 * face_area
}

/// Inside length (Å) of the grid line through sample `(0, 0, 0)` along `axis`: per edge, the
/// part on the inside of the linearly interpolated crossing.
fn inside_length(grid: &PeriodicGrid, values: &[f32], iso: f32, axis: usize) -> f64 {
    let n = grid.dims[axis] as usize;
    let h = grid.spacing[axis] as f64;
    let at = |k: usize| {
        let mut p = [0usize; 3];
        p[axis] = k;
        values[grid.index(p)]
    };
    (0..n)
        .map(|k| {
            let (va, vb) = (at(k), at(k + 1));
            let t = edge_t(va, vb, iso) as f64;
            match (va >= iso, vb >= iso) {
                (true, true) => h,
                (false, false) => 0.0,
                (true, false) => t * h,
                (false, true) => (1.0 - t) * h,
            }
        })
        .sum()
}
