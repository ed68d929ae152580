//! Stage 3 of the CPU engine, sparse: Marching Cubes on a [`BrickVolume`], visiting only the
//! active bricks, with the same vertices and triangles in the same order as the dense
//! [`super::marching_cubes::extract`] (DESIGN section 2).
//!
//! Data flow: [`BrickVolume`] -> [`Mesh`] -> area and volume.
//!
//! The dense pass numbers vertices plane by plane, row by row, x fastest, and emits triangles
//! cell layer by cell layer, row by row, x fastest. Here each row is walked through the active
//! bricks of its brick row in ascending x, which visits the same crossed edges and non-empty
//! cells in the same order (an inactive brick has none: its whole 9³ footprint is on one side
//! of I). Slabs are whole brick layers; the slab logic (vertex ownership, [`FOREIGN`] indices,
//! merge) is that of [`super::marching_cubes`]. Inside flags are written only over the
//! footprints of the active bricks, which are all the flags the walk reads. Positions and
//! normals come from [`edge_geometry`] on the stored samples, colours from the per-layer vertex
//! colours [`BrickVolume`] prepared in this order.

use rayon::prelude::*;

use super::analytic::AnalyticField;
use super::bricks::{BRICK, BrickVolume};
use super::marching_cubes::{
    FOREIGN, McScratch, SlabMesh, VertexData, crossed_edges_in_row, edge_refs, push_cell_triangles,
    word,
};
use super::mc_vertex::{edge_geometry_refined, edge_position};
use super::tables::McTables;

/// Marching Cubes over the bricks of `vol` (vertices refined on the exact Gaussian sum `field`
/// when given), leaving each slab's share of the mesh in `scratch` (for `merge` or
/// `McScratch::measure`); no slab when the grid is degenerate.
pub(super) fn march_bricks(
    vol: &BrickVolume,
    field: Option<&AnalyticField>,
    data: VertexData,
    scratch: &mut McScratch,
) {
    let [nx, ny, nz] = vol.grid.dims.map(|d| d as usize);
    if nx < 2 || ny < 2 || nz < 2 {
        scratch.slabs.clear();
        return;
    }
    let layers = nz - 1;
    let threads = rayon::current_num_threads().max(1);
    let ranges = slab_ranges(vol, layers, threads, field.is_some());
    let ctx = Ctx {
        vol,
        iso: vol.iso,
        field,
        data,
        tables: McTables::get(),
    };
    scratch.slabs.resize_with(ranges.len(), SlabMesh::default);
    scratch
        .slabs
        .par_iter_mut()
        .zip(&ranges)
        .for_each(|(out, &(c0, c1))| ctx.slab(c0, c1, out));
}

/// The slabs of [`march_bricks`]: ranges `c0..c1` of its `layers` cell layers along z, whole
/// brick layers each, holding about equal shares of the active bricks, about eight slabs per
/// thread. Each slab has at least two brick layers (a slab starts by flagging and numbering
/// two planes, which on small grids costs as much as marching one), or one with `refined`
/// vertices, whose root finding makes an active brick far costlier. Shares of the work rather
/// than of the grid keep the threads busy when the surface fills only part of it, as a side of
/// an interface does on the complex's grid (7ddo's spike RBD under the SES preset, on two
/// cores: 16.6 ms of Marching Cubes per frame with slabs of two brick layers each, 14.4 ms
/// with these, 14.5 ms on its own grid). The mesh does not depend on where the slabs end.
fn slab_ranges(
    vol: &BrickVolume,
    layers: usize,
    threads: usize,
    refined: bool,
) -> Vec<(usize, usize)> {
    let per_layer: Vec<usize> = (0..vol.bdims[2])
        .map(|bk| {
            (0..vol.bdims[1])
                .map(|bj| vol.active_row(bk, bj).len())
                .sum()
        })
        .collect();
    let share = per_layer.iter().sum::<usize>().div_ceil(8 * threads).max(1);
    let least = if refined { 1 } else { 2 };
    let mut ranges = Vec::new();
    let (mut start, mut held, mut held_layers) = (0, 0, 0);
    for (bk, &active) in per_layer.iter().enumerate() {
        let end = ((bk + 1) * BRICK).min(layers);
        held += active;
        held_layers += 1;
        if end > start && (end == layers || (held >= share && held_layers >= least)) {
            ranges.push((start, end));
            (start, held, held_layers) = (end, 0, 0);
        }
        if end == layers {
            break;
        }
    }
    ranges
}

struct Ctx<'a> {
    vol: &'a BrickVolume,
    iso: f32,
    field: Option<&'a AnalyticField>,
    data: VertexData,
    tables: &'static McTables,
}

/// Position in the per-layer vertex colour lists.
struct ColourCursor {
    layer: usize,
    next: usize,
}

impl Ctx<'_> {
    /// Active bricks (x indices) of the brick row holding sample row `j` of plane `k`.
    fn row(&self, k: usize, j: usize) -> &[u32] {
        self.vol.active_row(k / BRICK, j / BRICK)
    }

    /// Inside flags of plane `k` over the footprints of the active bricks that read it.
    fn flags(&self, k: usize, out: &mut [u8]) {
        let [nx, ny, _] = self.vol.grid.dims.map(|d| d as usize);
        let by = self.vol.bdims[1];
        let bk = k / BRICK;
        let below = (k.is_multiple_of(BRICK) && bk > 0).then(|| bk - 1);
        for layer in std::iter::once(bk).chain(below) {
            for bj in 0..by {
                let row = self.vol.active_row(layer, bj);
                if row.is_empty() {
                    continue;
                }
                for j in bj * BRICK..=(bj * BRICK + BRICK).min(ny - 1) {
                    for &bi in row {
                        let i0 = bi as usize * BRICK;
                        let n = BRICK.min(nx - i0);
                        let dst = &mut out[j * nx + i0..j * nx + i0 + n];
                        match self.vol.brick_row(i0, j, k) {
                            Some(src) => {
                                for (f, &v) in dst.iter_mut().zip(src) {
                                    *f = u8::from(v >= self.iso);
                                }
                            }
                            None => dst.fill(0),
                        }
                        if i0 + BRICK < nx {
                            let v = self.vol.get(i0 + BRICK, j, k);
                            out[j * nx + i0 + BRICK] = u8::from(v >= self.iso);
                        }
                    }
                }
            }
        }
    }

    /// Cells of layers `c0..c1`; as [`super::marching_cubes`]'s slab, walking active bricks.
    fn slab(&self, c0: usize, c1: usize, out: &mut SlabMesh) {
        let [nx, ny, nz] = self.vol.grid.dims.map(|d| d as usize);
        let plane = nx * ny;
        let last = c1 == nz - 1;
        out.positions.clear();
        out.normals.clear();
        out.colours.clear();
        out.indices.clear();
        let mut cursor = ColourCursor {
            layer: usize::MAX,
            next: 0,
        };
        let [mut fa, mut fb, mut fc] = std::mem::take(&mut out.flags);
        let [mut cur, mut next] = std::mem::take(&mut out.maps);
        for f in [&mut fa, &mut fb, &mut fc] {
            f.resize(plane, 0);
        }
        for m in [&mut cur, &mut next] {
            m.resize(plane * 3, 0);
        }
        self.flags(c0, &mut fa);
        self.flags(c0 + 1, &mut fb);
        self.plane(c0, &fa, Some(&fb), &mut cur, Some(&mut *out), &mut cursor);
        let edge_ref = edge_refs(nx);
        for k in c0..c1 {
            let owned = k + 1 < c1 || last;
            let up = k + 2 < nz;
            if up {
                self.flags(k + 2, &mut fc);
            }
            let emit = owned.then_some(&mut *out);
            self.plane(
                k + 1,
                &fb,
                up.then_some(&fc[..]),
                &mut next,
                emit,
                &mut cursor,
            );
            let flag = if owned { 0 } else { FOREIGN };
            let (a, b) = (&fa, &fb);
            for j in 0..ny - 1 {
                let r = j * nx;
                let column = |i: usize| {
                    let p = r + i;
                    a[p] | a[p + nx] << 2 | b[p] << 4 | b[p + nx] << 6
                };
                for &bi in self.row(k, j) {
                    let i0 = bi as usize * BRICK;
                    let i1 = (i0 + BRICK).min(nx - 1);
                    if i0 + 9 <= nx && i1 == i0 + BRICK {
                        // Interior brick row: the cases of its 8 cells as the bytes of one
                        // word (corner flags are 0 or 1, so the shifted words never carry
                        // into the next byte), visited in order, skipping cells entirely
                        // inside or outside.
                        let columns = |q: usize| {
                            word(a, q)
                                | word(a, q + nx) << 2
                                | word(b, q) << 4
                                | word(b, q + nx) << 6
                        };
                        let cases = columns(r + i0) | columns(r + i0 + 1) << 1;
                        for (n, case) in cases.to_le_bytes().into_iter().enumerate() {
                            if case == 0 || case == 255 {
                                continue;
                            }
                            push_cell_triangles(
                                self.tables,
                                case,
                                r + i0 + n,
                                &edge_ref,
                                [&cur, &next],
                                flag,
                                &mut out.indices,
                            );
                        }
                        continue;
                    }
                    let mut left = column(i0);
                    for i in i0..i1 {
                        let right = column(i + 1);
                        let case = left | right << 1;
                        left = right;
                        if case == 0 || case == 255 {
                            continue;
                        }
                        let p = r + i;
                        push_cell_triangles(
                            self.tables,
                            case,
                            p,
                            &edge_ref,
                            [&cur, &next],
                            flag,
                            &mut out.indices,
                        );
                    }
                }
            }
            std::mem::swap(&mut cur, &mut next);
            std::mem::swap(&mut fa, &mut fb);
            std::mem::swap(&mut fb, &mut fc);
        }
        out.flags = [fa, fb, fc];
        out.maps = [cur, next];
    }

    /// As [`super::marching_cubes`]'s `plane`, over the points of the active bricks.
    fn plane(
        &self,
        k: usize,
        a: &[u8],
        up: Option<&[u8]>,
        map: &mut [u32],
        mut emit: Option<&mut SlabMesh>,
        cursor: &mut ColourCursor,
    ) {
        let [nx, ny, _] = self.vol.grid.dims.map(|d| d as usize);
        let mut count = emit.as_ref().map_or(0, |m| m.positions.len()) as u32;
        if emit.is_some() && cursor.layer != k / BRICK {
            *cursor = ColourCursor {
                layer: k / BRICK,
                next: 0,
            };
        }
        let colours = self.vol.layer_colours(k / BRICK);
        let mut add = |[i, j]: [usize; 2], p: usize, axis: usize| {
            map[p * 3 + axis] = count;
            count += 1;
            if let Some(m) = emit.as_deref_mut() {
                self.emit_vertex([i, j, k], axis, m, colours, cursor);
            }
        };
        for j in 0..ny {
            for &bi in self.row(k, j) {
                let i0 = bi as usize * BRICK;
                let i1 = (i0 + BRICK).min(nx);
                crossed_edges_in_row([nx, ny], j, i0..i1, a, up, &mut add);
            }
        }
    }

    /// Appends the vertex on the crossed edge from point `ijk` along `axis` to `m` (position,
    /// and normal and colour unless only positions are wanted).
    fn emit_vertex(
        &self,
        ijk: [usize; 3],
        axis: usize,
        m: &mut SlabMesh,
        colours: &[[f32; 3]],
        cursor: &mut ColourCursor,
    ) {
        let grid = &self.vol.grid;
        let [i, j, k] = ijk;
        if self.data == VertexData::PositionsOnly && self.field.is_none() {
            let mut b = ijk;
            b[axis] += 1;
            let va = self.vol.get(i, j, k);
            let vb = self.vol.get(b[0], b[1], b[2]);
            let (position, _) = edge_position(grid, va, vb, self.iso, ijk, axis);
            m.positions.push(position);
            return;
        }
        let value = |q: [usize; 3]| self.vol.get(q[0], q[1], q[2]);
        let (position, normal, _) =
            edge_geometry_refined(grid, value, self.iso, ijk, axis, self.field);
        m.positions.push(position);
        m.normals.push(normal);
        let colour = if self.vol.with_colour {
            let c = colours[cursor.next];
            cursor.next += 1;
            c
        } else {
            [1.0; 3]
        };
        m.colours.push(colour);
    }
}
