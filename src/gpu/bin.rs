//! Binning stage (the paper's t_sort): counting sort of the atoms into the uniform cell grid of
//! [`super::plan::FramePlan`] with `shaders/bin.wgsl` (count per cell, exclusive scan, copy the
//! starts into the fill cursors, scatter, sort each cell), so the density gather can walk
//! neighbouring cells. The per-cell sort by (x, y, z, alpha) makes the order within a cell, and
//! so every density sum, independent of the run and of the input order (cells of more than 1024
//! atoms keep the scatter order).

use super::kernel::{Kernel, groups_1d, module, uniform};
use super::plan::FramePlan;
use super::resources::Buffers;
use super::scan::{ScanPlan, Scanner};
use super::types::BinUniform;

/// The binning kernels.
#[derive(Debug)]
pub struct Binner {
    count: Kernel,
    copy_starts: Kernel,
    scatter: Kernel,
    sort_cells: Kernel,
    max_groups: u32,
}

/// Bind groups of one frame's binning.
#[derive(Debug)]
pub struct BinFrame {
    count: wgpu::BindGroup,
    copy_starts: wgpu::BindGroup,
    scatter: wgpu::BindGroup,
    sort_cells: wgpu::BindGroup,
    scan: ScanPlan,
    atoms: u64,
    cells: u64,
    _uniform: wgpu::Buffer,
}

impl Binner {
    /// Compiles the kernels.
    pub fn new(device: &wgpu::Device, max_groups: u32) -> Binner {
        let m = module(device, "bin.wgsl", super::shaders::BIN);
        Binner {
            count: Kernel::new(device, &m, "count", &[]),
            copy_starts: Kernel::new(device, &m, "copy_starts", &[]),
            scatter: Kernel::new(device, &m, "scatter", &[]),
            sort_cells: Kernel::new(device, &m, "sort_cells", &[]),
            max_groups,
        }
    }

    /// Prepares the bind groups for `atoms` atoms under `plan`; `scratch` receives the scan total.
    pub fn frame(
        &self,
        device: &wgpu::Device,
        scanner: &Scanner,
        b: &Buffers,
        plan: &FramePlan,
        atoms: u64,
        radius_scale: f32,
    ) -> BinFrame {
        let u = uniform(
            device,
            "bin uniform",
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
        let ub = || u.as_entire_binding();
        let count = self.count.bind(
            device,
            &[
                (0, ub()),
                (1, b.positions.buffer.as_entire_binding()),
                (4, b.cell_start.buffer.as_entire_binding()),
            ],
        );
        let copy_starts = self.copy_starts.bind(
            device,
            &[
                (0, ub()),
                (5, b.cell_start.buffer.as_entire_binding()),
                (6, b.cell_end.buffer.as_entire_binding()),
            ],
        );
        let scatter = self.scatter.bind(
            device,
            &[
                (0, ub()),
                (1, b.positions.buffer.as_entire_binding()),
                (2, b.radii.buffer.as_entire_binding()),
                (3, b.colours.buffer.as_entire_binding()),
                (6, b.cell_end.buffer.as_entire_binding()),
                (7, b.sorted_atoms.buffer.as_entire_binding()),
                (8, b.sorted_colours.buffer.as_entire_binding()),
            ],
        );
        let sort_cells = self.sort_cells.bind(
            device,
            &[
                (0, ub()),
                (5, b.cell_start.buffer.as_entire_binding()),
                (6, b.cell_end.buffer.as_entire_binding()),
                (7, b.sorted_atoms.buffer.as_entire_binding()),
                (8, b.sorted_colours.buffer.as_entire_binding()),
            ],
        );
        // The scan total (atom count) goes to a spare word of the partials buffer.
        let scan = scanner.plan(
            device,
            &b.cell_start.buffer,
            plan.cell_count(),
            (&b.partials, 0),
        );
        BinFrame {
            count,
            copy_starts,
            scatter,
            sort_cells,
            scan,
            atoms,
            cells: plan.cell_count(),
            _uniform: u,
        }
    }

    /// Records the binning: clears the cell counts, then count, scan, copy, scatter.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scanner: &Scanner,
        b: &Buffers,
        f: &BinFrame,
        ts: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        encoder.clear_buffer(&b.cell_start.buffer, 0, Some(f.cells * 4));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bin"),
            timestamp_writes: ts,
        });
        let atom_groups = groups_1d(f.atoms.div_ceil(256), self.max_groups);
        self.count.dispatch(&mut pass, &f.count, atom_groups);
        scanner.record(&mut pass, &f.scan);
        self.copy_starts.dispatch(
            &mut pass,
            &f.copy_starts,
            groups_1d(f.cells.div_ceil(256), self.max_groups),
        );
        self.scatter.dispatch(&mut pass, &f.scatter, atom_groups);
        let cell_groups = groups_1d(f.cells.div_ceil(256), self.max_groups);
        self.sort_cells
            .dispatch(&mut pass, &f.sort_cells, cell_groups);
    }
}
