//! The periodic engine in a triclinic cell (issue 30): density sampled along the cell vectors,
//! Marching Cubes in index space, the mesh mapped to Å with the cell matrix.
//!
//! Data flow: [`AtomSet`] + [`TriclinicCell`] + [`SurfaceParams`] -> images of every atom
//! whose cutoff sphere reaches the cell ([`images`]) -> density (and colour) at the samples
//! `origin + i/N_a a + j/N_b b + k/N_c c` ([`super::triclinic_fill::fill`]) -> [`super::mc::extract`] on the index
//! grid (spacing 1 along each axis, so vertex positions are `(i + t, j, k)` and so on) ->
//! per-cell volume in index space ([`super::measure::box_volume`]) times `|det J|` -> the mesh
//! (replicated in index space, so copies meet exactly) mapped to Cartesian by
//! `x = origin + J g`, `J = [a/N_a, b/N_b, c/N_c]`, normals by `J^-T` -> area of the Cartesian
//! triangles.
//!
//! Definitions (DESIGN section 2, every periodic image counted): `rho(x) = sum_i sum_n
//! exp(-|x - p_i - n M|^2 / (2 alpha_i^2))` over the pairs with `|x - p_i - n M| < q alpha_i`,
//! every image within the cutoff (not only the minimum image), the exponential of the full
//! squared distance in Å² (a polynomial within 1e-6 of it, [`super::triclinic_fill`]). The
//! affine map sends the piecewise-linear index-space surface onto
//! the Cartesian mesh, so the volume per cell is exactly the volume of the region `rho >= I`
//! inside the cell bounded by that mesh and the cell faces, the same rule as the rectangular
//! box's. Images are summed in a canonical order, so the atoms' order changes nothing.

use std::cmp::Ordering;
use std::time::Instant;

use glam::{DMat3, Vec3};
use rayon::prelude::*;

use super::cell::{TriclinicCell, images_reaching_cell};
use super::density::PeriodicGrid;
use super::triclinic_fill::fill;
use super::{Replicate, mc, measure, replicate_mesh};
use crate::surface::DensityVolume;
use crate::surface::{
    AtomSet, GridSpec, Mesh, StageTimings, SurfaceError, SurfaceOutput, SurfaceParams,
};

/// One atom image: index-space position, Cartesian position relative to the cell origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Image {
    /// Position in index space (samples along a, b, c).
    pub index: [f32; 3],
    /// Position relative to the cell origin (Å); may lie outside the cell.
    pub pos: Vec3,
    /// Exponent factor `0.5 / alpha^2` (Å⁻²).
    pub k: f32,
    /// Cutoff radius `q alpha` (Å).
    pub cut: f32,
    /// Linear RGB colour (white without colours).
    pub colour: [f32; 3],
}

/// The sampling geometry shared by the stages.
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    /// The cell.
    pub cell: TriclinicCell,
    /// Samples along a, b, c.
    pub dims: [u32; 3],
    /// Index space to Cartesian (columns `a / N_a` ... in Å).
    pub jac: DMat3,
    /// Half-width in samples of a sphere of radius 1 Å along each index axis (the norms of
    /// the rows of `J^-1`).
    pub reach: [f64; 3],
}

impl Geometry {
    /// The geometry of `cell` sampled with `dims`.
    pub fn new(cell: TriclinicCell, dims: [u32; 3]) -> Geometry {
        let jac = cell.index_matrix(dims);
        let inv = jac.inverse();
        Geometry {
            cell,
            dims,
            jac,
            reach: [inv.row(0), inv.row(1), inv.row(2)].map(|r| r.length()),
        }
    }

    /// The grid in index space (spacing 1), as Marching Cubes and the measures read it.
    pub fn index_grid(&self) -> PeriodicGrid {
        PeriodicGrid {
            origin: Vec3::ZERO,
            dims: self.dims,
            spacing: Vec3::ONE,
        }
    }
}

/// The images of `atoms` (validated) whose cutoff spheres reach the samples of the cell, in
/// canonical order (by index-space cell, z-major, then by the bits of the image's data).
pub fn images(atoms: &AtomSet<'_>, params: &SurfaceParams, geo: &Geometry) -> Vec<Image> {
    let q = params.cutoff();
    let inv = geo.cell.matrix().inverse();
    let dims = geo.dims.map(f64::from);
    let m = geo.cell.matrix();
    let [nx, ny, nz] = geo.dims;
    let cell = |g: f32, n: u32| ((g.floor().max(0.0)) as u64).min(n as u64 - 1);
    let key = |a: &Image| {
        (cell(a.index[2], nz) * ny as u64 + cell(a.index[1], ny)) * nx as u64 + cell(a.index[0], nx)
    };
    let mut keyed: Vec<(u64, Image)> = atoms
        .positions
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, &p)| {
            let alpha = atoms.radii[i] * params.radius_scale;
            let cut = q * alpha;
            let s = inv * (p - geo.cell.origin).as_dvec3();
            // Reach in fractional units plus one sample of margin.
            let r = [0, 1, 2].map(|a| cut as f64 * geo.reach[a] / dims[a] + 1.0 / dims[a]);
            let k = 0.5 / (alpha * alpha);
            let colour = atoms.colour(i);
            images_reaching_cell(s, r).map(move |f| {
                let image = Image {
                    index: (f * glam::DVec3::from(dims)).as_vec3().to_array(),
                    pos: (m * f).as_vec3(),
                    k,
                    cut,
                    colour,
                };
                (key(&image), image)
            })
        })
        .collect();
    let tie = |a: &Image, b: &Image| -> Ordering {
        (0..3)
            .map(|k| a.pos[k].total_cmp(&b.pos[k]))
            .chain(std::iter::once(a.k.total_cmp(&b.k)))
            .chain(std::iter::once(a.cut.total_cmp(&b.cut)))
            .chain((0..3).map(|k| a.colour[k].total_cmp(&b.colour[k])))
            .find(|o| o.is_ne())
            .unwrap_or(Ordering::Equal)
    };
    keyed.par_sort_unstable_by(|a, b| a.0.cmp(&b.0).then_with(|| tie(&a.1, &b.1)));
    keyed.into_par_iter().map(|(_, image)| image).collect()
}

/// Maps an index-space mesh to Cartesian (Å) for `geo`, `replicate` copies of the cell
/// shifted by whole cells in index space (so vertices on shared faces coincide exactly),
/// normals by `J^-T`, winding reversed for a left-handed cell.
pub fn to_cartesian(mesh: Mesh, geo: &Geometry, replicate: Replicate) -> Mesh {
    let extent = Vec3::new(geo.dims[0] as f32, geo.dims[1] as f32, geo.dims[2] as f32);
    let mut out = replicate_mesh(mesh, extent, replicate);
    let jac = geo.jac;
    let normal_map = jac.inverse().transpose();
    let origin = geo.cell.origin;
    out.positions
        .par_iter_mut()
        .for_each(|p| *p = (jac * p.as_dvec3()).as_vec3() + origin);
    out.normals.par_iter_mut().for_each(|n| {
        let m = (normal_map * n.as_dvec3()).normalize_or_zero().as_vec3();
        if m != Vec3::ZERO {
            *n = m;
        }
    });
    if jac.determinant() < 0.0 {
        for t in out.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    out
}

/// The periodic surface of `atoms` in the triclinic `cell` (see the module docs); area (Å²)
/// and volume (Å³) per cell times the number of images. `memory` is the byte limit for the
/// grid; `vol` keeps the density between calls.
pub fn compute(
    vol: &mut DensityVolume,
    memory: u64,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    cell: &TriclinicCell,
    replicate: Replicate,
) -> Result<SurfaceOutput, SurfaceError> {
    let dims = cell.samples(params.spacing);
    let with_colour = atoms.colours.is_some();
    super::check_grid(dims, with_colour, memory)?;
    let geo = Geometry::new(*cell, dims);
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let list = images(atoms, params, &geo);
    let bin_ms = ms(t);
    let t = Instant::now();
    fill(vol, &list, &geo, params.isovalue, with_colour);
    drop(list);
    let density_ms = ms(t);
    let t = Instant::now();
    let grid = geo.index_grid();
    let index_mesh = mc::extract(&grid, vol, params.isovalue);
    let volume = measure::box_volume(&index_mesh, &grid, &vol.values, params.isovalue, 0)
        * geo.jac.determinant().abs();
    super::check_replicas(index_mesh.positions.len(), replicate, "cell")?;
    let top = Vec3::from_array(dims.map(|n| n as f32 + 0.0));
    let (face_twins, unmatched) = super::seams::face_twins(&index_mesh.positions, top);
    let seams = super::PeriodicMesh {
        cell: *cell,
        replicate,
        cell_vertices: index_mesh.positions.len() as u32,
        cell_triangles: index_mesh.triangle_count() as u32,
        face_twins,
        unmatched,
    };
    let area = if replicate.is_one() {
        None
    } else {
        Some(to_cartesian(index_mesh.clone(), &geo, Replicate::default()).area())
    };
    let mesh = to_cartesian(index_mesh, &geo, replicate);
    let area = area.unwrap_or_else(|| mesh.area());
    let timings = StageTimings {
        exposure_ms: 0.0,
        upload_ms: 0.0,
        bin_ms,
        density_ms,
        mc_ms: ms(t),
    };
    let grid = GridSpec {
        origin: cell.origin,
        spacing: cell.spacing(dims).max_element(),
        dims,
    };
    Ok(super::periodic_output(
        grid,
        mesh,
        [area, volume],
        seams,
        timings,
    ))
}
