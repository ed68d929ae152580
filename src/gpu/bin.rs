//! Binning stage (the paper's t_sort): counting sort of the atoms into the uniform cell grid of
//! [`super::plan::FramePlan`] with `shaders/bin.wgsl` (count per cell, exclusive scan, copy the
//! starts into the fill cursors, scatter, sort each cell), so the density gather can walk
//! neighbouring cells. The per-cell sort by (x, y, z, alpha) makes the order within a cell, and
//! so every density sum, independent of the run and of the input order (cells of more than 1024
//! atoms keep the scatter order).

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Uniform, groups_1d, module};
use super::layout::bin as b;
use super::plan::FramePlan;
use super::resources::Buffers;
use super::scan::{ScanPlan, Scanner};
use super::types::BinUniform;

/// The binning kernels and their persistent uniform, scan scratch and bind groups.
#[derive(Debug)]
pub struct Binner {
    count: Kernel,
    copy_starts: Kernel,
    scatter: Kernel,
    sort_cells: Kernel,
    max_groups: u32,
    uniform: Uniform<BinUniform>,
    binds: [Bound; 4],
    scan: ScanPlan,
    atoms: u64,
    cells: u64,
}

impl Binner {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext, max_groups: u32) -> Binner {
        let m = module(&ctx.device, "bin.wgsl", super::shaders::BIN);
        Binner {
            count: Kernel::with_slots(ctx, &m, "count", b::COUNT),
            copy_starts: Kernel::with_slots(ctx, &m, "copy_starts", b::COPY_STARTS),
            scatter: Kernel::with_slots(ctx, &m, "scatter", b::SCATTER),
            sort_cells: Kernel::with_slots(ctx, &m, "sort_cells", b::SORT_CELLS),
            max_groups,
            uniform: Uniform::new(ctx, "bin uniform"),
            binds: Default::default(),
            scan: ScanPlan::default(),
            atoms: 0,
            cells: 0,
        }
    }

    /// Prepares the frame for `atoms` atoms under `plan`: writes the uniform, refreshes the bind
    /// groups whose buffers were replaced, prepares the scan of the cell counts.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scanner: &Scanner,
        bufs: &Buffers,
        plan: &FramePlan,
        atoms: u64,
        radius_scale: f32,
    ) {
        self.uniform.write(
            &ctx.queue,
            &BinUniform {
                cell_origin: plan.grid.origin.to_array(),
                cell_size: plan.cell_size,
                cell_dims: plan.cell_dims,
                atom_count: atoms as u32,
                radius_scale,
                cell_count: plan.cell_count() as u32,
                _pad: [0; 2],
            },
        );
        let u = &self.uniform.buffer;
        let [count, copy_starts, scatter, sort_cells] = &mut self.binds;
        self.count.bind(
            ctx,
            count,
            &[
                (b::U, u),
                (b::POSITIONS, &bufs.positions.buffer),
                (b::CELL_COUNT, &bufs.cell_start.buffer),
            ],
        );
        self.copy_starts.bind(
            ctx,
            copy_starts,
            &[
                (b::U, u),
                (b::CELL_START, &bufs.cell_start.buffer),
                (b::CELL_END, &bufs.cell_end.buffer),
            ],
        );
        self.scatter.bind(
            ctx,
            scatter,
            &[
                (b::U, u),
                (b::POSITIONS, &bufs.positions.buffer),
                (b::RADII, &bufs.radii.buffer),
                (b::COLOURS, &bufs.colours.buffer),
                (b::CELL_END, &bufs.cell_end.buffer),
                (b::SORTED_ATOMS, &bufs.sorted_atoms.buffer),
                (b::SORTED_COLOURS, &bufs.sorted_colours.buffer),
            ],
        );
        self.sort_cells.bind(
            ctx,
            sort_cells,
            &[
                (b::U, u),
                (b::CELL_START, &bufs.cell_start.buffer),
                (b::CELL_END, &bufs.cell_end.buffer),
                (b::SORTED_ATOMS, &bufs.sorted_atoms.buffer),
                (b::SORTED_COLOURS, &bufs.sorted_colours.buffer),
            ],
        );
        // The scan total (atom count) goes to a spare word of the partials buffer.
        scanner.prepare(
            ctx,
            &mut self.scan,
            &bufs.cell_start.buffer,
            plan.cell_count(),
            (&bufs.partials, 0),
        );
        self.atoms = atoms;
        self.cells = plan.cell_count();
    }

    /// Records the prepared binning: clears the cell counts, then count, scan, copy, scatter,
    /// sort.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scanner: &Scanner,
        bufs: &Buffers,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        encoder.clear_buffer(&bufs.cell_start.buffer, 0, Some(self.cells * 4));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bin"),
            timestamp_writes: ts,
        });
        let [count, copy_starts, scatter, sort_cells] = &self.binds;
        let atom_groups = groups_1d(self.atoms.div_ceil(256), self.max_groups);
        let cell_groups = groups_1d(self.cells.div_ceil(256), self.max_groups);
        self.count.dispatch(&mut pass, count, &[], atom_groups);
        scanner.record(&mut pass, &self.scan);
        self.copy_starts
            .dispatch(&mut pass, copy_starts, &[], cell_groups);
        self.scatter.dispatch(&mut pass, scatter, &[], atom_groups);
        self.sort_cells
            .dispatch(&mut pass, sort_cells, &[], cell_groups);
    }
}
