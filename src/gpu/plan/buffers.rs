//! The bytes of a frame's buffers: device limits, storage rounding, when a buffer must be
//! replaced ([`Need`]), mesh capacity growth, [`BufferPlan`]'s sizes and the [`GpuMemory`] a
//! fresh engine holds after a frame.

use super::*;

/// Bytes of one output vertex ([`GpuVertex`]: position, normal, colour).
pub const BYTES_PER_VERTEX: u64 = size_of::<GpuVertex>() as u64;
/// Bytes of one output triangle (three u32 indices).
pub const BYTES_PER_TRIANGLE: u64 = 12;
/// Bytes of the area/volume partial sums (two f32 per workgroup of the partial sums).
pub const PARTIALS_BYTES: u64 = crate::gpu::measure::PARTIAL_GROUPS as u64 * 8;
/// Bytes of an indirect dispatch buffer (3 u32 arguments plus one spare word).
pub const DISPATCH_ARGS_BYTES: u64 = 16;
/// The engine's default mesh headroom: grown mesh buffers hold this many times the counts
/// that made them grow (the default of `EngineOptions::headroom`).
pub const DEFAULT_HEADROOM: f32 = 1.25;

/// The device limits that size the engine's buffers, in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceLimits {
    /// `max_storage_buffer_binding_size`.
    pub max_storage_binding: u64,
    /// `max_buffer_size`.
    pub max_buffer_size: u64,
    /// `min_uniform_buffer_offset_alignment` (the stride of the per-slab uniforms).
    pub uniform_alignment: u64,
}

impl DeviceLimits {
    /// What wgpu 30 reported on an 80 GB NVIDIA H100 under Vulkan (driver 580.159, read by
    /// `mdsurf bench --table1 --backend gpu` on 2026-11-24), the limits `mdsurf bench --table1
    /// --plan-only` sizes for: storage bindings of 2^31 - 4 bytes, buffers of 4,292,870,144
    /// bytes (just under 4 GiB, so the volume budget is a quarter of it, about 1 GiB), and
    /// uniform offsets aligned to 256 bytes (WebGPU's default, which the engine asks for).
    pub const NVIDIA_80GB: DeviceLimits = DeviceLimits {
        max_storage_binding: 2_147_483_644,
        max_buffer_size: 4_292_870_144,
        uniform_alignment: 256,
    };

    /// The limits a device was created with.
    pub fn of(limits: &wgpu::Limits) -> DeviceLimits {
        DeviceLimits {
            max_storage_binding: limits.max_storage_buffer_binding_size,
            max_buffer_size: limits.max_buffer_size,
            uniform_alignment: limits.min_uniform_buffer_offset_alignment as u64,
        }
    }

    /// Largest single storage binding in bytes.
    pub fn max_binding(&self) -> u64 {
        self.max_storage_binding.min(self.max_buffer_size)
    }

    /// The engine's default budget for the per-voxel slab buffers in bytes: a quarter of the
    /// largest buffer, within 64 MiB..4 GiB (the default of `EngineOptions::volume_budget`).
    pub fn volume_budget(&self) -> u64 {
        (self.max_buffer_size / 4).clamp(64 << 20, 4 << 30)
    }

    /// Bytes between two slabs' uniforms (a [`SlabUniform`] rounded up to the alignment).
    pub fn slab_uniform_stride(&self) -> u64 {
        (size_of::<SlabUniform>() as u64).next_multiple_of(self.uniform_alignment.max(16))
    }
}

/// Bytes a storage buffer asked for `bytes` is created with: wgpu wants a multiple of 4, and
/// the engine never makes one under 16.
pub fn storage_bytes(bytes: u64) -> u64 {
    bytes.max(16).next_multiple_of(4)
}

/// `bytes` plus an eighth to spare, within the largest binding (never less than `bytes`).
pub fn with_slack(bytes: u64, max_binding: u64) -> u64 {
    (bytes + bytes / 8).min(max_binding).max(bytes)
}

/// Bytes the slab uniform buffer is replaced with when `slabs` uniforms of `stride` bytes do
/// not fit: a quarter more slabs to spare.
pub fn slab_uniform_replacement(slabs: u64, stride: u64) -> u64 {
    (stride * slabs.max(1) + (slabs / 4) * stride).next_multiple_of(16)
}

/// What one growing buffer needs for a frame, in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Need {
    /// Bytes the frame uses; a smaller buffer is replaced.
    pub bytes: u64,
    /// Bytes the replacement asks for (`bytes` plus any room to spare).
    pub replace_with: u64,
}

impl Need {
    /// Exactly `bytes`.
    pub fn exact(bytes: u64) -> Need {
        Need {
            bytes,
            replace_with: bytes,
        }
    }

    /// `bytes`, replaced with an eighth to spare ([`with_slack`]).
    pub fn slack(bytes: u64, max_binding: u64) -> Need {
        Need {
            bytes,
            replace_with: with_slack(bytes, max_binding),
        }
    }

    /// Bytes the buffer holds in a fresh engine (every growing buffer starts at 16 bytes)
    /// after a frame with this need.
    pub fn fresh(&self) -> u64 {
        if self.bytes <= 16 {
            16
        } else {
            storage_bytes(self.replace_with)
        }
    }
}

/// Vertex and triangle capacity of each output set's mesh buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshCapacity {
    /// Vertices.
    pub vertices: u64,
    /// Triangles.
    pub triangles: u64,
}

impl MeshCapacity {
    /// The capacity `want` asks for, within the largest binding (vertices of
    /// [`BYTES_PER_VERTEX`], triangles of [`BYTES_PER_TRIANGLE`]).
    pub fn clipped(want: (u64, u64), max_binding: u64) -> MeshCapacity {
        MeshCapacity {
            vertices: want.0.min(max_binding / BYTES_PER_VERTEX),
            triangles: want.1.min(max_binding / BYTES_PER_TRIANGLE),
        }
    }

    /// The most the mesh buffers can ever hold: each one the largest binding. An upper bound
    /// for any surface.
    pub fn largest(max_binding: u64) -> MeshCapacity {
        Self::clipped((u64::MAX, u64::MAX), max_binding)
    }

    /// The capacity a fresh engine settles at for a surface of `counts` (vertices, triangles)
    /// when its first frame asked for `first_want` ([`first_mesh_want`] unless the caller set
    /// `EngineOptions::initial_mesh_capacity`): grown by [`grown_mesh_want`] when a count
    /// passes 90 % of the first capacity. One growth settles, since the grown capacity holds
    /// more than the count over 0.9.
    pub fn settled(
        first_want: (u64, u64),
        counts: (u64, u64),
        headroom: f32,
        max_binding: u64,
    ) -> MeshCapacity {
        let first = Self::clipped(first_want, max_binding);
        let v = grown_mesh_want(counts.0, first.vertices, headroom);
        let t = grown_mesh_want(counts.1, first.triangles, headroom);
        if v.is_none() && t.is_none() {
            return first;
        }
        let grown = (
            first_want.0.max(v.unwrap_or(0)),
            first_want.1.max(t.unwrap_or(0)),
        );
        Self::clipped(grown, max_binding)
    }
}

/// The engine's first guess of the mesh size (vertices, triangles) before any frame was
/// counted: a surface through about an eighth of the grid's layers.
pub fn first_mesh_want(plan: &FramePlan) -> (u64, u64) {
    let [nx, ny, nz] = plan.grid.dims.map(|d| d as u64);
    let v = (nx * ny + ny * nz + nx * nz) * 2 + plan.grid.voxel_count() / 16;
    (v.max(4096), 2 * v.max(4096))
}

/// The mesh buffers' growth rule: when `count` passes 90 % of `capacity`, they should hold
/// `count` times `headroom` (at least 1) plus 64; None while the count is below that mark, so
/// counts that wander a little from frame to frame settle.
pub fn grown_mesh_want(count: u64, capacity: u64, headroom: f32) -> Option<u64> {
    let h = headroom.max(1.0) as f64;
    (count as f64 > 0.9 * capacity as f64).then(|| (count as f64 * h).ceil() as u64 + 64)
}

/// Every buffer of the engine sized for one frame (see the module docs): the growing ones as
/// [`Need`]s, the fixed ones in bytes. [`crate::gpu::resources::Buffers`] grows to it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BufferPlan {
    /// Positions, 12 bytes per atom.
    pub positions: Need,
    /// Radii, 4 bytes per atom.
    pub radii: Need,
    /// Packed colours, 8 bytes per atom.
    pub colours: Need,
    /// Sorted atoms, 16 bytes per atom.
    pub sorted_atoms: Need,
    /// Sorted packed colours, 8 bytes per atom.
    pub sorted_colours: Need,
    /// First slot per bin cell (u32).
    pub cell_start: Need,
    /// One past the last slot per bin cell (u32).
    pub cell_end: Need,
    /// Slab density, 4 bytes per voxel; on sparse bricks the brick slot table (4 bytes per
    /// brick) and 4 bytes per sample of each brick slot.
    pub density: Need,
    /// Slab colour, 12 bytes per voxel, or per sample of each brick slot (none without
    /// colours).
    pub colour: Need,
    /// Class words, 4 bytes per class entry ([`ClassEntries`]).
    pub classes: Need,
    /// Vertex base, 4 bytes per class entry.
    pub vertex_base: Need,
    /// Active cells, 8 bytes per class entry.
    pub active: Need,
    /// Where the class entries live (per classified point, or per brick slot).
    pub class_entries: ClassEntries,
    /// Each of the three block-sum arrays, 4 bytes per classification block.
    pub block_sums: Need,
    /// Reached flag per sparse brick (u32).
    pub brick_flags: Need,
    /// Scanned flags per sparse brick (u32).
    pub brick_scan: Need,
    /// Reached-brick count and list (u32).
    pub active_bricks: Need,
    /// Output vertices of one output set.
    pub vertices: Need,
    /// Output indices of one output set.
    pub indices: Need,
    /// Bytes of the per-slab uniform buffer of a fresh engine.
    pub slab_uniforms: u64,
}

impl BufferPlan {
    /// The buffers of a frame of `atoms` atoms on `plan` (with the colour volume when
    /// `with_colour`) and mesh buffers of `mesh` capacity, on a device with `limits`;
    /// `brick_slots`: on sparse bricks, the reached bricks the density and colour buffers hold
    /// (None: the dense per-slab volumes).
    pub fn new(
        plan: &FramePlan,
        atoms: u64,
        with_colour: bool,
        mesh: MeshCapacity,
        brick_slots: Option<u64>,
        limits: &DeviceLimits,
    ) -> BufferPlan {
        let max_binding = limits.max_binding();
        let slack = |bytes| Need::slack(bytes, max_binding);
        let cells = plan.cell_count();
        let voxels = plan.slab_voxels();
        let class_entries = ClassEntries::for_plan(plan, brick_slots);
        let entries = class_entries.entries;
        // Brick buffers are replaced with room for one more brick per axis: a box that
        // breathes across a multiple of 8 samples adds a whole brick layer, more than the
        // usual eighth to spare.
        let bricks = plan.brick_count();
        let roomy: u64 = plan.brick_dims.iter().map(|&d| d as u64 + 1).product();
        let brick_need = |extra: u64| Need {
            bytes: (bricks + extra) * 4,
            replace_with: (roomy + extra) * 4,
        };
        let stride = limits.slab_uniform_stride();
        let slabs = plan.slabs.len() as u64;
        let slab_uniforms = if slabs <= 1 {
            stride
        } else {
            slab_uniform_replacement(slabs, stride)
        };
        BufferPlan {
            positions: Need::exact(atoms * 12),
            radii: Need::exact(atoms * 4),
            colours: Need::exact(atoms * 8),
            sorted_atoms: Need::exact(atoms * 16),
            sorted_colours: Need::exact(atoms * 8),
            cell_start: slack(cells * 4),
            cell_end: slack(cells * 4),
            density: match brick_slots {
                // The slot table (room for a brick more per axis, as the brick buffers) and
                // the slots themselves (the grown count already has room to spare).
                Some(slots) => Need {
                    bytes: (bricks + slots * BRICK_SAMPLES) * 4,
                    replace_with: (roomy + slots * BRICK_SAMPLES) * 4,
                },
                None => slack(voxels * 4),
            },
            colour: match (with_colour, brick_slots) {
                (false, _) => Need::default(),
                (true, Some(slots)) => Need::exact(slots * BRICK_SAMPLES * 12),
                (true, None) => slack(voxels * 12),
            },
            classes: slack(entries * 4),
            vertex_base: slack(entries * 4),
            active: slack(entries * 8),
            class_entries,
            block_sums: slack(plan.class_blocks() * 4),
            brick_flags: brick_need(0),
            brick_scan: brick_need(0),
            active_bricks: brick_need(1),
            vertices: Need::exact(mesh.vertices * BYTES_PER_VERTEX),
            indices: Need::exact(mesh.triangles * BYTES_PER_TRIANGLE),
            slab_uniforms,
        }
    }

    /// GPU memory a fresh engine holds after a frame with these needs (what
    /// [`crate::gpu::GpuEngine::gpu_bytes`] reports), by group.
    pub fn fresh_memory(&self) -> GpuMemory {
        let sum = |needs: &[Need]| needs.iter().map(Need::fresh).sum::<u64>();
        let output_set = self.vertices.fresh()
            + self.indices.fresh()
            + storage_bytes(size_of::<DrawIndexedArgs>() as u64);
        GpuMemory {
            atoms: sum(&[
                self.positions,
                self.radii,
                self.colours,
                self.sorted_atoms,
                self.sorted_colours,
            ]),
            cells: sum(&[self.cell_start, self.cell_end]),
            volumes: sum(&[
                self.density,
                self.colour,
                self.classes,
                self.vertex_base,
                self.active,
            ]) + 3 * self.block_sums.fresh(),
            bricks: sum(&[self.brick_flags, self.brick_scan, self.active_bricks]),
            mesh: crate::gpu::resources::OUTPUT_SETS as u64 * output_set,
            fixed: storage_bytes(size_of::<GpuCounters>() as u64)
                + 2 * DISPATCH_ARGS_BYTES
                + PARTIALS_BYTES
                + (size_of::<McTablesUniform>() as u64).next_multiple_of(4)
                + self.slab_uniforms,
        }
    }
}

/// GPU memory of the engine's buffers by group, in bytes. Not counted (as in
/// [`crate::gpu::GpuEngine::gpu_bytes`]): the prefix sums' block totals (4 bytes per 1024 scanned
/// elements), stage uniforms, timestamp and counter readback buffers (about 150 KB) and the
/// staging buffer of a mesh readback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GpuMemory {
    /// Per-atom inputs and their sorted copies.
    pub atoms: u64,
    /// Bin cell ranges.
    pub cells: u64,
    /// Per-slab volumes: density, colour, class words, vertex bases, active cells, block sums.
    pub volumes: u64,
    /// Sparse-brick flags and list.
    pub bricks: u64,
    /// Both output sets' vertices, indices and draw arguments.
    pub mesh: u64,
    /// Counters, dispatch arguments, partial sums, Marching Cubes tables, slab uniforms.
    pub fixed: u64,
}

impl GpuMemory {
    /// All groups together.
    pub fn total(&self) -> u64 {
        self.atoms + self.cells + self.volumes + self.bricks + self.mesh + self.fixed
    }
}
