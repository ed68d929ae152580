//! Reusable exclusive prefix sum of u32 arrays on the GPU (`shaders/scan.wgsl`): blocks of 1024
//! elements per workgroup, recursing over the block totals, adding the scanned totals back. The
//! grand total lands in a caller-chosen u32 slot (a counter the next stages read on the GPU).

use super::kernel::{Kernel, groups_1d, module, storage, uniform};
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

/// Buffers and bind groups that scan one data buffer of a fixed element count.
#[derive(Debug)]
pub struct ScanPlan {
    /// (groups, scan bind group, add bind group or None at the top level), lowest level first.
    levels: Vec<([u32; 3], wgpu::BindGroup, Option<wgpu::BindGroup>)>,
    _buffers: Vec<wgpu::Buffer>,
    /// Number of elements scanned.
    pub count: u64,
}

impl Scanner {
    /// Compiles the scan kernels.
    pub fn new(device: &wgpu::Device, max_groups: u32) -> Scanner {
        let m = module(device, "scan.wgsl", super::shaders::SCAN);
        Scanner {
            scan_blocks: Kernel::new(device, &m, "scan_blocks", &[]),
            add_sums: Kernel::new(device, &m, "add_sums", &[]),
            max_groups,
        }
    }

    /// Plans an exclusive scan of the first `count` u32 of `data`, writing the total to
    /// `total.0[total.1]` (a u32 index).
    pub fn plan(
        &self,
        device: &wgpu::Device,
        data: &wgpu::Buffer,
        count: u64,
        total: (&wgpu::Buffer, u32),
    ) -> ScanPlan {
        let mut levels = Vec::new();
        let mut buffers = Vec::new();
        let mut level_data = data.clone();
        let mut n = count.max(1);
        loop {
            let blocks = n.div_ceil(SCAN_BLOCK);
            let top = blocks == 1;
            let sums = if top {
                total.0.clone()
            } else {
                storage(device, "scan sums", blocks * 4, wgpu::BufferUsages::empty())
            };
            let u = uniform(
                device,
                "scan uniform",
                &ScanUniform {
                    count: n as u32,
                    sum_index: if top { total.1 } else { 0 },
                    _pad: [0; 2],
                },
            );
            let entries = [
                (0, u.as_entire_binding()),
                (1, level_data.as_entire_binding()),
                (2, sums.as_entire_binding()),
            ];
            let scan_bind = self.scan_blocks.bind(device, &entries);
            let add_bind = (!top).then(|| self.add_sums.bind(device, &entries));
            levels.push((groups_1d(blocks, self.max_groups), scan_bind, add_bind));
            buffers.push(u);
            if top {
                break;
            }
            buffers.push(sums.clone());
            level_data = sums;
            n = blocks;
        }
        ScanPlan {
            levels,
            _buffers: buffers,
            count,
        }
    }

    /// Records the scan into `pass` (dispatches separated by wgpu's automatic barriers).
    pub fn record(&self, pass: &mut wgpu::ComputePass<'_>, plan: &ScanPlan) {
        for (groups, scan, _) in &plan.levels {
            self.scan_blocks.dispatch(pass, scan, *groups);
        }
        for (groups, _, add) in plan.levels.iter().rev() {
            if let Some(add) = add {
                self.add_sums.dispatch(pass, add, *groups);
            }
        }
    }
}
