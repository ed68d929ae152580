//! Sizing one frame before anything is dispatched: the bin cell grid, the z-slabs the density and
//! Marching Cubes run in (so no buffer exceeds the device's binding limit or the memory budget),
//! the sparse bricks of [`BRICK`]^3 samples, and the bytes that costs. Pure arithmetic, tested
//! without a GPU.
//!
//! The bytes are computed in one place, [`BufferPlan`]: the engine's buffers
//! ([`super::resources::Buffers`]) are grown to exactly its sizes, and
//! [`BufferPlan::fresh_memory`] adds up what a fresh engine holds after a frame, so the GPU
//! memory of a frame is known without a device (`mdsurf bench --table1 --plan-only`) and
//! cannot drift from what the engine allocates (`tests/it/gpu_plan_memory.rs` checks both
//! against [`super::GpuEngine::gpu_bytes`]).

use crate::surface::{GridSpec, SurfaceParams};

use super::GpuError;
use super::types::{DrawIndexedArgs, GpuCounters, GpuVertex, McTablesUniform, SlabUniform};

/// Bytes per voxel of a slab: density 4, colour 12, class word 4, vertex base 4, active cell 8
/// (on sparse bricks density and colour are held per reached brick instead).
pub const BYTES_PER_VOXEL: u64 = 32;
/// Samples per sparse-brick edge (`BRICK` in `shaders/bricks.wgsl`, `density.wgsl` and
/// `classify.wgsl`); one density thread's run of [`super::density::RUN`] voxels spans a brick row.
pub const BRICK: u32 = 8;
const _: () = assert!(BRICK == super::density::RUN);

/// Bytes per atom: positions 12, radius 4, packed colour 8, sorted atom 16, sorted colour 8.
pub const BYTES_PER_ATOM: u64 = 48;

/// One z-slab: the layers it owns and the layers of density it computes (owned plus one below
/// for the normals and two above for the shared top layer's edges and normals).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slab {
    /// First owned layer.
    pub own_z0: u32,
    /// One past the last owned layer.
    pub own_z1: u32,
    /// First density layer computed.
    pub dens_z0: u32,
    /// Density layers computed.
    pub dens_layers: u32,
}

/// Everything sized for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlan {
    /// The density grid.
    pub grid: GridSpec,
    /// Bin cell edge in Å.
    pub cell_size: f32,
    /// Bin cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Largest cutoff distance in Å.
    pub max_cut: f32,
    /// The slabs, bottom to top.
    pub slabs: Vec<Slab>,
    /// Layers classified per slab (largest owned count + 1, capped at nz).
    pub class_layers: u32,
    /// Largest density layer count of any slab.
    pub dens_layers: u32,
    /// Sparse bricks of [`BRICK`]^3 samples along x, y, z, covering the whole grid (the last
    /// brick along an axis may stick out of it).
    pub brick_dims: [u32; 3],
}

impl FramePlan {
    /// Number of bin cells.
    pub fn cell_count(&self) -> u64 {
        self.cell_dims.iter().map(|&d| d as u64).product()
    }

    /// Points classified per slab.
    pub fn class_points(&self) -> u64 {
        self.grid.dims[0] as u64 * self.grid.dims[1] as u64 * self.class_layers as u64
    }

    /// Voxels held in the density buffer.
    pub fn slab_voxels(&self) -> u64 {
        self.grid.dims[0] as u64 * self.grid.dims[1] as u64 * self.dens_layers as u64
    }

    /// Number of sparse bricks covering the grid.
    pub fn brick_count(&self) -> u64 {
        self.brick_dims.iter().map(|&d| d as u64).product()
    }

    /// Workgroups of 256 points in classification.
    pub fn class_blocks(&self) -> u64 {
        self.class_points().div_ceil(256)
    }

    /// Bricks the density layers of `slab` touch (whole brick layers).
    pub fn slab_bricks(&self, slab: &Slab) -> u64 {
        let bz0 = slab.dens_z0 / BRICK;
        let bz1 = (slab.dens_z0 + slab.dens_layers.max(1) - 1) / BRICK;
        (bz1 - bz0 + 1) as u64 * self.brick_dims[0] as u64 * self.brick_dims[1] as u64
    }

    /// The most brick slots one slab can use: every brick its density layers touch.
    pub fn max_slab_bricks(&self) -> u64 {
        self.slabs
            .iter()
            .map(|s| self.slab_bricks(s))
            .max()
            .unwrap_or(1)
    }
}

/// Samples per sparse brick ([`BRICK`]^3).
pub const BRICK_SAMPLES: u64 = (BRICK * BRICK * BRICK) as u64;

/// Class entries per brick slot on sparse classes, (`BRICK` + 1)^3 (`shaders/class_entries.wgsl`):
/// a reached brick holds its own points' class words and vertex bases, and the points just below
/// it in unreached bricks, whose cells reach into it.
pub const CLASS_ENTRIES_PER_SLOT: u64 = ((BRICK + 1) * (BRICK + 1) * (BRICK + 1)) as u64;

/// The class entries (class words and vertex bases) one slab needs and whether they are held
/// per brick slot (`sparse`): on sparse bricks with `brick_slots` slots, per slot when that
/// takes fewer entries than one per classified point ([`FramePlan::class_points`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClassEntries {
    /// Entries of the class-word and vertex-base buffers (the active-cell list holds as many).
    pub entries: u64,
    /// Held per brick slot.
    pub sparse: bool,
}

impl ClassEntries {
    /// The layout for `plan` with `brick_slots` (None: dense volumes).
    pub fn for_plan(plan: &FramePlan, brick_slots: Option<u64>) -> ClassEntries {
        let points = plan.class_points();
        match brick_slots {
            Some(slots) if slots * CLASS_ENTRIES_PER_SLOT < points => ClassEntries {
                entries: slots * CLASS_ENTRIES_PER_SLOT,
                sparse: true,
            },
            _ => ClassEntries {
                entries: points,
                sparse: false,
            },
        }
    }
}

/// The most brick slots the largest binding allows (the colour slots, 12 bytes per sample,
/// and the density table plus slots).
pub fn brick_slot_limit(plan: &FramePlan, max_binding: u64) -> u64 {
    let roomy: u64 = plan.brick_dims.iter().map(|&d| d as u64 + 1).product();
    let by_colour = max_binding / (12 * BRICK_SAMPLES);
    let by_density = (max_binding / 4).saturating_sub(roomy) / BRICK_SAMPLES;
    by_colour.min(by_density).max(1)
}

/// The brick slots the buffers grow to when a frame's slabs needed `slots` (the most reached
/// bricks of one slab) and the buffers held `capacity` slots (None when they suffice): the
/// need with an eighth to spare, rounded up to a multiple of 64 bricks, within
/// [`brick_slot_limit`].
pub fn grown_brick_want(
    plan: &FramePlan,
    slots: u64,
    capacity: u64,
    max_binding: u64,
) -> Option<u64> {
    let need = slots.min(plan.max_slab_bricks());
    (need > capacity).then(|| {
        (need + need / 8)
            .next_multiple_of(64)
            .min(brick_slot_limit(plan, max_binding))
    })
}

/// The brick slots a fresh engine settles at for a frame on `plan` whose slabs need `slots`
/// (the most reached bricks of one slab: [`ReachedBricks::slab_need`]). Its first sparse
/// frame counts the reached bricks before density runs (a brick pass, read back once), so the
/// slots are sized from that count as [`grown_brick_want`] grows them, and density runs once.
pub fn settled_brick_slots(plan: &FramePlan, slots: u64, max_binding: u64) -> u64 {
    grown_brick_want(plan, slots.max(1), 0, max_binding).unwrap_or(1)
}

/// The most brick slots the engine can hold on `plan`: grown for a slab whose every brick is
/// reached.
pub fn largest_brick_slots(plan: &FramePlan, max_binding: u64) -> u64 {
    settled_brick_slots(plan, plan.max_slab_bricks(), max_binding)
}

/// The brick slot table the sparse-brick pass writes into the first words of the density
/// buffer (`shaders/bricks.wgsl`), read on the host: per brick its slot (the exclusive scan of
/// the reached flags), with [`SlotTable::UNREACHED`] set when no atom reaches it.
#[derive(Debug, Clone, Copy)]
pub struct SlotTable<'a> {
    plan: &'a FramePlan,
    words: &'a [u32],
}

impl<'a> SlotTable<'a> {
    /// The bit set on an unreached brick's word.
    pub const UNREACHED: u32 = 1 << 31;

    /// The table of `plan` in `words` (its first [`FramePlan::brick_count`] words are read).
    pub fn new(plan: &'a FramePlan, words: &'a [u32]) -> SlotTable<'a> {
        SlotTable { plan, words }
    }

    /// The slot of brick `b` (brick coordinates), None when no atom reaches it (or it lies
    /// outside the table).
    pub fn slot(&self, b: [u32; 3]) -> Option<u32> {
        let [bx, by, bz] = self.plan.brick_dims;
        if b[0] >= bx || b[1] >= by || b[2] >= bz {
            return None;
        }
        let t = *self.words.get((b[0] + bx * (b[1] + by * b[2])) as usize)?;
        (t & Self::UNREACHED == 0).then_some(t)
    }

    /// The slot the slots of `slab` count from: that of its first density brick layer (the
    /// reached bricks before it, for an unreached brick too).
    pub fn first_slot(&self, slab: &Slab) -> u32 {
        let [bx, by, _] = self.plan.brick_dims;
        let at = ((slab.dens_z0 / BRICK) * bx * by) as usize;
        self.words.get(at).copied().unwrap_or(0) & !Self::UNREACHED
    }

    /// Reached bricks per brick layer (z), bottom to top.
    pub fn reached(&self) -> ReachedBricks {
        let [bx, by, bz] = self.plan.brick_dims;
        let layer = (bx * by).max(1) as usize;
        ReachedBricks {
            layers: self
                .words
                .chunks(layer)
                .take(bz as usize)
                .map(|l| l.iter().filter(|&&t| t & Self::UNREACHED == 0).count() as u64)
                .collect(),
        }
    }
}

/// Reached sparse bricks per brick layer (z), counted on the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReachedBricks {
    /// Reached bricks of each brick layer, bottom to top.
    pub layers: Vec<u64>,
}

impl ReachedBricks {
    /// All reached bricks ([`super::output::FrameStats::reached_bricks`]).
    pub fn total(&self) -> u64 {
        self.layers.iter().sum()
    }

    /// The most reached bricks the density layers of one slab of `plan` touch: the brick
    /// slots the frame needs ([`super::output::FrameStats::brick_slots`]).
    pub fn slab_need(&self, plan: &FramePlan) -> u64 {
        plan.slabs
            .iter()
            .map(|s| {
                let bz0 = (s.dens_z0 / BRICK) as usize;
                let bz1 = ((s.dens_z0 + s.dens_layers.max(1) - 1) / BRICK) as usize;
                self.layers[bz0..=bz1.min(self.layers.len() - 1)]
                    .iter()
                    .sum::<u64>()
            })
            .max()
            .unwrap_or(0)
    }
}

/// The bricks `shaders/bricks.wgsl` marks as reached for atoms at `positions` (Å) of radii
/// `radii` (Å) on `plan`, counted on the host with the shader's f32 arithmetic (`mark`: the
/// atoms of the bin cells around each brick, the same slack), per brick layer: what the
/// engine's counters report, so the brick slots are known without a device.
pub fn count_reached_bricks(
    plan: &FramePlan,
    positions: &[glam::Vec3],
    radii: &[f32],
    radius_scale: f32,
    cutoff: f32,
) -> ReachedBricks {
    let g = &plan.grid;
    let o = g.origin;
    let cd = plan.cell_dims;
    let cell_coord = |x: f32, o: f32, n: u32| -> u32 {
        (((x - o) / plan.cell_size).floor() as i32).clamp(0, n as i32 - 1) as u32
    };
    let cell_index = |c: [u32; 3]| (c[0] + cd[0] * (c[1] + cd[1] * c[2])) as usize;
    let mut cells: Vec<Vec<(glam::Vec3, f32)>> = vec![Vec::new(); plan.cell_count() as usize];
    for (p, &r) in positions.iter().zip(radii) {
        let c = [
            cell_coord(p.x, o.x, cd[0]),
            cell_coord(p.y, o.y, cd[1]),
            cell_coord(p.z, o.z, cd[2]),
        ];
        cells[cell_index(c)].push((*p, r * radius_scale));
    }
    let reach = plan.max_cut * 1.0001 + 1e-4;
    let [bx, by, bz] = plan.brick_dims;
    let mut reached = vec![0; bz as usize];
    for k in 0..bz {
        for j in 0..by {
            for i in 0..bx {
                let corner = |add: u32| {
                    glam::Vec3::new(
                        o.x + g.spacing * (i * BRICK + add) as f32,
                        o.y + g.spacing * (j * BRICK + add) as f32,
                        o.z + g.spacing * (k * BRICK + add) as f32,
                    )
                };
                let (lo, hi) = (corner(0), corner(BRICK - 1));
                let c0 = [
                    cell_coord(lo.x - reach, o.x, cd[0]),
                    cell_coord(lo.y - reach, o.y, cd[1]),
                    cell_coord(lo.z - reach, o.z, cd[2]),
                ];
                let c1 = [
                    cell_coord(hi.x + reach, o.x, cd[0]),
                    cell_coord(hi.y + reach, o.y, cd[1]),
                    cell_coord(hi.z + reach, o.z, cd[2]),
                ];
                let hit = (c0[2]..=c1[2]).any(|cz| {
                    (c0[1]..=c1[1]).any(|cy| {
                        (c0[0]..=c1[0]).any(|cx| {
                            cells[cell_index([cx, cy, cz])].iter().any(|&(a, w)| {
                                let d = (lo - a).max(a - hi).max(glam::Vec3::ZERO);
                                let c = cutoff * w * 1.001 + 1e-3;
                                d.x * d.x + d.y * d.y + d.z * d.z < c * c
                            })
                        })
                    })
                });
                reached[k as usize] += u64::from(hit);
            }
        }
    }
    ReachedBricks { layers: reached }
}

/// Plans a frame on `grid` for atoms of largest radius `max_radius` (Å). `max_binding` is the
/// largest storage binding (bytes), `volume_budget` the bytes allowed for slab buffers, and
/// `max_slab_layers` an optional cap on owned layers per slab (tests force slabs with it).
pub fn plan_frame(
    grid: GridSpec,
    params: &SurfaceParams,
    max_radius: f32,
    max_binding: u64,
    volume_budget: u64,
    max_slab_layers: Option<u32>,
) -> Result<FramePlan, GpuError> {
    let [nx, ny, nz] = grid.dims;
    let h = grid.spacing;
    let max_cut = params.cutoff() * params.radius_scale * max_radius;
    // Cells at least one cutoff wide (so 3 cells per axis reach) and one voxel wide, and few
    // enough that the per-cell arrays fit one binding.
    let mut cell_size = max_cut.max(h);
    let extent = [
        (nx - 1) as f32 * h,
        (ny - 1) as f32 * h,
        (nz - 1) as f32 * h,
    ];
    let dims_for = |c: f32| extent.map(|e| (e / c).floor() as u32 + 1);
    let limit = (max_binding / 4).min(u32::MAX as u64 / 2);
    loop {
        let d = dims_for(cell_size);
        let count: u64 = d.iter().map(|&v| v as u64).product();
        if count <= limit {
            break;
        }
        cell_size *= ((count as f64 / limit as f64).cbrt() as f32).max(1.01);
    }
    let cell_dims = dims_for(cell_size);

    let layer = nx as u64 * ny as u64;
    // The colour volume (12 bytes per voxel) is the largest per-voxel binding.
    let by_binding = max_binding / (12 * layer);
    let by_budget = volume_budget / (BYTES_PER_VOXEL * layer);
    let fit = by_binding
        .min(by_budget)
        .min(u32::MAX as u64 / layer.max(1));
    if fit < 4 {
        return Err(GpuError::TooLarge {
            what: "one 4-layer slab of the density grid",
            needed: 4 * BYTES_PER_VOXEL * layer,
            limit: by_binding.min(by_budget) * BYTES_PER_VOXEL * layer,
        });
    }
    let mut own = if fit as u32 >= nz { nz } else { fit as u32 - 3 };
    if let Some(cap) = max_slab_layers {
        own = own.min(cap.max(1));
    }
    let mut slabs = Vec::new();
    let mut z0 = 0;
    while z0 < nz {
        let z1 = (z0 + own).min(nz);
        let d0 = z0.saturating_sub(1);
        let d1 = (z1 + 2).min(nz);
        slabs.push(Slab {
            own_z0: z0,
            own_z1: z1,
            dens_z0: d0,
            dens_layers: d1 - d0,
        });
        z0 = z1;
    }
    let dens_layers = slabs.iter().map(|s| s.dens_layers).max().unwrap_or(1);
    Ok(FramePlan {
        grid,
        cell_size,
        cell_dims,
        max_cut,
        slabs,
        class_layers: (own + 1).min(nz),
        dens_layers,
        brick_dims: grid.dims.map(|d| d.div_ceil(BRICK)),
    })
}

/// Bytes of one output vertex ([`GpuVertex`]: position, normal, colour).
pub const BYTES_PER_VERTEX: u64 = size_of::<GpuVertex>() as u64;
/// Bytes of one output triangle (three u32 indices).
pub const BYTES_PER_TRIANGLE: u64 = 12;
/// Bytes of the area/volume partial sums (256 workgroups, two f32 each).
pub const PARTIALS_BYTES: u64 = 256 * 8;
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
/// [`Need`]s, the fixed ones in bytes. [`super::resources::Buffers`] grows to it.
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
    /// [`super::GpuEngine::gpu_bytes`] reports), by group.
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
            mesh: super::resources::OUTPUT_SETS as u64 * output_set,
            fixed: storage_bytes(size_of::<GpuCounters>() as u64)
                + 2 * DISPATCH_ARGS_BYTES
                + PARTIALS_BYTES
                + (size_of::<McTablesUniform>() as u64).next_multiple_of(4)
                + self.slab_uniforms,
        }
    }
}

/// GPU memory of the engine's buffers by group, in bytes. Not counted (as in
/// [`super::GpuEngine::gpu_bytes`]): the prefix sums' block totals (4 bytes per 1024 scanned
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn grid(dims: [u32; 3]) -> GridSpec {
        GridSpec {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims,
        }
    }

    #[test]
    fn slabs_tile_the_grid_with_overlap() {
        let p = SurfaceParams::default();
        let plan = plan_frame(grid([10, 10, 23]), &p, 1.5, 1 << 30, 1 << 30, Some(5)).unwrap();
        assert_eq!(plan.slabs.len(), 5);
        let mut next = 0;
        for s in &plan.slabs {
            assert_eq!(s.own_z0, next);
            next = s.own_z1;
            assert!(s.dens_z0 + 1 >= s.own_z0 && s.dens_z0 <= s.own_z0);
            assert!(s.dens_z0 + s.dens_layers >= (s.own_z1 + 2).min(23));
            assert!(s.dens_layers <= plan.dens_layers);
        }
        assert_eq!(next, 23);
        assert_eq!(plan.class_layers, 6);
    }

    #[test]
    fn binding_limit_forces_slabs() {
        let p = SurfaceParams::default();
        let layer_bytes = 12 * 100 * 100;
        let plan = plan_frame(
            grid([100, 100, 100]),
            &p,
            1.5,
            20 * layer_bytes,
            1 << 40,
            None,
        )
        .unwrap();
        assert!(plan.slabs.len() > 1);
        assert!(plan.slab_voxels() * 12 <= 20 * layer_bytes);
        let one = plan_frame(grid([100, 100, 100]), &p, 1.5, 1 << 40, 1 << 40, None).unwrap();
        assert_eq!(one.slabs.len(), 1);
        assert_eq!(one.slabs[0].dens_layers, 100);
        assert_eq!(one.brick_dims, [13, 13, 13]);
        assert_eq!(one.brick_count(), 13 * 13 * 13);
    }

    #[test]
    fn cells_cover_the_cutoff() {
        let p = SurfaceParams::default();
        let plan = plan_frame(grid([50, 40, 30]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
        assert!(plan.cell_size >= plan.max_cut);
        for a in 0..3 {
            assert!(plan.cell_dims[a] as f32 * plan.cell_size >= (plan.grid.dims[a] - 1) as f32);
        }
    }

    #[test]
    fn reached_bricks_are_counted_per_layer_from_the_slot_table() {
        let p = SurfaceParams::default();
        // 3 x 2 x 2 bricks.
        let plan = plan_frame(grid([20, 10, 12]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
        assert_eq!(plan.brick_dims, [3, 2, 2]);
        const UNREACHED: u32 = SlotTable::UNREACHED;
        // Layer 0 reaches bricks 1, 2 and 4; layer 1 brick 9 only.
        let reached = [1, 2, 4, 9];
        let mut slot = 0;
        let table: Vec<u32> = (0..12)
            .map(|b| {
                let t = if reached.contains(&b) {
                    slot
                } else {
                    slot | UNREACHED
                };
                slot += u32::from(reached.contains(&b));
                t
            })
            .collect();
        let counted = SlotTable::new(&plan, &table).reached();
        assert_eq!(counted.layers, vec![3, 1]);
        assert_eq!(counted.total(), 4);
        // One slab holds both layers; the slots hold the need with room, in blocks of 64.
        assert_eq!(counted.slab_need(&plan), 4);
        assert_eq!(settled_brick_slots(&plan, 4, 1 << 30), 64);
    }

    #[test]
    fn class_entries_move_to_brick_slots_only_when_that_takes_fewer() {
        let p = SurfaceParams::default();
        let plan = plan_frame(grid([64, 64, 64]), &p, 1.5, 1 << 30, 1 << 30, None).unwrap();
        let points = plan.class_points();
        let dense = ClassEntries::for_plan(&plan, None);
        assert_eq!((dense.entries, dense.sparse), (points, false));
        // 64 slots of 729 entries: far fewer than 64^3 points.
        let few = ClassEntries::for_plan(&plan, Some(64));
        assert_eq!(
            (few.entries, few.sparse),
            (64 * CLASS_ENTRIES_PER_SLOT, true)
        );
        // Every brick reached: the slots' entries (9^3 per 8^3 points) would take more.
        let all = ClassEntries::for_plan(&plan, Some(plan.brick_count()));
        assert_eq!((all.entries, all.sparse), (points, false));
        let limits = DeviceLimits::NVIDIA_80GB;
        let mesh = MeshCapacity::default();
        let sizes = BufferPlan::new(&plan, 100, false, mesh, Some(64), &limits);
        assert_eq!(sizes.classes.bytes, 64 * CLASS_ENTRIES_PER_SLOT * 4);
        assert_eq!(sizes.active.bytes, 64 * CLASS_ENTRIES_PER_SLOT * 8);
        assert_eq!(sizes.class_entries, few);
    }

    #[test]
    fn fresh_buffers_round_like_wgpu_and_start_at_16_bytes() {
        assert_eq!(Need::exact(0).fresh(), 16);
        assert_eq!(Need::exact(10).fresh(), 16);
        assert_eq!(Need::exact(18).fresh(), 20);
        let slack = Need::slack(800, 1 << 30);
        assert_eq!(
            (slack.bytes, slack.replace_with, slack.fresh()),
            (800, 900, 900)
        );
        // The slack never passes the largest binding, nor drops below the need.
        assert_eq!(Need::slack(800, 850).replace_with, 850);
        assert_eq!(Need::slack(800, 100).replace_with, 800);
    }

    #[test]
    fn mesh_grows_past_90_percent_and_then_holds() {
        let plan = plan_frame(
            grid([40, 40, 40]),
            &SurfaceParams::default(),
            1.5,
            1 << 30,
            1 << 30,
            None,
        )
        .unwrap();
        let first = first_mesh_want(&plan);
        let big = 1 << 40;
        // Counts well under the first guess keep it.
        let calm = MeshCapacity::settled(first, (first.0 / 2, first.1 / 2), 1.25, big);
        assert_eq!((calm.vertices, calm.triangles), first);
        // A triangle count past 90 % grows the triangles only, to hold the count with room.
        let t = first.1 * 95 / 100;
        let grown = MeshCapacity::settled(first, (10, t), 1.25, big);
        assert_eq!(grown.vertices, first.0);
        assert!(grown.triangles > t && grown.triangles as f64 > t as f64 / 0.9);
        assert!(grown_mesh_want(t, grown.triangles, 1.25).is_none());
        // Never past the largest binding.
        let small = 1 << 20;
        let clipped = MeshCapacity::settled(first, (u32::MAX as u64, u32::MAX as u64), 1.25, small);
        assert_eq!(clipped, MeshCapacity::largest(small));
        assert!(clipped.vertices * BYTES_PER_VERTEX <= small);
        assert!(clipped.triangles * BYTES_PER_TRIANGLE <= small);
    }

    #[test]
    fn buffer_plan_adds_up_per_atom_and_per_mesh_element() {
        let limits = DeviceLimits::NVIDIA_80GB;
        let plan = plan_frame(
            grid([60, 50, 40]),
            &SurfaceParams::default(),
            1.5,
            limits.max_binding(),
            limits.volume_budget(),
            None,
        )
        .unwrap();
        let mesh = MeshCapacity {
            vertices: 1000,
            triangles: 2000,
        };
        let m =
            |atoms, mesh| BufferPlan::new(&plan, atoms, true, mesh, None, &limits).fresh_memory();
        let (a, b) = (m(10_000, mesh), m(11_000, mesh));
        assert_eq!(b.atoms - a.atoms, 1000 * BYTES_PER_ATOM);
        assert_eq!(b.total() - a.total(), 1000 * BYTES_PER_ATOM);
        let more = MeshCapacity {
            vertices: 1100,
            triangles: 2100,
        };
        let c = m(10_000, more);
        let per_set = 100 * BYTES_PER_VERTEX + 100 * BYTES_PER_TRIANGLE;
        assert_eq!(
            c.mesh - a.mesh,
            super::super::resources::OUTPUT_SETS as u64 * per_set
        );
        // Without colours the colour volume stays at its initial 16 bytes.
        let grey = BufferPlan::new(&plan, 10_000, false, mesh, None, &limits).fresh_memory();
        assert_eq!(
            a.volumes - grey.volumes,
            with_slack(plan.slab_voxels() * 12, limits.max_binding()) - 16
        );
    }
}
