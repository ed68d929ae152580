//! Stage 2 of the CPU engine, sparse: the density sampled only in the bricks of the grid that
//! some atom reaches, plus what Marching Cubes needs to skip the rest (DESIGN section 2 defines
//! the values; this module only decides where they are stored).
//!
//! Data flow: [`AtomBins`] (binned by brick layers, one plane of overlap) -> [`BrickVolume`] ->
//! sparse Marching Cubes ([`super::brick_mc`]).
//!
//! Layout: the grid is cut into bricks of [`BRICK`]³ samples (brick `(I, J, K)` holds samples
//! `8I..8I+8` by `8J..` by `8K..`, clamped to the grid). A brick is *occupied* when the
//! conservative sample box ([`sample_range`]) of some atom overlaps it; every other brick's
//! samples are exactly 0 in the dense volume, so they are neither computed nor stored. Occupied
//! bricks are stored one after another (512 f32 each, x fastest) in brick order (K, then J,
//! then I); a slot table maps bricks to them. A brick is *active* when its samples plus the
//! one-sample overlap with its +x, +y, +z neighbours (the 9³ footprint every Marching Cubes cell
//! and edge starting in it reads) are not all on one side of I; only active bricks are marched.
//!
//! Values: each brick layer (8 planes plus the first plane of the next layer) is filled by the
//! same kernel as the dense volume ([`super::density::fill_planes`]) with the atoms that reach
//! it in canonical order, so every stored sample has the same bits as in
//! [`super::density::compute`]. Colours are not stored per sample: while a layer's colour sums
//! are at hand, the colour of every vertex Marching Cubes will place on that layer's crossed
//! edges is interpolated (the formula of [`super::mc_vertex::edge_vertex_refined`]) and kept in the
//! order Marching Cubes numbers the vertices, 12 bytes per vertex instead of 12 per sample.
//!
//! Parallelism: rayon over groups of brick layers ([`slab_planes`]), each filled in one pass
//! into a per-thread scratch of its planes plus one; the slots, active lists and colours of a
//! layer depend only on the samples, so the result is the same for any grouping or thread
//! count.

use std::sync::Mutex;

use rayon::prelude::*;

mod active;
mod difference;

use active::LayerMasks;

use super::bin::{AtomBins, sample_range};
use super::density::{SampleLattice, fill_planes};
use super::mc_vertex::{edge_t, lerp_colour};
use super::{GridSpec, SurfaceParams};

/// Samples per brick along each axis.
pub const BRICK: usize = 8;
/// Samples per brick.
pub const BRICK_SAMPLES: usize = BRICK * BRICK * BRICK;
/// Slot of a brick that is not stored.
const EMPTY: u32 = u32::MAX;

/// Grid planes per atom slab for [`BrickVolume::compute`]: a whole number of brick layers,
/// computed in one pass (fewer passes over each atom and fewer shared planes), as many as keep
/// a thread's scratch (16 bytes per sample) near 32 MB and leave two groups per thread (fewer
/// passes over each atom on small grids, where each atom spans more than one brick layer).
pub fn slab_planes(grid: &GridSpec) -> u32 {
    let [nx, ny, nz] = grid.dims.map(|d| d as usize);
    let layer_bytes = (nx * ny * BRICK * 16).max(1);
    let threads = rayon::current_num_threads().max(1);
    let by_memory = (32 << 20) / layer_bytes;
    let by_balance = nz.div_ceil(BRICK) / (2 * threads);
    (by_memory.min(by_balance).clamp(1, 4) * BRICK) as u32
}

/// How much of the grid the sparse engine touched.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BrickStats {
    /// Samples per brick edge.
    pub brick_size: u32,
    /// Bricks covering the grid.
    pub bricks: u64,
    /// Bricks some atom reaches (computed and stored).
    pub occupied: u64,
    /// Bricks that the isosurface crosses (marched).
    pub active: u64,
}

impl BrickStats {
    /// Occupied bricks over all bricks (0..1).
    pub fn occupied_fraction(&self) -> f64 {
        self.occupied as f64 / self.bricks.max(1) as f64
    }

    /// Active (marched) bricks over all bricks (0..1).
    pub fn active_fraction(&self) -> f64 {
        self.active as f64 / self.bricks.max(1) as f64
    }
}

/// The active bricks of one brick layer and the vertex colours of its crossed edges.
#[derive(Debug, Clone, Default)]
struct Layer {
    /// `row_start[J]..row_start[J + 1]` indexes `cols` for brick row J.
    row_start: Vec<u32>,
    /// Brick x indices I of the active bricks, ascending within each row.
    cols: Vec<u32>,
    /// Colour of each vertex on a crossed edge starting in this layer, in Marching Cubes order.
    colours: Vec<[f32; 3]>,
}

/// A density volume stored in occupied bricks only, with the active brick lists.
#[derive(Debug, Clone, Default)]
pub struct BrickVolume {
    /// The grid the samples belong to.
    pub grid: GridSpec,
    /// Bricks along x, y, z.
    pub bdims: [usize; 3],
    /// Isovalue the active lists and vertex colours were made for.
    pub iso: f32,
    /// Whether vertex colours were computed.
    pub with_colour: bool,
    slots: Vec<u32>,
    data: Vec<f32>,
    layers: Vec<Layer>,
    stats: BrickStats,
}

/// Per-thread working memory of [`BrickVolume::compute`] (9 planes of density and colour sums).
#[derive(Default)]
pub struct BrickScratch {
    threads: Vec<Mutex<LayerScratch>>,
}

#[derive(Default)]
struct LayerScratch {
    vals: Vec<f32>,
    /// Colour sums, one plane per channel (see [`super::density::ColourPlanes`]).
    cols: [Vec<f32>; 3],
}

impl BrickVolume {
    /// Occupied and active brick counts of the last computation.
    pub fn stats(&self) -> BrickStats {
        self.stats
    }

    /// Bytes held by the stored bricks and slot table.
    pub fn stored_bytes(&self) -> u64 {
        (self.data.len() * 4 + self.slots.len() * 4) as u64
    }

    /// Density at sample (i, j, k); 0 outside the occupied bricks (exactly the dense value).
    #[inline(always)]
    pub fn get(&self, i: usize, j: usize, k: usize) -> f32 {
        let [bx, by, _] = self.bdims;
        let b = ((k >> 3) * by + (j >> 3)) * bx + (i >> 3);
        let s = self.slots[b];
        if s == EMPTY {
            0.0
        } else {
            self.data[s as usize * BRICK_SAMPLES + (((k & 7) << 6) | ((j & 7) << 3) | (i & 7))]
        }
    }

    /// The 8 stored samples `i0..i0 + 8` of row (j, k), `i0` a multiple of [`BRICK`]; `None`
    /// when their brick is not occupied (all 0). Entries past the grid's end are 0.
    #[inline]
    pub fn brick_row(&self, i0: usize, j: usize, k: usize) -> Option<&[f32; BRICK]> {
        let [bx, by, _] = self.bdims;
        let b = ((k >> 3) * by + (j >> 3)) * bx + (i0 >> 3);
        let s = self.slots[b];
        if s == EMPTY {
            return None;
        }
        let o = s as usize * BRICK_SAMPLES + (((k & 7) << 6) | ((j & 7) << 3));
        self.data[o..o + BRICK].try_into().ok()
    }

    /// X indices of the active bricks in brick row `bj` of brick layer `bk`, ascending.
    pub fn active_row(&self, bk: usize, bj: usize) -> &[u32] {
        let l = &self.layers[bk];
        &l.cols[l.row_start[bj] as usize..l.row_start[bj + 1] as usize]
    }

    /// Vertex colours of brick layer `bk` in Marching Cubes order (empty without colours).
    pub fn layer_colours(&self, bk: usize) -> &[[f32; 3]] {
        &self.layers[bk].colours
    }

    /// Samples the density of `bins` (made by [`super::bin::bin_atoms_overlapping`] with
    /// [`slab_planes`] planes per slab, a multiple of [`BRICK`], and an overlap of 1) on the occupied bricks of `grid`, finds
    /// the active bricks for isovalue `params.isovalue` and, when `with_colour`, the colours of
    /// the vertices Marching Cubes will place. Reuses the buffers of `self` and `scratch`.
    pub fn compute(
        &mut self,
        bins: &AtomBins,
        params: &SurfaceParams,
        grid: &GridSpec,
        with_colour: bool,
        scratch: &mut BrickScratch,
    ) {
        let group = (bins.slab_planes as usize / BRICK).max(1);
        debug_assert_eq!(bins.slab_planes as usize, group * BRICK);
        let [nx, ny, nz] = grid.dims.map(|d| d as usize);
        let bdims = [nx, ny, nz].map(|n| n.div_ceil(BRICK));
        let [bx, by, bz] = bdims;
        let layer_bricks = bx * by;
        self.grid = *grid;
        self.bdims = bdims;
        self.iso = params.isovalue;
        self.with_colour = with_colour;

        // Occupancy per brick layer from the conservative sample boxes.
        let mut occ = vec![0u8; layer_bricks * bz];
        let (o, h) = (grid.origin, grid.spacing);
        occ.par_chunks_mut(layer_bricks.max(1))
            .enumerate()
            .for_each(|(bk, occ)| {
                let (z0, z1) = (bk * BRICK, bk * BRICK + BRICK - 1);
                for &a in bins.slab(bk / group) {
                    let at = &bins.atoms[a as usize];
                    let [px, py, pz] = at.pos;
                    let (Some(rx), Some(ry), Some(rz)) = (
                        sample_range(px, at.cut, o.x, h, nx as u32),
                        sample_range(py, at.cut, o.y, h, ny as u32),
                        sample_range(pz, at.cut, o.z, h, nz as u32),
                    ) else {
                        continue;
                    };
                    if (rz.1 as usize) < z0 || rz.0 as usize > z1 {
                        continue;
                    }
                    for bj in ry.0 as usize / BRICK..=ry.1 as usize / BRICK {
                        let row = &mut occ[bj * bx..(bj + 1) * bx];
                        row[rx.0 as usize / BRICK..=rx.1 as usize / BRICK].fill(1);
                    }
                }
            });

        // Slots in brick order; each layer's bricks are contiguous.
        self.slots.clear();
        self.slots.reserve(occ.len());
        let mut layer_start = Vec::with_capacity(bz + 1);
        let mut count = 0u32;
        for (b, &o) in occ.iter().enumerate() {
            if b % layer_bricks.max(1) == 0 {
                layer_start.push(count as usize);
            }
            if o != 0 {
                self.slots.push(count);
                count += 1;
            } else {
                self.slots.push(EMPTY);
            }
        }
        layer_start.push(count as usize);
        // Every stored sample is overwritten below, so only a grown tail is zeroed. A store that
        // must grow is allocated anew, zeroed by the allocator (fresh pages from the system): the
        // worker threads then fault its pages in while they fill their layers, instead of this
        // thread zeroing it all first (a million atoms: over 100 MB).
        let samples = count as usize * BRICK_SAMPLES;
        if samples > self.data.capacity() {
            self.data = Vec::new();
            self.data = vec![0.0; samples];
        } else {
            self.data.resize(samples, 0.0);
        }

        let mut chunks: Vec<&mut [f32]> = Vec::with_capacity(bz);
        let mut rest = &mut self.data[..];
        for bk in 0..bz {
            let n = (layer_start[bk + 1] - layer_start[bk]) * BRICK_SAMPLES;
            let (head, tail) = rest.split_at_mut(n);
            chunks.push(head);
            rest = tail;
        }
        self.layers.resize_with(bz, Layer::default);
        let threads = rayon::current_num_threads().max(1);
        if scratch.threads.len() < threads + 1 {
            scratch
                .threads
                .resize_with(threads + 1, || Mutex::new(LayerScratch::default()));
        }
        let ctx = LayerCtx {
            bins,
            grid,
            occ: &occ,
            bdims,
            iso: params.isovalue,
            inv_iso: 1.0 / params.isovalue,
            with_colour,
        };
        let scratch = &scratch.threads;
        let mut groups: Vec<Vec<&mut [f32]>> = Vec::with_capacity(bz.div_ceil(group));
        for (bk, chunk) in chunks.into_iter().enumerate() {
            if bk % group == 0 {
                groups.push(Vec::with_capacity(group));
            }
            if let Some(g) = groups.last_mut() {
                g.push(chunk);
            }
        }
        self.layers
            .par_chunks_mut(group)
            .zip(groups)
            .enumerate()
            .for_each(|(c, (layers, dsts))| {
                let t = rayon::current_thread_index()
                    .unwrap_or(threads)
                    .min(threads);
                let mut s = scratch[t].lock().unwrap_or_else(|e| e.into_inner());
                ctx.group(c, c * group, layers, dsts, &mut s);
            });

        let active = self.layers.iter().map(|l| l.cols.len() as u64).sum();
        self.stats = BrickStats {
            brick_size: BRICK as u32,
            bricks: (bx * by * bz) as u64,
            occupied: count as u64,
            active,
        };
    }
}

/// What every layer reads.
struct LayerCtx<'a> {
    bins: &'a AtomBins,
    grid: &'a GridSpec,
    occ: &'a [u8],
    bdims: [usize; 3],
    iso: f32,
    inv_iso: f32,
    with_colour: bool,
}

impl LayerCtx<'_> {
    /// Computes the brick layers `bk0 .. bk0 + layers.len()` (atom slab `slab`) in one pass:
    /// their samples into the scratch (planes `8 bk0 ..=` the first plane of the next layer),
    /// then each layer's occupied bricks into `dsts`, its active list and vertex colours into
    /// `layers`.
    fn group(
        &self,
        slab: usize,
        bk0: usize,
        layers: &mut [Layer],
        dsts: Vec<&mut [f32]>,
        s: &mut LayerScratch,
    ) {
        let [nx, ny, nz] = self.grid.dims.map(|d| d as usize);
        let [bx, by, bz] = self.bdims;
        let plane = nx * ny;
        let z0 = bk0 * BRICK;
        let np = (BRICK * layers.len() + 1).min(nz - z0);
        let lb = bx * by;
        let temp = plane * (BRICK * layers.len() + 1);
        if s.vals.len() < temp {
            s.vals = vec![0.0; temp];
        }
        if self.with_colour && s.cols[0].len() < temp {
            s.cols = [(); 3].map(|_| vec![0.0; temp]);
        }
        let LayerScratch { vals, cols } = s;
        let vals = &mut vals[..plane * np];
        let [r, g, b] = cols;
        let mut cols = self.with_colour.then(|| {
            [
                &mut r[..plane * np],
                &mut g[..plane * np],
                &mut b[..plane * np],
            ]
        });

        // Zero the brick columns within one brick of an occupied brick (of a layer or the next,
        // whose first plane closes the layer's footprints): they hold every sample that gets a
        // term (only occupied bricks do) and every sample the footprints read, so the scratch
        // is exact wherever it is read. Columns further away are never touched.
        let mut nears = Vec::with_capacity(layers.len());
        for g in 0..layers.len() {
            let bk = bk0 + g;
            let occ_k = &self.occ[bk * lb..(bk + 1) * lb];
            let occ_up = (bk + 1 < bz).then(|| &self.occ[(bk + 1) * lb..(bk + 2) * lb]);
            let near: Vec<bool> = (0..lb)
                .map(|b| {
                    let (bi, bj) = (b % bx, b / bx);
                    (bj.saturating_sub(1)..=(bj + 1).min(by - 1)).any(|y| {
                        (bi.saturating_sub(1)..=(bi + 1).min(bx - 1)).any(|x| {
                            occ_k[y * bx + x] != 0 || occ_up.is_some_and(|o| o[y * bx + x] != 0)
                        })
                    })
                })
                .collect();
            for kk in g * BRICK..(g * BRICK + BRICK + 1).min(np) {
                for (b, _) in near.iter().enumerate().filter(|(_, n)| **n) {
                    let (bi, bj) = (b % bx, b / bx);
                    let (i0, i1) = (bi * BRICK, (bi * BRICK + BRICK).min(nx));
                    for j in bj * BRICK..(bj * BRICK + BRICK).min(ny) {
                        let r = kk * plane + j * nx;
                        vals[r + i0..r + i1].fill(0.0);
                        for c in cols.iter_mut().flatten() {
                            c[r + i0..r + i1].fill(0.0);
                        }
                    }
                }
            }
            nears.push(near);
        }
        let z1 = (z0 + np - 1) as u32;
        fill_planes(
            &self.bins.atoms,
            self.bins.slab(slab),
            &SampleLattice::of_grid(self.grid),
            z0 as u32,
            z1,
            vals,
            cols.as_mut()
                .map(|[r, g, b]| [&mut **r, &mut **g, &mut **b]),
        );
        for (((g, layer), dst), near) in layers.iter_mut().enumerate().zip(dsts).zip(&nears) {
            let base = g * BRICK * plane;
            let np = (BRICK + 1).min(np - g * BRICK);
            let vals = &vals[base..base + np * plane];
            let cols = cols
                .as_ref()
                .map(|c| [0, 1, 2].map(|n| &c[n][base..base + np * plane]));
            self.finish(bk0 + g, np, vals, cols, near, layer, dst);
        }
    }

    /// Stores the occupied bricks of layer `bk` from its `np` scratch planes (`vals`, `cols`,
    /// plane `8 bk` first) into `dst`, and finds its active bricks and vertex colours.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        bk: usize,
        np: usize,
        vals: &[f32],
        cols: Option<[&[f32]; 3]>,
        near: &[bool],
        layer: &mut Layer,
        dst: &mut [f32],
    ) {
        let [nx, ny, nz] = self.grid.dims.map(|d| d as usize);
        let [bx, by, bz] = self.bdims;
        let plane = nx * ny;
        let z0 = bk * BRICK;
        let lb = bx * by;
        let occ_k = &self.occ[bk * lb..(bk + 1) * lb];
        let occ_up = (bk + 1 < bz).then(|| &self.occ[(bk + 1) * lb..(bk + 2) * lb]);

        // Store the occupied bricks of this layer.
        let mut slot = 0usize;
        for bj in 0..by {
            for bi in 0..bx {
                if occ_k[bj * bx + bi] == 0 {
                    continue;
                }
                let out = &mut dst[slot * BRICK_SAMPLES..(slot + 1) * BRICK_SAMPLES];
                slot += 1;
                for kk in 0..BRICK {
                    for jj in 0..BRICK {
                        let o = (kk * BRICK + jj) * BRICK;
                        let (j, k) = (bj * BRICK + jj, kk);
                        let i0 = bi * BRICK;
                        if j >= ny || k >= np.min(BRICK) {
                            out[o..o + BRICK].fill(0.0);
                            continue;
                        }
                        let n = BRICK.min(nx - i0);
                        let r = k * plane + j * nx + i0;
                        out[o..o + n].copy_from_slice(&vals[r..r + n]);
                        out[o + n..o + BRICK].fill(0.0);
                    }
                }
            }
        }

        let iso = self.iso;

        // Inside flags as bit masks: bit t of `masks[(kk * ny + j) * bx + bi]` is set when
        // sample (8 bi + t, j, 8 bk + kk) has rho >= I. Columns not near an occupied brick hold
        // only zeros (below I), so their masks stay 0 without reading the scratch there.
        let mut masks = vec![0u8; np * ny * bx];
        for kk in 0..np {
            for bj in 0..by {
                for bi in 0..bx {
                    if !near[bj * bx + bi] {
                        continue;
                    }
                    let i0 = bi * BRICK;
                    let n = BRICK.min(nx - i0);
                    for j in bj * BRICK..(bj * BRICK + BRICK).min(ny) {
                        let r = kk * plane + j * nx + i0;
                        let m = vals[r..r + n]
                            .iter()
                            .enumerate()
                            .fold(0u8, |m, (t, &v)| m | (u8::from(v >= iso) << t));
                        masks[(kk * ny + j) * bx + bi] = m;
                    }
                }
            }
        }
        let layer_masks = LayerMasks {
            masks: &masks,
            dims: [nx, ny],
            bdims: [bx, by],
            planes: np,
        };
        let mask9 = |kk: usize, j: usize, bi: usize| layer_masks.mask9(kk, j, bi);
        let touched = |bi: usize, bj: usize| {
            let near = |occ: &[u8]| {
                (bj..=(bj + 1).min(by - 1))
                    .any(|y| (bi..=(bi + 1).min(bx - 1)).any(|x| occ[y * bx + x] != 0))
            };
            near(occ_k) || occ_up.is_some_and(near)
        };
        layer_masks.find_active(touched, layer);

        // Vertex colours in the order Marching Cubes visits the crossed edges: plane by plane,
        // row by row, active bricks by x, points by x, axes x, y, z.
        layer.colours.clear();
        let Some(cols) = cols else { return };
        for kk in 0..np.min(BRICK) {
            let k = z0 + kk;
            for j in 0..ny {
                let bj = j / BRICK;
                let row =
                    &layer.cols[layer.row_start[bj] as usize..layer.row_start[bj + 1] as usize];
                for &bi in row {
                    let bi = bi as usize;
                    let i0 = bi * BRICK;
                    let n = BRICK.min(nx - i0); // points of this brick in the row
                    let r = kk * plane + j * nx + i0;
                    // Bit t: point i0 + t is inside; crossed edges along x, y, z as bit masks.
                    let fa = mask9(kk, j, bi);
                    let own = (1u32 << n) - 1;
                    let xs = (fa ^ (fa >> 1)) & own & ((1u32 << (nx - 1 - i0).min(BRICK)) - 1);
                    let ys = if j + 1 < ny {
                        (fa ^ mask9(kk, j + 1, bi)) & own
                    } else {
                        0
                    };
                    let zs = if k + 1 < nz {
                        (fa ^ mask9(kk + 1, j, bi)) & own
                    } else {
                        0
                    };
                    if xs | ys | zs == 0 {
                        continue;
                    }
                    for t in 0..n {
                        let p = r + t;
                        for (mask, step) in [(xs, 1), (ys, nx), (zs, plane)] {
                            if mask >> t & 1 == 0 {
                                continue;
                            }
                            let t_edge = edge_t(vals[p], vals[p + step], iso);
                            let ca = [0, 1, 2].map(|n| cols[n][p] * self.inv_iso);
                            let cb = [0, 1, 2].map(|n| cols[n][p + step] * self.inv_iso);
                            layer.colours.push(lerp_colour(ca, cb, t_edge));
                        }
                    }
                }
            }
        }
    }
}
