//! Exposure radii of the SES preset on the GPU (issue 33 section 3): the pass that replaces
//! the host's [`crate::model::exposure::ExposureModel::apply`] when the GPU engine computes a
//! surface whose radii follow exposure, so a preset frame makes no pass over the atoms on the
//! host. `shaders/exposure.wgsl` bins the heavy atoms by counting sort into cells of a quarter
//! of the counting radius (grown where atoms are sparse over a large box, as the host grows
//! its cells), counts for every atom the heavy atoms within the radius (nearest cells first,
//! stopping at the model's saturation: the count is min(true count, saturation), as the host's),
//! and writes radius = own radius * factor into the engine's radii buffer, which binning reads.
//!
//! Exactness: the inclusion test is the host's `d² <= r²` with `d²` rounded as glam rounds it
//! (each square and sum rounded to f32; the shader keeps the compiler from fusing them into
//! multiply-adds), and `r²` is rounded on the host; the factors are
//! [`ExposureModel::factor`] of every count 0 ..= saturation, computed on the host from the
//! model's own terms, so radius = own radius * factor is one f32 product on both sides. The
//! counts and radii equal the host's bit for bit (`tests/it/gpu_exposure.rs`).

use glam::{DVec3, IVec3, Vec3};

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Uniform, groups_1d, module};
use super::plan::FramePlan;
use super::resources::{Buffers, Grow};
use super::scan::{ScanPlan, Scanner};
use super::types::ExposureUniform;
use crate::model::exposure::ExposureModel;

/// The bindings of `shaders/exposure.wgsl` (listed in [`crate::gpu::layout::SHADERS`] with the
/// other stages' tables).
pub mod slots {
    use crate::gpu::layout::Kind::{Read, ReadWrite, Uniform};
    use crate::gpu::layout::{Slot, slot};
    /// [`crate::gpu::types::ExposureUniform`].
    pub const U: Slot = slot(0, "u", Uniform);
    /// Positions.
    pub const POSITIONS: Slot = slot(1, "positions", Read);
    /// Heavy atom indices.
    pub const HEAVY: Slot = slot(2, "heavy", Read);
    /// Heavy atoms per cell (the cell-start buffer before its scan).
    pub const CELL_COUNT: Slot = slot(3, "cell_count", ReadWrite);
    /// First slot per cell.
    pub const CELL_START: Slot = slot(4, "cell_start", Read);
    /// Fill cursors, then one past the last slot per cell.
    pub const CELL_END: Slot = slot(5, "cell_end", ReadWrite);
    /// Heavy atom positions by cell.
    pub const SORTED_HEAVY: Slot = slot(6, "sorted_heavy", ReadWrite);
    /// Reachable cell offsets, nearest first.
    pub const OFFSETS: Slot = slot(7, "offsets", Read);
    /// Radius factor per count.
    pub const FACTORS: Slot = slot(8, "factors", Read);
    /// The atoms' own radii.
    pub const BASE_RADII: Slot = slot(9, "base_radii", Read);
    /// This frame's radii (the engine's radii buffer).
    pub const RADII: Slot = slot(10, "radii", ReadWrite);
    /// Counts per atom.
    pub const COUNTS: Slot = slot(11, "counts", ReadWrite);
    /// Layout of `count_heavy`.
    pub const COUNT_HEAVY: &[Slot] = &[U, POSITIONS, HEAVY, CELL_COUNT];
    /// Layout of `copy_starts`.
    pub const COPY_STARTS: &[Slot] = &[U, CELL_START, CELL_END];
    /// Layout of `scatter_heavy`.
    pub const SCATTER_HEAVY: &[Slot] = &[U, POSITIONS, HEAVY, CELL_END, SORTED_HEAVY];
    /// Layout of `count_neighbours`.
    pub const COUNT_NEIGHBOURS: &[Slot] = &[
        U,
        POSITIONS,
        CELL_START,
        SORTED_HEAVY,
        OFFSETS,
        FACTORS,
        BASE_RADII,
        RADII,
        COUNTS,
    ];
    /// Every binding of the file.
    pub const ALL: &[Slot] = &[
        U,
        POSITIONS,
        HEAVY,
        CELL_COUNT,
        CELL_START,
        CELL_END,
        SORTED_HEAVY,
        OFFSETS,
        FACTORS,
        BASE_RADII,
        RADII,
        COUNTS,
    ];
}

/// The largest saturation (count) a model may have to run on the GPU: its factor table holds
/// one f32 per count.
pub const MAX_GPU_SATURATION: u32 = 1 << 16;

/// True when `model` can run on the GPU (a finite positive radius, a saturation of at most
/// [`MAX_GPU_SATURATION`]); otherwise its radii must come from the host.
pub fn runs_on_gpu(model: &ExposureModel) -> bool {
    model.radius.is_finite() && model.radius > 0.0 && model.saturation() <= MAX_GPU_SATURATION
}

/// Cells per counting radius along an axis (as the host's cells, a quarter of the radius).
const CELLS_PER_RADIUS: f32 = 4.0;

/// The cells of a frame's heavy-atom binning: cell edge (Å) and cells along x, y, z, for atoms
/// within the box `lo`..`hi` (Å), `heavy` heavy atoms and counting radius `radius` (Å). Cells of
/// radius / 4, grown by a quarter at a time until there are at most four per heavy atom (at
/// least 4096 cells allowed), so that a box of any finite size gets a grid; one spare layer
/// past `hi` takes the roundings of the cell index.
pub fn exposure_cells(lo: Vec3, hi: Vec3, heavy: usize, radius: f32) -> (f32, [u32; 3]) {
    let limit = (4 * heavy).max(1 << 12) as f64;
    let extent = (hi - lo).as_dvec3().max(DVec3::ZERO);
    let dims_for = |size: f32| (extent / size as f64).floor() + 2.0;
    let mut size = radius / CELLS_PER_RADIUS;
    while dims_for(size).element_product() > limit {
        size *= 1.25;
    }
    let d = dims_for(size);
    (size, [d.x as u32, d.y as u32, d.z as u32])
}

/// The cell offsets around an atom's cell that a sphere of `radius` (Å) can reach with cells of
/// `size` (Å), nearest first: those whose nearest point lies within the radius (with a margin
/// of 1e-4 of it, so that no atom rounded into a neighbouring cell is missed; every atom of a
/// visited cell is still tested by its distance).
pub fn reach_offsets(radius: f32, size: f32) -> Vec<IVec3> {
    let reach = (radius / size).ceil() as i32;
    let limit = (radius as f64 * 1.0001).powi(2);
    let mut offsets: Vec<IVec3> = (-reach..=reach)
        .flat_map(|z| (-reach..=reach).flat_map(move |y| (-reach..=reach).map(move |x| (x, y, z))))
        .map(|(x, y, z)| IVec3::new(x, y, z))
        .filter(|o| {
            let gap = (o.abs() - 1).max(IVec3::ZERO).as_dvec3() * size as f64;
            gap.length_squared() <= limit
        })
        .collect();
    offsets.sort_by_key(|o| o.length_squared());
    offsets
}

/// The exposure model and heavy atoms the engine computes radii with.
#[derive(Debug, Clone, PartialEq)]
struct Input {
    model: ExposureModel,
    /// Which atoms are heavy (one flag per atom).
    heavy_flags: Vec<bool>,
}

/// The pass's own buffers.
#[derive(Debug)]
struct Own {
    heavy: Grow,
    cell_start: Grow,
    cell_end: Grow,
    sorted_heavy: Grow,
    offsets: Grow,
    factors: Grow,
    base_radii: Grow,
    counts: Grow,
    /// The scan's total (heavy atoms binned).
    total: Grow,
}

/// The exposure pass: kernels, buffers, uniform and bind groups (see the module docs).
#[derive(Debug)]
pub struct ExposureStage {
    count_heavy: Kernel,
    copy_starts: Kernel,
    scatter_heavy: Kernel,
    count_neighbours: Kernel,
    max_groups: u32,
    uniform: Uniform<ExposureUniform>,
    binds: [Bound; 4],
    scan: ScanPlan,
    own: Own,
    input: Option<Input>,
    /// The heavy indices and factors in the buffers are those of `input`.
    uploaded: bool,
    /// (radius, cell size) the offsets buffer was written for, and how many it holds.
    offsets_for: Option<(f32, f32, u32)>,
    /// What the last [`ExposureStage::prepare`] set up: atoms, heavy atoms, cells.
    prepared: (u64, u64, u64),
}

impl ExposureStage {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext, max_groups: u32) -> ExposureStage {
        let m = module(&ctx.device, "exposure.wgsl", super::shaders::EXPOSURE);
        let grow = |label| {
            Grow::new(
                ctx,
                label,
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            )
        };
        ExposureStage {
            count_heavy: Kernel::with_slots(ctx, &m, "count_heavy", slots::COUNT_HEAVY),
            copy_starts: Kernel::with_slots(ctx, &m, "copy_starts", slots::COPY_STARTS),
            scatter_heavy: Kernel::with_slots(ctx, &m, "scatter_heavy", slots::SCATTER_HEAVY),
            count_neighbours: Kernel::with_slots(
                ctx,
                &m,
                "count_neighbours",
                slots::COUNT_NEIGHBOURS,
            ),
            max_groups,
            uniform: Uniform::new(ctx, "exposure uniform"),
            binds: Default::default(),
            scan: ScanPlan::default(),
            own: Own {
                heavy: grow("exposure heavy atoms"),
                cell_start: grow("exposure cell start"),
                cell_end: grow("exposure cell end"),
                sorted_heavy: grow("exposure sorted heavy atoms"),
                offsets: grow("exposure offsets"),
                factors: grow("exposure factors"),
                base_radii: grow("exposure own radii"),
                counts: grow("exposure counts"),
                total: grow("exposure total"),
            },
            input: None,
            uploaded: false,
            offsets_for: None,
            prepared: (0, 0, 0),
        }
    }

    /// Sets the model and heavy atoms (`None`: radii come from the host); true when that
    /// changed. A model that does not [`runs_on_gpu`] is taken as `None`.
    pub fn set(&mut self, exposure: Option<(ExposureModel, &[bool])>) -> bool {
        let exposure = exposure.filter(|(m, _)| runs_on_gpu(m));
        let same = match (&self.input, &exposure) {
            (None, None) => true,
            (Some(i), Some((m, h))) => i.model == *m && i.heavy_flags == *h,
            _ => false,
        };
        if !same {
            self.input = exposure.map(|(model, heavy)| Input {
                model,
                heavy_flags: heavy.to_vec(),
            });
            self.uploaded = false;
        }
        !same
    }

    /// True when the engine's radii come from this pass.
    pub fn active(&self) -> bool {
        self.input.is_some()
    }

    /// The atoms the heavy flags were given for (0 without a model).
    pub fn atoms(&self) -> usize {
        self.input.as_ref().map_or(0, |i| i.heavy_flags.len())
    }

    /// The largest factor of the model over every count (1 without a model): the radii this
    /// pass writes are at most the largest own radius times this.
    pub fn max_factor(&self) -> f32 {
        self.input.as_ref().map_or(1.0, |i| {
            (0..=i.model.saturation())
                .map(|n| i.model.factor(n))
                .fold(0.0, f32::max)
        })
    }

    /// Uploads the atoms' own radii (Å).
    pub fn upload_radii(&mut self, ctx: &GpuContext, radii: &[f32]) {
        self.own.base_radii.ensure(ctx, 4 * radii.len() as u64);
        ctx.queue
            .write_buffer(&self.own.base_radii.buffer, 0, bytemuck::cast_slice(radii));
    }

    /// Bytes of GPU memory the pass's buffers hold.
    pub fn bytes(&self) -> u64 {
        let o = &self.own;
        [
            &o.heavy,
            &o.cell_start,
            &o.cell_end,
            &o.sorted_heavy,
            &o.offsets,
            &o.factors,
            &o.base_radii,
            &o.counts,
            &o.total,
        ]
        .iter()
        .map(|g| g.size())
        .sum()
    }

    /// The counts buffer (heavy atoms counted per atom, capped at the saturation; test hooks).
    pub fn counts_buffer(&self) -> &wgpu::Buffer {
        &self.own.counts.buffer
    }

    /// Prepares the pass for `atoms` atoms binned under `plan` (whose grid holds every atom):
    /// sizes the cells, uploads the heavy atoms, factors and offsets when they changed, writes
    /// the uniform, binds the buffers, prepares the scan. Nothing without a model.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scanner: &Scanner,
        b: &Buffers,
        plan: &FramePlan,
        atoms: u64,
    ) {
        let Some(input) = &self.input else {
            return;
        };
        let model = input.model;
        let q = &ctx.queue;
        let own = &mut self.own;
        if !self.uploaded {
            let heavy: Vec<u32> = (input.heavy_flags.iter().enumerate())
                .filter_map(|(i, &h)| h.then_some(i as u32))
                .collect();
            own.heavy.ensure(ctx, 4 * heavy.len() as u64);
            q.write_buffer(&own.heavy.buffer, 0, bytemuck::cast_slice(&heavy));
            own.sorted_heavy.ensure(ctx, 16 * heavy.len() as u64);
            let factors: Vec<f32> = (0..=model.saturation()).map(|n| model.factor(n)).collect();
            own.factors.ensure(ctx, 4 * factors.len() as u64);
            q.write_buffer(&own.factors.buffer, 0, bytemuck::cast_slice(&factors));
            self.prepared.1 = heavy.len() as u64;
            self.uploaded = true;
        }
        let heavy = self.prepared.1;
        let g = &plan.grid;
        let last = glam::UVec3::from(g.dims).saturating_sub(glam::UVec3::ONE);
        let hi = g.origin + last.as_vec3() * g.spacing;
        let (size, dims) = exposure_cells(g.origin, hi, heavy as usize, model.radius);
        let cells = dims.iter().map(|&d| d as u64).product::<u64>();
        own.cell_start.ensure(ctx, 4 * cells);
        own.cell_end.ensure(ctx, 4 * cells);
        own.counts.ensure(ctx, 4 * atoms);
        let offset_count = match self.offsets_for {
            Some((r, s, n)) if r == model.radius && s == size => n,
            _ => {
                let offsets: Vec<[i32; 4]> = reach_offsets(model.radius, size)
                    .iter()
                    .map(|o| [o.x, o.y, o.z, 0])
                    .collect();
                own.offsets.ensure(ctx, 16 * offsets.len() as u64);
                q.write_buffer(&own.offsets.buffer, 0, bytemuck::cast_slice(&offsets));
                self.offsets_for = Some((model.radius, size, offsets.len() as u32));
                offsets.len() as u32
            }
        };
        self.uniform.write(
            q,
            &ExposureUniform {
                cell_origin: g.origin.to_array(),
                cell_size: size,
                cell_dims: dims,
                atom_count: atoms as u32,
                heavy_count: heavy as u32,
                offset_count,
                cap: model.saturation(),
                radius_sq: model.radius * model.radius,
                zero_bits: 0,
                cell_count: cells as u32,
                _pad: [0; 2],
            },
        );
        let u = &self.uniform.buffer;
        let own = &self.own;
        let [count, copy, scatter, neighbours] = &mut self.binds;
        self.count_heavy.bind(
            ctx,
            count,
            &[
                (slots::U, u),
                (slots::POSITIONS, &b.positions.buffer),
                (slots::HEAVY, &own.heavy.buffer),
                (slots::CELL_COUNT, &own.cell_start.buffer),
            ],
        );
        self.copy_starts.bind(
            ctx,
            copy,
            &[
                (slots::U, u),
                (slots::CELL_START, &own.cell_start.buffer),
                (slots::CELL_END, &own.cell_end.buffer),
            ],
        );
        self.scatter_heavy.bind(
            ctx,
            scatter,
            &[
                (slots::U, u),
                (slots::POSITIONS, &b.positions.buffer),
                (slots::HEAVY, &own.heavy.buffer),
                (slots::CELL_END, &own.cell_end.buffer),
                (slots::SORTED_HEAVY, &own.sorted_heavy.buffer),
            ],
        );
        self.count_neighbours.bind(
            ctx,
            neighbours,
            &[
                (slots::U, u),
                (slots::POSITIONS, &b.positions.buffer),
                (slots::CELL_START, &own.cell_start.buffer),
                (slots::SORTED_HEAVY, &own.sorted_heavy.buffer),
                (slots::OFFSETS, &own.offsets.buffer),
                (slots::FACTORS, &own.factors.buffer),
                (slots::BASE_RADII, &own.base_radii.buffer),
                (slots::RADII, &b.radii.buffer),
                (slots::COUNTS, &own.counts.buffer),
            ],
        );
        scanner.prepare(
            ctx,
            &mut self.scan,
            &own.cell_start.buffer,
            cells,
            (&own.total.buffer, 0),
        );
        self.prepared = (atoms, heavy, cells);
    }

    /// Records the prepared pass (nothing without a model): clears the cell counts, bins the
    /// heavy atoms, counts every atom's neighbours and writes the radii.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scanner: &Scanner,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        if self.input.is_none() {
            return;
        }
        let (atoms, heavy, cells) = self.prepared;
        encoder.clear_buffer(&self.own.cell_start.buffer, 0, Some(cells * 4));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("exposure"),
            timestamp_writes: ts,
        });
        let [count, copy, scatter, neighbours] = &self.binds;
        let heavy_groups = groups_1d(heavy.div_ceil(256), self.max_groups);
        let cell_groups = groups_1d(cells.div_ceil(256), self.max_groups);
        let atom_groups = groups_1d(atoms.div_ceil(256), self.max_groups);
        self.count_heavy
            .dispatch(&mut pass, count, &[], heavy_groups);
        scanner.record(&mut pass, &self.scan);
        self.copy_starts.dispatch(&mut pass, copy, &[], cell_groups);
        self.scatter_heavy
            .dispatch(&mut pass, scatter, &[], heavy_groups);
        self.count_neighbours
            .dispatch(&mut pass, neighbours, &[], atom_groups);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_nearest_first_and_cover_the_sphere() {
        let offsets = reach_offsets(16.0, 4.0);
        assert_eq!(offsets[0], IVec3::ZERO);
        assert!(
            offsets
                .windows(2)
                .all(|w| w[0].length_squared() <= w[1].length_squared())
        );
        // Every cell with a point within 16 Å of a point of the own cell is listed: a gap of
        // three cells (12 Å) along one axis is, a gap of 4 + 4 + 4 ... is not.
        assert!(offsets.contains(&IVec3::new(4, 0, 0)));
        assert!(offsets.contains(&IVec3::new(3, 3, 0)));
        assert!(!offsets.contains(&IVec3::new(4, 4, 4)));
    }

    #[test]
    fn cells_grow_over_a_sparse_box_and_hold_every_atom() {
        let (size, dims) = exposure_cells(Vec3::ZERO, Vec3::splat(40.0), 1000, 16.0);
        assert_eq!(size, 4.0);
        assert_eq!(dims, [12, 12, 12]);
        let (size, dims) = exposure_cells(Vec3::ZERO, Vec3::new(1e30, 0.0, 0.0), 10, 16.0);
        assert!(
            size > 1e26 && dims[0] as f64 * size as f64 > 1e30,
            "{size} {dims:?}"
        );
        assert!(dims.iter().map(|&d| d as f64).product::<f64>() <= 4096.0);
    }
}
