//! Sparse bricks on the GPU (issue 12): after binning, `shaders/bricks.wgsl` marks each brick
//! of [`BRICK`](super::plan::BRICK)^3 samples that some atom's cutoff sphere reaches (from the
//! atoms of the bin cells around it, with a little slack so rounding never misses one), scans
//! the marks ([`super::scan`]), lists the reached bricks after their count, and writes the
//! indirect dispatch arguments of the density pass over that list ([`super::density`]). Bricks
//! no atom reaches are never sampled: their samples keep the 0 the frame clears the volumes to,
//! which is exactly what the dense pass computes there, and classification skips points whose
//! neighbourhood holds no reached brick, so the mesh is the dense path's, bit for bit.
//!
//! Memory follows the reached bricks too: `compact` also writes the brick slot table into the
//! first words of the density buffer (per brick its slot, the exclusive scan of the flags, with
//! the high bit set when no atom reaches it), and the density and colour samples are stored
//! brick-locally after it, [`BRICK_SAMPLES`](super::plan::BRICK_SAMPLES) per slot, counted
//! from the slot of the slab's first brick layer; every stage that reads samples goes through
//! that table (an unreached brick reads as 0). The per-point Marching Cubes buffers (class
//! words, vertex bases, active cells) are held per slot too when that takes fewer entries than
//! one per point of the slab ([`ClassEntries`](super::plan::ClassEntries),
//! `shaders/class_entries.wgsl`): 9^3 entries per slot, the brick's own points and the points
//! just below it in unreached bricks, the only ones of those bricks whose cells reach a reached
//! brick. The first sparse frame of a system (a fresh engine's, or a new atom count on a grid
//! of half as many bricks again as the one last counted) runs binning and this pass alone,
//! reads the slot table back and sizes the slots from the most reached bricks of one slab
//! ([`settled_brick_slots`](super::plan::settled_brick_slots)), so its density runs once; later
//! frames grow the slots like the mesh buffers (the density pass, or classification, sets
//! [`OVERFLOW_BRICKS`](super::types::OVERFLOW_BRICKS) when a slab's bricks do not fit, and the
//! engine grows them and re-runs density). The flags and list add 12 bytes per brick (under
//! 0.03 byte per sample).

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Uniform, groups_1d, module};
use super::layout::bricks as b;
use super::plan::FramePlan;
use super::resources::Buffers;
use super::scan::{ScanPlan, Scanner};
use super::types::{BrickUniform, C_REACHED_BRICKS};

/// The sparse-brick kernels, their uniform, scan scratch and cached bind groups.
#[derive(Debug)]
pub struct BrickStage {
    mark: Kernel,
    compact: Kernel,
    args: Kernel,
    uniform: Uniform<BrickUniform>,
    /// `mark`, `compact`, `args`.
    binds: [Bound; 3],
    scan: ScanPlan,
    bricks: u64,
    max_groups: u32,
}

impl BrickStage {
    /// Compiles the kernels.
    pub fn new(ctx: &GpuContext, max_groups: u32) -> BrickStage {
        let m = module(&ctx.device, "bricks.wgsl", super::shaders::BRICKS);
        BrickStage {
            mark: Kernel::with_slots(ctx, &m, "mark", b::MARK),
            compact: Kernel::with_slots(ctx, &m, "compact", b::COMPACT),
            args: Kernel::with_slots(ctx, &m, "args", b::ARGS),
            uniform: Uniform::new(ctx, "brick uniform"),
            binds: Default::default(),
            scan: ScanPlan::default(),
            bricks: 0,
            max_groups,
        }
    }

    /// Prepares the frame under `plan` with cutoff `cutoff` (q, in units of alpha): writes the
    /// uniform, refreshes the bind groups whose buffers were replaced, prepares the scan.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scanner: &Scanner,
        bufs: &Buffers,
        plan: &FramePlan,
        cutoff: f32,
    ) {
        let g = &plan.grid;
        self.bricks = plan.brick_count();
        self.uniform.write(
            &ctx.queue,
            &BrickUniform {
                origin: g.origin.to_array(),
                spacing: g.spacing,
                dims: g.dims,
                brick_count: self.bricks as u32,
                brick_dims: plan.brick_dims,
                max_groups: self.max_groups,
                cell_origin: g.origin.to_array(),
                cell_size: plan.cell_size,
                cell_dims: plan.cell_dims,
                cutoff,
                max_cut: plan.max_cut,
                _pad: [0; 3],
            },
        );
        let u = &self.uniform.buffer;
        let [mark, compact, args] = &mut self.binds;
        self.mark.bind(
            ctx,
            mark,
            &[
                (b::U, u),
                (b::SORTED_ATOMS, &bufs.sorted_atoms.buffer),
                (b::CELL_START, &bufs.cell_start.buffer),
                (b::CELL_END, &bufs.cell_end.buffer),
                (b::BRICK_FLAGS, &bufs.brick_flags.buffer),
                (b::BRICK_SCAN, &bufs.brick_scan.buffer),
            ],
        );
        self.compact.bind(
            ctx,
            compact,
            &[
                (b::U, u),
                (b::BRICK_FLAGS, &bufs.brick_flags.buffer),
                (b::BRICK_SCAN, &bufs.brick_scan.buffer),
                (b::ACTIVE_BRICKS, &bufs.active_bricks.buffer),
                (b::DENSITY, &bufs.density.buffer),
            ],
        );
        self.args.bind(
            ctx,
            args,
            &[
                (b::U, u),
                (b::ACTIVE_BRICKS, &bufs.active_bricks.buffer),
                (b::BRICK_ARGS, &bufs.brick_args),
            ],
        );
        // The total (reached bricks) goes to word 3 of the dispatch arguments.
        scanner.prepare(
            ctx,
            &mut self.scan,
            &bufs.brick_scan.buffer,
            self.bricks,
            (&bufs.brick_args, 3),
        );
    }

    /// Records the prepared pass (after binning): mark, scan, compact, dispatch arguments.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, scanner: &Scanner) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("sparse bricks"),
            timestamp_writes: None,
        });
        let [mark, compact, args] = &self.binds;
        let groups = groups_1d(self.bricks.div_ceil(64), self.max_groups);
        self.mark.dispatch(&mut pass, mark, &[], groups);
        scanner.record(&mut pass, &self.scan);
        self.compact.dispatch(&mut pass, compact, &[], groups);
        self.args.dispatch(&mut pass, args, &[], [1, 1, 1]);
    }

    /// Records the copy of the reached-brick count (of the last brick pass) into the frame
    /// counters ([`super::types::GpuCounters::reached_bricks`]); every sparse frame does it, so
    /// a frame that re-runs only Marching Cubes reports the count too.
    pub fn record_count(encoder: &mut wgpu::CommandEncoder, bufs: &Buffers) {
        encoder.copy_buffer_to_buffer(
            &bufs.brick_args,
            12,
            &bufs.counters,
            4 * C_REACHED_BRICKS as u64,
            Some(4),
        );
    }
}
