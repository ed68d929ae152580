//! The engine's GPU buffers: per-atom inputs and sorted copies, bin cells, per-slab volumes,
//! the sparse-brick flags and list, Marching Cubes scratch, counters, the per-slab uniforms and two sets of output mesh buffers
//! ([`OutputSet`]: frames alternate between them, so the surface the renderer draws is never
//! overwritten by the frame computed after it). Each grows
//! (never shrinks) to what a frame needs, the grid-sized ones with an eighth to spare so that a
//! trajectory whose box breathes a little does not replace them every frame. Every size comes
//! from [`super::plan::BufferPlan`], which also adds up the bytes without a device. A replaced
//! buffer invalidates the cached bind groups that bound it ([`super::kernel::Bound`]).

use super::GpuError;
use super::context::GpuContext;
use super::kernel::{storage, uniform};
use super::plan::{self, BufferPlan, Need};
use super::types::{DrawIndexedArgs, GpuCounters, McTablesUniform, SlabUniform};
use crate::surface::McTables;

/// A buffer that is replaced by a bigger one when a frame needs more.
#[derive(Debug)]
pub struct Grow {
    /// The current buffer.
    pub buffer: wgpu::Buffer,
    label: &'static str,
    usage: wgpu::BufferUsages,
}

impl Grow {
    /// A 16-byte buffer that grows on demand.
    pub fn new(ctx: &GpuContext, label: &'static str, usage: wgpu::BufferUsages) -> Grow {
        Grow {
            buffer: storage(ctx, label, 16, usage),
            label,
            usage,
        }
    }

    /// Ensures at least `bytes`; returns true when the buffer was replaced (contents lost).
    pub fn ensure(&mut self, ctx: &GpuContext, bytes: u64) -> bool {
        self.ensure_need(ctx, Need::exact(bytes))
    }

    /// Like [`Grow::ensure`], but a replacement gets an eighth more than `bytes` (within the
    /// device's largest binding), so sizes that vary a little from frame to frame settle.
    pub fn ensure_slack(&mut self, ctx: &GpuContext, bytes: u64) -> bool {
        self.ensure_need(ctx, Need::slack(bytes, ctx.max_binding()))
    }

    /// Replaces the buffer with one of `need.replace_with` bytes (as [`plan::storage_bytes`]
    /// rounds it) when it holds fewer than `need.bytes`; true when it was replaced.
    pub fn ensure_need(&mut self, ctx: &GpuContext, need: Need) -> bool {
        if self.buffer.size() >= need.bytes {
            return false;
        }
        let size = plan::storage_bytes(need.replace_with);
        self.buffer = storage(ctx, self.label, size, self.usage);
        true
    }

    /// Size in bytes.
    pub fn size(&self) -> u64 {
        self.buffer.size()
    }
}

/// All buffers of one engine.
#[derive(Debug)]
pub struct Buffers {
    /// Positions in Å, 3 f32 per atom.
    pub positions: Grow,
    /// Radii in Å.
    pub radii: Grow,
    /// Packed colours (see [`super::types::pack_colour`]).
    pub colours: Grow,
    /// Sorted atoms (x, y, z, alpha).
    pub sorted_atoms: Grow,
    /// Sorted packed colours.
    pub sorted_colours: Grow,
    /// First slot per cell.
    pub cell_start: Grow,
    /// One past the last slot per cell.
    pub cell_end: Grow,
    /// Slab density.
    pub density: Grow,
    /// Slab colour (3 f32 per voxel).
    pub colour: Grow,
    /// Class words.
    pub classes: Grow,
    /// Vertex base per point.
    pub vertex_base: Grow,
    /// Active cells (point, first triangle).
    pub active: Grow,
    /// Block sums of vertices, triangles, active cells.
    pub block_sums: [Grow; 3],
    /// Per sparse brick: 1 when some atom reaches it (u32).
    pub brick_flags: Grow,
    /// Per sparse brick: the flag, scanned into list slots (u32).
    pub brick_scan: Grow,
    /// Count of reached bricks, then their ids (u32; `shaders/bricks.wgsl`).
    pub active_bricks: Grow,
    /// Indirect dispatch arguments of the sparse density pass (3 u32) and the reached-brick
    /// count (word 3).
    pub brick_args: wgpu::Buffer,
    /// The two output sets; frame after frame the engine writes the other one.
    pub outputs: [OutputSet; OUTPUT_SETS],
    /// Frame counters ([`GpuCounters`]).
    pub counters: wgpu::Buffer,
    /// Emit dispatch arguments.
    pub dispatch_args: wgpu::Buffer,
    /// Area/volume partial sums.
    pub partials: wgpu::Buffer,
    /// MC tables ([`super::types::McTablesUniform`], a uniform buffer).
    pub mc_tables: wgpu::Buffer,
    /// One [`SlabUniform`] per slab, bound at dynamic offsets.
    pub slab_uniforms: SlabUniforms,
}

/// How many output sets the engine alternates between (double buffering).
pub const OUTPUT_SETS: usize = 2;

/// What the renderer draws from: one frame's mesh and its indirect draw arguments. The engine
/// keeps [`OUTPUT_SETS`] of them, grown together, and writes a different one each frame.
#[derive(Debug)]
pub struct OutputSet {
    /// Output vertices ([`super::types::GpuVertex`]).
    pub vertices: Grow,
    /// Output indices (u32, 3 per triangle).
    pub indices: Grow,
    /// Indirect draw arguments ([`DrawIndexedArgs`]).
    pub draw_args: wgpu::Buffer,
}

impl OutputSet {
    fn new(ctx: &GpuContext) -> OutputSet {
        use wgpu::BufferUsages as U;
        OutputSet {
            vertices: Grow::new(ctx, "vertices", U::VERTEX | U::COPY_SRC),
            indices: Grow::new(ctx, "indices", U::INDEX | U::COPY_SRC),
            draw_args: storage(
                ctx,
                "draw args",
                size_of::<DrawIndexedArgs>() as u64,
                U::INDIRECT | U::COPY_SRC,
            ),
        }
    }

    /// Bytes of GPU memory held.
    fn bytes(&self) -> u64 {
        self.vertices.size() + self.indices.size() + self.draw_args.size()
    }
}

/// The [`SlabUniform`]s of a frame in one uniform buffer, one per `stride` bytes (the device's
/// uniform offset alignment); the slab stages bind it once at a dynamic offset per slab.
#[derive(Debug)]
pub struct SlabUniforms {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    stride: u64,
    bytes: Vec<u8>,
}

impl SlabUniforms {
    fn new(ctx: &GpuContext) -> SlabUniforms {
        let stride = ctx.device_limits().slab_uniform_stride();
        SlabUniforms {
            buffer: super::kernel::uniform_buffer(ctx, "slab uniforms", stride),
            stride,
            bytes: Vec::new(),
        }
    }

    /// Queues `slabs` for the next submit, growing the buffer (a quarter to spare) when needed.
    pub fn write(&mut self, ctx: &GpuContext, slabs: &[SlabUniform]) {
        let need = self.stride * slabs.len().max(1) as u64;
        if self.buffer.size() < need {
            let size = plan::slab_uniform_replacement(slabs.len() as u64, self.stride);
            self.buffer = super::kernel::uniform_buffer(ctx, "slab uniforms", size);
        }
        self.bytes.clear();
        self.bytes.resize(need as usize, 0);
        for (i, s) in slabs.iter().enumerate() {
            let at = i * self.stride as usize;
            self.bytes[at..at + size_of::<SlabUniform>()].copy_from_slice(bytemuck::bytes_of(s));
        }
        ctx.queue.write_buffer(&self.buffer, 0, &self.bytes);
    }

    /// The dynamic offset of slab `i`.
    pub fn offset(&self, i: usize) -> u32 {
        (i as u64 * self.stride) as u32
    }
}

impl Buffers {
    /// Empty buffers plus the Marching Cubes tables; the error says the tables did not fit
    /// their uniform (never for the shared tables; `types` tests it), the buffers exist anyway.
    pub fn new(ctx: &GpuContext) -> (Buffers, Option<GpuError>) {
        let device = ctx;
        use wgpu::BufferUsages as U;
        let (mc_tables, error) = match McTablesUniform::new(McTables::get()) {
            Some(t) => (t, None),
            None => (
                bytemuck::zeroed_box(),
                Some(GpuError::TooLarge {
                    what: "the Marching Cubes tables",
                    needed: 0,
                    limit: 16 * super::types::MC_TABLE_ROWS as u64,
                }),
            ),
        };
        let copy = U::COPY_DST | U::COPY_SRC;
        let buffers = Buffers {
            positions: Grow::new(device, "positions", U::COPY_DST),
            radii: Grow::new(device, "radii", U::COPY_DST | U::COPY_SRC),
            colours: Grow::new(device, "colours", U::COPY_DST),
            sorted_atoms: Grow::new(device, "sorted atoms", U::empty()),
            sorted_colours: Grow::new(device, "sorted colours", U::empty()),
            cell_start: Grow::new(device, "cell start", U::COPY_DST | U::COPY_SRC),
            cell_end: Grow::new(device, "cell end", U::empty()),
            // Dense per-slab volumes, or on sparse bricks the brick slot table and the reached
            // bricks' samples (`shaders/bricks.wgsl`, `shaders/density.wgsl`).
            density: Grow::new(device, "density", copy),
            colour: Grow::new(device, "colour volume", copy),
            classes: Grow::new(device, "classes", U::COPY_SRC),
            vertex_base: Grow::new(device, "vertex base", U::empty()),
            active: Grow::new(device, "active cells", U::empty()),
            block_sums: [
                Grow::new(device, "block vertices", U::empty()),
                Grow::new(device, "block triangles", U::empty()),
                Grow::new(device, "block active", U::empty()),
            ],
            brick_flags: Grow::new(device, "brick flags", U::empty()),
            brick_scan: Grow::new(device, "brick scan", U::empty()),
            active_bricks: Grow::new(device, "active bricks", U::empty()),
            brick_args: storage(
                device,
                "brick dispatch args",
                plan::DISPATCH_ARGS_BYTES,
                U::INDIRECT | U::COPY_SRC,
            ),
            outputs: [OutputSet::new(device), OutputSet::new(device)],
            counters: storage(device, "counters", size_of::<GpuCounters>() as u64, copy),
            dispatch_args: storage(
                device,
                "emit dispatch args",
                plan::DISPATCH_ARGS_BYTES,
                U::INDIRECT,
            ),
            partials: storage(
                device,
                "area/volume partials",
                plan::PARTIALS_BYTES,
                U::empty(),
            ),
            mc_tables: uniform(device, "mc tables", &*mc_tables),
            slab_uniforms: SlabUniforms::new(ctx),
        };
        (buffers, error)
    }

    /// Grows the per-atom buffers to `sizes`; true when any input buffer was replaced.
    pub fn ensure_atoms(&mut self, device: &GpuContext, sizes: &BufferPlan) -> bool {
        let mut replaced = false;
        replaced |= self.positions.ensure_need(device, sizes.positions);
        replaced |= self.radii.ensure_need(device, sizes.radii);
        replaced |= self.colours.ensure_need(device, sizes.colours);
        self.sorted_atoms.ensure_need(device, sizes.sorted_atoms);
        self.sorted_colours
            .ensure_need(device, sizes.sorted_colours);
        replaced
    }

    /// Grows the cell, slab and brick buffers to `sizes` (the colour volume needs nothing
    /// without colours); true when the density or colour buffer was replaced (its samples lost).
    pub fn ensure_plan(&mut self, device: &GpuContext, sizes: &BufferPlan) -> bool {
        self.cell_start.ensure_need(device, sizes.cell_start);
        self.cell_end.ensure_need(device, sizes.cell_end);
        let mut volumes = self.density.ensure_need(device, sizes.density);
        volumes |= self.colour.ensure_need(device, sizes.colour);
        self.classes.ensure_need(device, sizes.classes);
        self.vertex_base.ensure_need(device, sizes.vertex_base);
        self.active.ensure_need(device, sizes.active);
        for b in &mut self.block_sums {
            b.ensure_need(device, sizes.block_sums);
        }
        self.brick_flags.ensure_need(device, sizes.brick_flags);
        self.brick_scan.ensure_need(device, sizes.brick_scan);
        self.active_bricks.ensure_need(device, sizes.active_bricks);
        volumes
    }

    /// Grows the mesh buffers of every output set to `sizes` (all sets together, so the sets
    /// always have the same capacity).
    pub fn ensure_mesh(&mut self, device: &GpuContext, sizes: &BufferPlan) {
        for set in &mut self.outputs {
            set.vertices.ensure_need(device, sizes.vertices);
            set.indices.ensure_need(device, sizes.indices);
        }
    }

    /// Vertex and triangle capacity of the mesh buffers (the same in every output set).
    pub fn mesh_capacity(&self) -> (u32, u32) {
        let set = &self.outputs[0];
        let v = set.vertices.size() / plan::BYTES_PER_VERTEX;
        let t = set.indices.size() / plan::BYTES_PER_TRIANGLE;
        (v.min(u32::MAX as u64) as u32, t.min(u32::MAX as u64) as u32)
    }

    /// Bytes of GPU memory held (all buffers, both output sets).
    pub fn bytes(&self) -> u64 {
        let grows = [
            &self.positions,
            &self.radii,
            &self.colours,
            &self.sorted_atoms,
            &self.sorted_colours,
            &self.cell_start,
            &self.cell_end,
            &self.density,
            &self.colour,
            &self.classes,
            &self.vertex_base,
            &self.active,
            &self.brick_flags,
            &self.brick_scan,
            &self.active_bricks,
        ];
        let fixed = [
            &self.counters,
            &self.brick_args,
            &self.dispatch_args,
            &self.partials,
            &self.mc_tables,
            &self.slab_uniforms.buffer,
        ];
        grows.iter().map(|g| g.size()).sum::<u64>()
            + self.block_sums.iter().map(|g| g.size()).sum::<u64>()
            + fixed.iter().map(|b| b.size()).sum::<u64>()
            + self.outputs.iter().map(OutputSet::bytes).sum::<u64>()
    }
}
