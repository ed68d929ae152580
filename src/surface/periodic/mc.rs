//! Stage 3 of the periodic engine: Marching Cubes over every cell of the periodic grid, with
//! wrap-around (cell `N - 1`'s upper corners are samples 0), giving the mesh inside one box.
//!
//! Data flow: [`DensityVolume`] + [`PeriodicGrid`] + I -> [`Mesh`] (local coordinates, Å from
//! the box origin) -> area and volume ([`super::measure`]).
//!
//! The walk is that of [`crate::surface::marching_cubes`] on the `(N_x + 1) x (N_y + 1) x
//! (N_z + 1)` points of the box, where point `N` along an axis reads sample 0: the same case
//! tables, cell triangles ([`push_cell_triangles`]), slab ownership of vertices and merge, so
//! the mesh is indexed and every edge inside the box belongs to two triangles. Vertices on the
//! faces `x = L_x` (and y, z) are copies of those on `x = 0` moved by `L`, so the mesh is open
//! at the faces and `a x b x c` copies side by side join without gaps. Vertex positions are
//! interpolated along the edge with the local coordinate `(index + t) h` (Å), so every vertex
//! on the upper face has exactly the coordinate `N h`; normals come from central differences
//! that wrap around the box, so both copies of a face vertex get the same normal.

use glam::Vec3;
use rayon::prelude::*;

use super::density::PeriodicGrid;
use crate::surface::DensityVolume;
use crate::surface::Mesh;
use crate::surface::marching_cubes::{PlaneSource, SlabMesh, crossed_edges, march_slab, merge};
use crate::surface::mc_vertex::{edge_t, interpolated_normal, lerp_colour};
use crate::surface::tables::McTables;

/// The isosurface `rho = iso` of `vol` inside one box of `grid`, positions local (Å from the
/// box origin), outward unit normals, colours (white without a colour volume).
pub fn extract(grid: &PeriodicGrid, vol: &DensityVolume, iso: f32) -> Mesh {
    if vol.values.len() != grid.len()
        || vol.colours.as_ref().is_some_and(|c| c.len() != grid.len())
        || grid.is_empty()
    {
        return Mesh::default();
    }
    let layers = grid.dims[2] as usize;
    let threads = rayon::current_num_threads().max(1);
    let planes = (layers / (8 * threads)).clamp(1, 64);
    let slabs = layers.div_ceil(planes);
    let ctx = Ctx {
        grid,
        vol,
        iso,
        tables: McTables::get(),
        points: grid.dims.map(|d| d as usize + 1),
    };
    let mut parts: Vec<SlabMesh> = (0..slabs).map(|_| SlabMesh::default()).collect();
    parts
        .par_iter_mut()
        .enumerate()
        .for_each(|(s, out)| march_slab(&ctx, s * planes, ((s + 1) * planes).min(layers), out));
    merge(&mut parts)
}

/// What every slab reads.
struct Ctx<'a> {
    grid: &'a PeriodicGrid,
    vol: &'a DensityVolume,
    iso: f32,
    tables: &'static McTables,
    /// Points per axis, `N + 1`.
    points: [usize; 3],
}

/// One mesh vertex.
pub struct Vertex {
    /// Local position (Å from the box origin).
    pub position: Vec3,
    /// Unit outward normal.
    pub normal: Vec3,
    /// Linear RGB colour.
    pub colour: [f32; 3],
}

/// The vertex on the edge from point `a` (any non-negative indices; read modulo the grid) to
/// `a + e_axis`: position `(a + t e_axis) h` (Å), normal the [`interpolated_normal`] of the
/// central differences (wrapping around the box), colour interpolated along the edge. The edge
/// must be crossed (`rho(a) >= iso` differs from `rho(b) >= iso`).
pub fn periodic_edge_vertex(
    grid: &PeriodicGrid,
    vol: &DensityVolume,
    iso: f32,
    a: [usize; 3],
    axis: usize,
) -> Vertex {
    let v = |p: [usize; 3]| vol.values[grid.index(p)];
    let mut b = a;
    b[axis] += 1;
    let (va, vb) = (v(a), v(b));
    let t = edge_t(va, vb, iso);
    let h = grid.spacing;
    let mut position = Vec3::ZERO;
    for k in 0..3 {
        let along = if k == axis { t } else { 0.0 };
        position[k] = (a[k] as f32 + along) * h[k];
    }
    let n = grid.dims.map(|d| d as usize);
    let gradient = |p: [usize; 3]| {
        let mut g = Vec3::ZERO;
        for k in 0..3 {
            let (mut lo, mut hi) = (p, p);
            lo[k] = (p[k] % n[k] + n[k] - 1) % n[k];
            hi[k] = p[k] + 1;
            g[k] = (v(hi) - v(lo)) / (2.0 * h[k]);
        }
        g
    };
    let normal = interpolated_normal(gradient(a), gradient(b), t, axis, va >= iso);
    let colour = match &vol.colours {
        Some(c) => lerp_colour(c[grid.index(a)], c[grid.index(b)], t),
        None => [1.0; 3],
    };
    Vertex {
        position,
        normal,
        colour,
    }
}

impl PlaneSource for Ctx<'_> {
    fn points(&self) -> [usize; 3] {
        self.points
    }

    fn tables(&self) -> &McTables {
        self.tables
    }

    /// Inside flags (1 when `rho >= iso`) of point plane `k` (`N_x + 1` by `N_y + 1`).
    fn flags(&self, k: usize, out: &mut [u8]) {
        let [px, py, _] = self.points;
        let [nx, ny, nz] = self.grid.dims.map(|d| d as usize);
        let src = &self.vol.values[(k % nz) * nx * ny..(k % nz + 1) * nx * ny];
        for j in 0..py {
            let row = &src[(j % ny) * nx..(j % ny + 1) * nx];
            let dst = &mut out[j * px..(j + 1) * px];
            for (f, &x) in dst.iter_mut().zip(row) {
                *f = u8::from(x >= self.iso);
            }
            dst[px - 1] = u8::from(row[0] >= self.iso);
        }
    }

    /// Numbers the crossed edges starting on point plane `k` (flags `a`, flags of plane
    /// `k + 1` in `up` unless `k` is the top plane) into `map`, appending their vertices to
    /// `emit` when given (else numbering from 0: the next slab's numbering of its first plane).
    fn plane(
        &self,
        k: usize,
        a: &[u8],
        up: Option<&[u8]>,
        map: &mut [u32],
        mut emit: Option<&mut SlabMesh>,
    ) {
        let [nx, ny, _] = self.points;
        let mut count = emit.as_ref().map_or(0, |m| m.positions.len()) as u32;
        crossed_edges([nx, ny], a, up, |[i, j], p, axis| {
            map[p * 3 + axis] = count;
            count += 1;
            if let Some(m) = emit.as_deref_mut() {
                let v = periodic_edge_vertex(self.grid, self.vol, self.iso, [i, j, k], axis);
                m.positions.push(v.position);
                m.normals.push(v.normal);
                m.colours.push(v.colour);
            }
        });
    }
}
