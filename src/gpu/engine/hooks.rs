//! Test hooks (feature `test-hooks`): read a frame's intermediate buffers (density, class
//! words, bin cell starts) back to the host so tests can compare each stage with the CPU engine.
//! Not in the shipped binary.

use super::GpuEngine;
use crate::gpu::GpuError;
use crate::gpu::plan::{BRICK, BRICK_SAMPLES, CLASS_ENTRIES_PER_SLOT, FramePlan, SlotTable};

impl GpuEngine {
    /// Test hook: the density volume of the last slab (whole grid when there was one slab),
    /// voxel `i + nx * (j + ny * (k - dens_z0))`; on sparse bricks gathered from the brick slots
    /// (samples of unreached bricks are 0).
    pub fn read_density(&self) -> Result<Vec<f32>, GpuError> {
        if !self.options.sparse_bricks {
            return self.read_planned(&self.buffers.density.buffer, FramePlan::slab_voxels);
        }
        let Some(plan) = self.state.plan.as_ref() else {
            return Ok(Vec::new());
        };
        let words: Vec<u32> = self.staging()?.read_pod(
            &self.ctx,
            &self.buffers.density.buffer,
            self.buffers.density.size() / 4,
        )?;
        Ok(sparse_volume(plan, &words))
    }

    /// Test hook: class words of the last slab (see `shaders/classify.wgsl`), point
    /// `i + nx * (j + ny * (k - own_z0))`; on sparse classes gathered from the brick slots'
    /// entries (points without an entry are 0).
    pub fn read_classes(&self) -> Result<Vec<u32>, GpuError> {
        if !self.state.sparse_classes {
            return self.read_planned(&self.buffers.classes.buffer, FramePlan::class_points);
        }
        let Some(plan) = self.state.plan.as_ref() else {
            return Ok(Vec::new());
        };
        let mut staging = self.staging()?;
        let table: Vec<u32> =
            staging.read_pod(&self.ctx, &self.buffers.density.buffer, plan.brick_count())?;
        let entries: Vec<u32> = staging.read_pod(
            &self.ctx,
            &self.buffers.classes.buffer,
            self.buffers.classes.size() / 4,
        )?;
        Ok(sparse_classes(plan, &table, &entries))
    }

    /// Test hook: the radii (Å) the last frame binned: the given ones, or those its exposure
    /// pass wrote ([`GpuEngine::set_exposure`]).
    pub fn read_radii(&self) -> Result<Vec<f32>, GpuError> {
        let n = self.state.atoms;
        self.staging()?
            .read_pod(&self.ctx, &self.buffers.radii.buffer, n)
    }

    /// Test hook: the heavy atoms the last frame's exposure pass counted per atom (capped at
    /// the model's saturation).
    pub fn read_exposure_counts(&self) -> Result<Vec<u32>, GpuError> {
        let n = self.state.atoms;
        self.staging()?
            .read_pod(&self.ctx, self.stages.exposure.counts_buffer(), n)
    }

    /// Test hook: first slot of every bin cell after the scan.
    pub fn read_cell_starts(&self) -> Result<Vec<u32>, GpuError> {
        self.read_planned(&self.buffers.cell_start.buffer, FramePlan::cell_count)
    }

    /// Reads the first `len(plan)` elements of `buffer` (none before the first frame).
    fn read_planned<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        len: fn(&FramePlan) -> u64,
    ) -> Result<Vec<T>, GpuError> {
        let n = self.state.plan.as_ref().map(len).unwrap_or(0);
        self.staging()?.read_pod(&self.ctx, buffer, n)
    }
}

/// The density of the last slab of `plan` as a dense slab volume, from the words of the sparse
/// density buffer: the brick slot table ([`SlotTable`]), then [`BRICK_SAMPLES`] samples per
/// slot counted from the slab's first brick layer.
fn sparse_volume(plan: &FramePlan, words: &[u32]) -> Vec<f32> {
    let [nx, ny, _] = plan.grid.dims;
    let Some(slab) = plan.slabs.last() else {
        return Vec::new();
    };
    let slots = SlotTable::new(plan, words);
    let first = slots.first_slot(slab);
    let samples_from = plan.brick_count();
    let mut out = Vec::with_capacity(plan.slab_voxels() as usize);
    for kl in 0..slab.dens_layers {
        let k = slab.dens_z0 + kl;
        for j in 0..ny {
            for i in 0..nx {
                let v = slots
                    .slot([i / BRICK, j / BRICK, k / BRICK])
                    .map_or(0.0, |t| {
                        let local = i % BRICK + BRICK * (j % BRICK + BRICK * (k % BRICK));
                        let at = samples_from + (t - first) as u64 * BRICK_SAMPLES + local as u64;
                        f32::from_bits(words.get(at as usize).copied().unwrap_or(0))
                    });
                out.push(v);
            }
        }
    }
    out
}

/// The class words of the last slab of `plan` per classified point, from the brick slot table
/// (`table`, [`SlotTable`]) and the class entries of sparse classes: the host twin of
/// `class_entry` in `shaders/class_entries.wgsl`.
fn sparse_classes(plan: &FramePlan, table: &[u32], entries: &[u32]) -> Vec<u32> {
    let dims = plan.grid.dims;
    let Some(slab) = plan.slabs.last() else {
        return Vec::new();
    };
    let slots = SlotTable::new(plan, table);
    let first = slots.first_slot(slab);
    let apron = BRICK + 1;
    let entry = |p: [u32; 3]| -> Option<usize> {
        // Along an axis where p is the last sample of its brick, the brick above may hold it.
        let up = [0, 1, 2].map(|a| u32::from(p[a] % BRICK == BRICK - 1 && p[a] + 1 < dims[a]));
        for dz in 0..=up[2] {
            for dy in 0..=up[1] {
                for dx in 0..=up[0] {
                    let d = [dx, dy, dz];
                    if let Some(t) = slots.slot([0, 1, 2].map(|a| p[a] / BRICK + d[a])) {
                        let l = [0, 1, 2].map(|a| p[a] % BRICK + 1 - BRICK * d[a]);
                        let local = l[0] + apron * (l[1] + apron * l[2]);
                        let e = (t - first) as u64 * CLASS_ENTRIES_PER_SLOT + local as u64;
                        return Some(e as usize);
                    }
                }
            }
        }
        None
    };
    let class_z1 = (slab.own_z1 + 1).min(dims[2]);
    let mut out = Vec::with_capacity(plan.class_points() as usize);
    for kl in 0..plan.class_layers {
        let k = slab.own_z0 + kl;
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let word = (k < class_z1)
                    .then(|| entry([i, j, k]))
                    .flatten()
                    .and_then(|e| entries.get(e).copied());
                out.push(word.unwrap_or(0));
            }
        }
    }
    out
}
