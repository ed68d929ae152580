//! Stage 3 of the CPU engine (the paper's `t_MC`): Marching Cubes on a [`DensityVolume`],
//! giving an indexed, closed [`Mesh`] with one vertex per crossed grid edge (DESIGN section 2).
//!
//! Data flow: [`DensityVolume`] + [`GridSpec`] + isovalue I -> [`Mesh`] -> area and volume
//! ([`Mesh::area`], [`Mesh::volume`]), export and rendering.
//!
//! Conventions are those of [`super::tables`]: a sample is inside when `rho >= I`; the vertex of
//! the edge from sample `a` to its neighbour `b = a + e_axis` belongs to `(a, axis)`.
//!
//! Parallelism: rayon over z-slabs of cells. A slab owns the vertices of the grid planes it
//! starts (the last slab also owns the top plane) and numbers them plane by plane, points x
//! fastest, axes x, y, z per point. Triangles of its top cell layer that use vertices of the next
//! slab's first plane refer to them by that slab's own numbering (which the slab recomputes for
//! that plane), so the merge just adds each slab's vertex offset: the result is the same as a
//! serial pass, for any slab size or thread count. Per-edge maps exist only for two planes per
//! slab at a time, never for the whole grid.

use glam::Vec3;
use rayon::prelude::*;

use super::analytic::AnalyticField;
use super::mc_vertex::{edge_position, edge_vertex_refined};
use super::tables::{EDGE_CORNERS, McTables, corner_offset, edge_axis};
use super::{DensityVolume, GridSpec, Mesh};

/// Marks a slab-local vertex index that belongs to the next slab's first plane.
pub(super) const FOREIGN: u32 = 1 << 31;

/// Case byte of every cell (`(nx-1) * (ny-1) * (nz-1)` entries, x fastest): bit `c` is set when
/// corner `c` (see [`super::tables`]) has `rho >= iso`. `values` is the density on `grid`.
pub fn classify(grid: &GridSpec, values: &[f32], iso: f32) -> Vec<u8> {
    let [nx, ny, nz] = grid.dims.map(|d| d as usize);
    if nx < 2 || ny < 2 || nz < 2 || values.len() < nx * ny * nz {
        return Vec::new();
    }
    let (cx, cy) = (nx - 1, ny - 1);
    let mut cases = vec![0u8; cx * cy * (nz - 1)];
    cases
        .par_chunks_mut(cx * cy)
        .enumerate()
        .for_each(|(k, out)| {
            for j in 0..cy {
                for i in 0..cx {
                    let mut case = 0u8;
                    for c in 0..8u8 {
                        let [dx, dy, dz] = corner_offset(c).map(|d| d as usize);
                        let p = (i + dx) + nx * ((j + dy) + ny * (k + dz));
                        if values[p] >= iso {
                            case |= 1 << c;
                        }
                    }
                    out[i + cx * j] = case;
                }
            }
        });
    cases
}

/// The isosurface `rho = iso` of `density` sampled on `grid`: positions (Å), outward unit normals,
/// colours (interpolated from the colour volume, white without one) and triangles wound
/// counter-clockwise seen from outside. An empty mesh when nothing crosses the isovalue.
pub fn extract(grid: &GridSpec, density: &DensityVolume, iso: f32) -> Mesh {
    extract_with(grid, density, iso, &mut McScratch::default())
}

/// What Marching Cubes records per vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum VertexData {
    /// Position, normal and colour: a mesh to draw or write.
    Full,
    /// Position only (no normal, no colour): enough for area, volume and counts
    /// ([`measure_slabs`]), for surfaces that are only measured. Positions are the same bits
    /// as in [`VertexData::Full`].
    PositionsOnly,
}

/// Working memory of [`extract_with`] (the per-plane buffers of each slab), kept between calls
/// so that repeated extractions (one per frame) do not allocate them again.
#[derive(Default)]
pub struct McScratch {
    pub(super) slabs: Vec<SlabMesh>,
}

/// [`extract`] reusing the buffers in `scratch`; gives the same mesh.
pub fn extract_with(
    grid: &GridSpec,
    density: &DensityVolume,
    iso: f32,
    scratch: &mut McScratch,
) -> Mesh {
    extract_refined(grid, density, iso, None, scratch)
}

/// [`extract_with`], with every vertex refined on the exact Gaussian sum `field` when given
/// ([`super::mc_vertex::edge_geometry_refined`]): same triangles and indices, positions on the
/// analytic surface, analytic normals.
pub fn extract_refined(
    grid: &GridSpec,
    density: &DensityVolume,
    iso: f32,
    field: Option<&AnalyticField>,
    scratch: &mut McScratch,
) -> Mesh {
    march_dense(grid, density, iso, field, VertexData::Full, scratch);
    merge(&mut scratch.slabs)
}

/// The slab walk of [`extract_refined`], leaving each slab's share of the mesh in
/// `scratch` (for [`merge`] or [`measure_slabs`]); no slab when nothing can be extracted.
pub(super) fn march_dense(
    grid: &GridSpec,
    density: &DensityVolume,
    iso: f32,
    field: Option<&AnalyticField>,
    data: VertexData,
    scratch: &mut McScratch,
) {
    let [nx, ny, nz] = grid.dims.map(|d| d as usize);
    let enough = density.values.len() >= nx * ny * nz
        && density
            .colours
            .as_ref()
            .is_none_or(|c| c.len() >= nx * ny * nz);
    if nx < 2 || ny < 2 || nz < 2 || !enough {
        scratch.slabs.clear();
        return;
    }
    let layers = nz - 1;
    let threads = rayon::current_num_threads().max(1);
    let planes = (layers / (8 * threads)).clamp(1, 64);
    let slabs = layers.div_ceil(planes);
    let ctx = Ctx {
        grid,
        density,
        iso,
        field,
        data,
        tables: McTables::get(),
    };
    scratch.slabs.resize_with(slabs, SlabMesh::default);
    scratch
        .slabs
        .par_iter_mut()
        .enumerate()
        .for_each(|(s, out)| march_slab(&ctx, s * planes, ((s + 1) * planes).min(layers), out));
}

impl McScratch {
    /// Measures the mesh of the last slab walk without assembling it ([`measure_slabs`]).
    pub(super) fn measure(&self) -> MeshMeasure {
        measure_slabs(&self.slabs)
    }

    /// Assembles the mesh of the last slab walk ([`merge`]).
    pub(super) fn merge(&mut self) -> Mesh {
        merge(&mut self.slabs)
    }
}

/// What every slab reads.
struct Ctx<'a> {
    grid: &'a GridSpec,
    density: &'a DensityVolume,
    iso: f32,
    field: Option<&'a AnalyticField>,
    data: VertexData,
    tables: &'static McTables,
}

/// One slab's share of the mesh, vertex indices local (or [`FOREIGN`]-flagged), plus its
/// per-plane working buffers.
#[derive(Default)]
pub(super) struct SlabMesh {
    pub(super) positions: Vec<Vec3>,
    pub(super) normals: Vec<Vec3>,
    pub(super) colours: Vec<[f32; 3]>,
    pub(super) indices: Vec<u32>,
    /// Inside flags of three consecutive planes.
    pub(super) flags: [Vec<u8>; 3],
    /// Edge maps of two consecutive planes.
    pub(super) maps: [Vec<u32>; 2],
}

/// For each cell edge: (plane 0 or 1 of the cell, offset of its start point within the plane
/// for planes `nx` points wide, axis), to find the edge's vertex in the per-plane edge maps.
pub(super) type EdgeRefs = [(usize, usize, usize); 12];

/// The [`EdgeRefs`] of planes `nx` points wide.
pub(super) fn edge_refs(nx: usize) -> EdgeRefs {
    std::array::from_fn(|e| {
        let [dx, dy, dz] = corner_offset(EDGE_CORNERS[e][0]).map(|d| d as usize);
        (dz, dx + dy * nx, edge_axis(e as u8) as usize)
    })
}

/// Appends the triangles of Marching Cubes `case` for the cell whose first point is `p` (flat
/// index in its plane): vertex indices come from the edge maps of the cell's lower and upper
/// planes (`maps`), the upper plane's tagged with `flag` ([`FOREIGN`] when another slab owns
/// it). Shared by the dense and the brick-sparse extraction, so both emit the same triangles.
pub(super) fn push_cell_triangles(
    tables: &McTables,
    case: u8,
    p: usize,
    edge_ref: &EdgeRefs,
    maps: [&[u32]; 2],
    flag: u32,
    indices: &mut Vec<u32>,
) {
    for tri in tables.case_triangles(case) {
        for &e in tri {
            let (dz, off, axis) = edge_ref[e as usize];
            let idx = if dz == 0 {
                maps[0][(p + off) * 3 + axis]
            } else {
                maps[1][(p + off) * 3 + axis] | flag
            };
            indices.push(idx);
        }
    }
}

/// Eight inside flags (bytes 0 or 1) starting at `q`, as one word.
pub(super) fn word(flags: &[u8], q: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&flags[q..q + 8]);
    u64::from_le_bytes(b)
}

/// Eight flags that are all 1.
pub(super) const ALL_ONE: u64 = 0x0101_0101_0101_0101;

impl PlaneSource for Ctx<'_> {
    fn points(&self) -> [usize; 3] {
        self.grid.dims.map(|d| d as usize)
    }

    fn tables(&self) -> &McTables {
        self.tables
    }

    /// Inside flags (1 when `rho >= iso`) of plane `k`.
    fn flags(&self, k: usize, out: &mut [u8]) {
        let plane = out.len();
        let v = &self.density.values[k * plane..(k + 1) * plane];
        for (flag, &x) in out.iter_mut().zip(v) {
            *flag = u8::from(x >= self.iso);
        }
    }

    /// Fills `map` with the index of each crossed edge starting on plane `k` (inside flags `a`,
    /// flags of plane `k + 1` in `up` unless `k` is the top plane), numbered from the slab's
    /// current vertex count when `emit` is given (and the vertex is appended), else from 0 (the
    /// next slab's numbering of its first plane). Entries of uncrossed edges are left as they were.
    fn plane(
        &self,
        k: usize,
        a: &[u8],
        up: Option<&[u8]>,
        map: &mut [u32],
        mut emit: Option<&mut SlabMesh>,
    ) {
        let [nx, ny, _] = self.grid.dims.map(|d| d as usize);
        let mut count = emit.as_ref().map_or(0, |m| m.positions.len()) as u32;
        crossed_edges([nx, ny], a, up, |[i, j], p, axis| {
            map[p * 3 + axis] = count;
            count += 1;
            let Some(m) = emit.as_deref_mut() else {
                return;
            };
            if self.data == VertexData::PositionsOnly && self.field.is_none() {
                let v = &self.density.values;
                let at = k * nx * ny + p;
                let (va, vb) = (v[at], v[at + [1, nx, nx * ny][axis]]);
                let (position, _) = edge_position(self.grid, va, vb, self.iso, [i, j, k], axis);
                m.positions.push(position);
                return;
            }
            let vert = edge_vertex_refined(
                self.grid,
                self.density,
                self.iso,
                [i, j, k],
                axis,
                self.field,
            );
            m.positions.push(vert.position);
            m.normals.push(vert.normal);
            m.colours.push(vert.colour);
        });
    }
}

/// Calls `visit([i, j], p, axis)` for each grid edge starting on a plane of `nx` by `ny` points
/// (inside flags `a`, those of the plane above in `up` unless it is the top plane) whose two
/// ends differ, in order of point `p = i + nx j` and then axis (0 x, 1 y, 2 z).
pub(super) fn crossed_edges(
    [nx, ny]: [usize; 2],
    a: &[u8],
    up: Option<&[u8]>,
    mut visit: impl FnMut([usize; 2], usize, usize),
) {
    for j in 0..ny {
        crossed_edges_in_row([nx, ny], j, 0..nx, a, up, &mut visit);
    }
}

/// [`crossed_edges`] for the points `i` in `range` of row `j` only.
pub(super) fn crossed_edges_in_row(
    [nx, ny]: [usize; 2],
    j: usize,
    range: std::ops::Range<usize>,
    a: &[u8],
    up: Option<&[u8]>,
    mut visit: impl FnMut([usize; 2], usize, usize),
) {
    let r = j * nx;
    let mut i = range.start;
    while i < range.end {
        if i + 9 <= nx
            && i + 8 <= range.end
            && j + 1 < ny
            && let Some(u) = up
        {
            // Eight points at once: their crossed edges as bits (byte `n` for point `i + n`,
            // bit 0/1/2 for its x/y/z edge), visited in increasing order, as point by point.
            let w = word(a, r + i);
            let x = w ^ word(a, r + i + 1);
            let y = w ^ word(a, r + nx + i);
            let z = w ^ word(u, r + i);
            let mut bits = x | y << 1 | z << 2;
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                visit([i + b / 8, j], r + i + b / 8, b % 8);
            }
            i += 8;
            continue;
        }
        let p = r + i;
        let f = a[p];
        let crossed = [
            i + 1 < nx && a[p + 1] != f,
            j + 1 < ny && a[p + nx] != f,
            up.is_some_and(|u| u[p] != f),
        ];
        for (axis, &c) in crossed.iter().enumerate() {
            if c {
                visit([i, j], p, axis);
            }
        }
        i += 1;
    }
}

/// Joins the slabs in order, turning local indices into global ones. Each slab's vertex and
/// index buffers are freed as soon as they are copied, and the output only reserves its
/// capacity up front, so memory holds about one copy of the mesh rather than two.
pub(super) fn merge(parts: &mut [SlabMesh]) -> Mesh {
    let total: usize = parts.iter().map(|p| p.positions.len()).sum();
    let tri_total: usize = parts.iter().map(|p| p.indices.len()).sum();
    let mut mesh = Mesh {
        positions: Vec::with_capacity(total),
        normals: Vec::with_capacity(total),
        colours: Vec::with_capacity(total),
        indices: Vec::with_capacity(tri_total),
    };
    for p in parts.iter_mut() {
        let own = mesh.positions.len() as u32;
        let next = own + p.positions.len() as u32;
        mesh.indices.extend(p.indices.iter().map(|&i| {
            if i & FOREIGN != 0 {
                next + (i & !FOREIGN)
            } else {
                own + i
            }
        }));
        mesh.positions.extend_from_slice(&p.positions);
        mesh.normals.extend_from_slice(&p.normals);
        mesh.colours.extend_from_slice(&p.colours);
        p.positions = Vec::new();
        p.normals = Vec::new();
        p.colours = Vec::new();
        p.indices = Vec::new();
    }
    mesh
}

/// Area, volume and size of a mesh that was measured without being assembled (see
/// [`measure_slabs`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MeshMeasure {
    /// Surface area in Å².
    pub area: f64,
    /// Enclosed volume in Å³.
    pub volume: f64,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Triangles of the mesh.
    pub triangles: usize,
}

/// Measures the mesh that [`merge`] would build from `parts`, without building it: triangles
/// are visited in merged order, in the same fixed chunks as [`Mesh::area_and_volume`], so area
/// and volume are bitwise those of the merged mesh. For runs that only report area and volume
/// (no mesh written), this saves the merged copy of the mesh (a third of the peak memory of a
/// million-atom frame) and the time to build it.
pub(super) fn measure_slabs(parts: &[SlabMesh]) -> MeshMeasure {
    use super::mesh::{MEASURE_CHUNK_TRIANGLES, accumulate_area_volume};
    // First global triangle of each slab, plus the total at the end.
    let mut starts = Vec::with_capacity(parts.len() + 1);
    let mut total = 0usize;
    for p in parts {
        starts.push(total);
        total += p.indices.len() / 3;
    }
    starts.push(total);
    // Position of local vertex `i` of slab `s`; a FOREIGN index counts on into the vertices
    // of the following slabs, as `merge` numbers them.
    let position = |s: usize, i: u32| -> Vec3 {
        if i & FOREIGN == 0 {
            return parts[s].positions[i as usize];
        }
        let (mut k, mut local) = (s + 1, (i & !FOREIGN) as usize);
        while local >= parts[k].positions.len() {
            local -= parts[k].positions.len();
            k += 1;
        }
        parts[k].positions[local]
    };
    let chunks = total.div_ceil(MEASURE_CHUNK_TRIANGLES);
    let partial: Vec<(f64, f64)> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let end = ((c + 1) * MEASURE_CHUNK_TRIANGLES).min(total);
            let mut t = c * MEASURE_CHUNK_TRIANGLES;
            let mut s = starts.partition_point(|&x| x <= t) - 1;
            let mut sums = (0.0, 0.0);
            while t < end {
                while starts[s + 1] <= t {
                    s += 1;
                }
                let stop = end.min(starts[s + 1]);
                let local = &parts[s].indices[3 * (t - starts[s])..3 * (stop - starts[s])];
                sums = accumulate_area_volume(sums, local, |i| position(s, i));
                t = stop;
            }
            sums
        })
        .collect();
    let (area, volume) = partial
        .iter()
        .fold((0.0, 0.0), |(a, v), (pa, pv)| (a + pa, v + pv));
    MeshMeasure {
        area,
        volume,
        vertices: parts.iter().map(|p| p.positions.len()).sum(),
        triangles: total,
    }
}

/// What the slab walk ([`march_slab`]) needs from a sampled field: the size of its point grid,
/// the inside flags of each point plane, and the numbering (and emission) of the crossed edges
/// starting on a plane. The dense grid and the periodic box grid both provide it.
pub(super) trait PlaneSource: Sync {
    /// Points per axis.
    fn points(&self) -> [usize; 3];
    /// The case tables.
    fn tables(&self) -> &McTables;
    /// Inside flags (0 or 1) of point plane `k`.
    fn flags(&self, k: usize, out: &mut [u8]);
    /// Numbers the crossed edges starting on plane `k` (flags `a`, flags of plane `k + 1` in
    /// `up` unless `k` is the top plane) into `map`, appending their vertices to `emit` when
    /// given (else numbering from 0: the next slab's numbering of its first plane).
    fn plane(
        &self,
        k: usize,
        a: &[u8],
        up: Option<&[u8]>,
        map: &mut [u32],
        emit: Option<&mut SlabMesh>,
    );
}

/// Marching Cubes over the cell layers `c0..c1` of `src` (layer k between point planes k and
/// k + 1) into `out`: vertices of the edges the slab owns, triangles of its cells, skipping
/// runs of 8 cells whose corners are all inside or all outside.
pub(super) fn march_slab(src: &impl PlaneSource, c0: usize, c1: usize, out: &mut SlabMesh) {
    let [nx, ny, nz] = src.points();
    let plane = nx * ny;
    let last = c1 == nz - 1;
    out.positions.clear();
    out.normals.clear();
    out.colours.clear();
    out.indices.clear();
    // Inside flags of planes k, k + 1, k + 2 and edge maps of planes k, k + 1.
    let [mut fa, mut fb, mut fc] = std::mem::take(&mut out.flags);
    let [mut cur, mut next] = std::mem::take(&mut out.maps);
    for f in [&mut fa, &mut fb, &mut fc] {
        f.resize(plane, 0);
    }
    for m in [&mut cur, &mut next] {
        m.resize(plane * 3, 0);
    }
    src.flags(c0, &mut fa);
    src.flags(c0 + 1, &mut fb);
    src.plane(c0, &fa, Some(&fb), &mut cur, Some(&mut *out));
    let edge_ref = edge_refs(nx);
    for k in c0..c1 {
        let owned = k + 1 < c1 || last;
        let up = k + 2 < nz;
        if up {
            src.flags(k + 2, &mut fc);
        }
        let emit = owned.then_some(&mut *out);
        src.plane(k + 1, &fb, up.then_some(&fc[..]), &mut next, emit);
        let flag = if owned { 0 } else { FOREIGN };
        let (a, b) = (&fa, &fb);
        for j in 0..ny - 1 {
            let r = j * nx;
            let column = |i: usize| {
                let p = r + i;
                a[p] | a[p + nx] << 2 | b[p] << 4 | b[p + nx] << 6
            };
            let mut i = 0;
            let mut left = column(0);
            while i < nx - 1 {
                if i + 9 <= nx {
                    let ws = [r + i, r + i + 1, r + nx + i, r + nx + i + 1];
                    let (mut or, mut and) = (0u64, u64::MAX);
                    for q in ws {
                        for f in [a, b] {
                            let w = word(f, q);
                            or |= w;
                            and &= w;
                        }
                    }
                    if or == 0 || and == ALL_ONE {
                        i += 8;
                        left = column(i);
                        continue;
                    }
                }
                let right = column(i + 1);
                let case = left | right << 1;
                left = right;
                let p = r + i;
                i += 1;
                if case == 0 || case == 255 {
                    continue;
                }
                push_cell_triangles(
                    src.tables(),
                    case,
                    p,
                    &edge_ref,
                    [&cur, &next],
                    flag,
                    &mut out.indices,
                );
            }
        }
        std::mem::swap(&mut cur, &mut next);
        std::mem::swap(&mut fa, &mut fb);
        std::mem::swap(&mut fb, &mut fc);
    }
    out.flags = [fa, fb, fc];
    out.maps = [cur, next];
}
