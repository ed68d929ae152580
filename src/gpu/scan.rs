//! Reusable exclusive prefix sum of u32 arrays on the GPU (`shaders/scan.wgsl`): blocks of 1024
//! elements per workgroup, recursing over the block totals, adding the scanned totals back. The
//! grand total lands in a caller-chosen u32 slot (a counter the next stages read on the GPU).
//! Each scanned array has a persistent [`ScanPlan`] owned by the engine: its level uniforms are
//! rewritten in place, its block-total scratch grows, its bind groups are rebuilt only when a
//! buffer they bind was replaced.

use super::context::GpuContext;
use super::kernel::{Bound, Kernel, Layout, Uniform, groups_1d, module};
use super::layout::scan as b;
use super::resources::Grow;
use super::types::ScanUniform;

/// Elements per scan workgroup.
pub const SCAN_BLOCK: u64 = 1024;

/// The scan pipelines (one per device).
#[derive(Debug)]
pub struct Scanner {
    scan_blocks: Kernel,
    add_sums: Kernel,
    max_groups: u32,
}

/// One level of a scan: its uniform, its block totals (unless it is the top level) and bind
/// groups (the scan's kept for both roles, so a count that crosses a multiple of 1024 back and
/// forth rebuilds nothing).
#[derive(Debug)]
struct Level {
    uniform: Uniform<ScanUniform>,
    sums: Grow,
    scan: Bound,
    scan_top: Bound,
    add: Bound,
    groups: [u32; 3],
    top: bool,
}

/// The persistent scratch and bind groups that scan one data buffer (see the module docs).
#[derive(Debug, Default)]
pub struct ScanPlan {
    levels: Vec<Level>,
    used: usize,
    /// Number of elements scanned by the last [`Scanner::prepare`].
    pub count: u64,
}

impl Scanner {
    /// Compiles the scan kernels.
    pub fn new(ctx: &GpuContext, max_groups: u32) -> Scanner {
        let m = module(&ctx.device, "scan.wgsl", super::shaders::SCAN);
        let layout = Layout::new(ctx, "scan", b::ALL);
        Scanner {
            scan_blocks: Kernel::new(ctx, &m, "scan_blocks", &[], &layout),
            add_sums: Kernel::new(ctx, &m, "add_sums", &[], &layout),
            max_groups,
        }
    }

    /// Prepares `plan` for an exclusive scan of the first `count` u32 of `data`, writing the
    /// total to `total.0[total.1]` (a u32 index): writes the level uniforms, grows the scratch.
    pub fn prepare(
        &self,
        ctx: &GpuContext,
        plan: &mut ScanPlan,
        data: &wgpu::Buffer,
        count: u64,
        total: (&wgpu::Buffer, u32),
    ) {
        let mut n = count.max(1);
        let mut i = 0;
        loop {
            let blocks = n.div_ceil(SCAN_BLOCK);
            let top = blocks == 1;
            if plan.levels.len() == i {
                plan.levels.push(Level {
                    uniform: Uniform::new(ctx, "scan uniform"),
                    sums: Grow::new(ctx, "scan sums", wgpu::BufferUsages::empty()),
                    scan: Bound::default(),
                    scan_top: Bound::default(),
                    add: Bound::default(),
                    groups: [0; 3],
                    top,
                });
            }
            let (lower, upper) = plan.levels.split_at_mut(i);
            let level = &mut upper[0];
            if !top {
                level.sums.ensure_slack(ctx, blocks * 4);
            }
            level.uniform.write(
                &ctx.queue,
                &ScanUniform {
                    count: n as u32,
                    sum_index: if top { total.1 } else { 0 },
                    _pad: [0; 2],
                },
            );
            level.groups = groups_1d(blocks, self.max_groups);
            level.top = top;
            let level_data = match lower.last() {
                Some(below) => &below.sums.buffer,
                None => data,
            };
            let sums = if top { total.0 } else { &level.sums.buffer };
            let entries = [
                (b::U, &level.uniform.buffer),
                (b::DATA, level_data),
                (b::SUMS, sums),
            ];
            if top {
                self.scan_blocks.bind(ctx, &mut level.scan_top, &entries);
            } else {
                self.scan_blocks.bind(ctx, &mut level.scan, &entries);
                self.add_sums.bind(ctx, &mut level.add, &entries);
            }
            i += 1;
            if top {
                break;
            }
            n = blocks;
        }
        plan.used = i;
        plan.count = count;
    }

    /// Records the scan last prepared in `plan` into `pass` (dispatches separated by wgpu's
    /// automatic barriers).
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, plan: &ScanPlan) {
        let levels = &plan.levels[..plan.used];
        for l in levels {
            let bind = if l.top { &l.scan_top } else { &l.scan };
            self.scan_blocks.dispatch(pass, bind, &[], l.groups);
        }
        for l in levels.iter().rev().filter(|l| !l.top) {
            self.add_sums.dispatch(pass, &l.add, &[], l.groups);
        }
    }
}
