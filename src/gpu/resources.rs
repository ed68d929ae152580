//! The engine's GPU buffers: per-atom inputs and sorted copies, bin cells, per-slab volumes,
//! Marching Cubes scratch, counters and the output mesh. Each grows (never shrinks) to what a
//! frame needs; see [`super::plan`] for the byte counts per voxel and per atom.

use super::GpuError;
use super::kernel::{storage, uniform};
use super::plan::FramePlan;
use super::types::{DrawIndexedArgs, GpuCounters, GpuVertex, McTablesUniform};
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
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Grow {
        Grow {
            buffer: storage(device, label, 16, usage),
            label,
            usage,
        }
    }

    /// Ensures at least `bytes`; returns true when the buffer was replaced (contents lost).
    pub fn ensure(&mut self, device: &wgpu::Device, bytes: u64) -> bool {
        if self.buffer.size() >= bytes {
            return false;
        }
        self.buffer = storage(device, self.label, bytes, self.usage);
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
    /// Output vertices ([`GpuVertex`]).
    pub vertices: Grow,
    /// Output indices (u32, 3 per triangle).
    pub indices: Grow,
    /// Frame counters ([`GpuCounters`]).
    pub counters: wgpu::Buffer,
    /// Emit dispatch arguments.
    pub dispatch_args: wgpu::Buffer,
    /// Indirect draw arguments ([`DrawIndexedArgs`]).
    pub draw_args: wgpu::Buffer,
    /// Area/volume partial sums.
    pub partials: wgpu::Buffer,
    /// MC tables ([`super::types::McTablesUniform`], a uniform buffer).
    pub mc_tables: wgpu::Buffer,
}

impl Buffers {
    /// Empty buffers plus the Marching Cubes tables; the error says the tables did not fit
    /// their uniform (never for the shared tables; `types` tests it), the buffers exist anyway.
    pub fn new(device: &wgpu::Device) -> (Buffers, Option<GpuError>) {
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
            radii: Grow::new(device, "radii", U::COPY_DST),
            colours: Grow::new(device, "colours", U::COPY_DST),
            sorted_atoms: Grow::new(device, "sorted atoms", U::empty()),
            sorted_colours: Grow::new(device, "sorted colours", U::empty()),
            cell_start: Grow::new(device, "cell start", U::COPY_DST | U::COPY_SRC),
            cell_end: Grow::new(device, "cell end", U::empty()),
            density: Grow::new(device, "density", U::COPY_SRC),
            colour: Grow::new(device, "colour volume", U::COPY_SRC),
            classes: Grow::new(device, "classes", U::COPY_SRC),
            vertex_base: Grow::new(device, "vertex base", U::empty()),
            active: Grow::new(device, "active cells", U::empty()),
            block_sums: [
                Grow::new(device, "block vertices", U::empty()),
                Grow::new(device, "block triangles", U::empty()),
                Grow::new(device, "block active", U::empty()),
            ],
            vertices: Grow::new(device, "vertices", U::VERTEX | U::COPY_SRC),
            indices: Grow::new(device, "indices", U::INDEX | U::COPY_SRC),
            counters: storage(device, "counters", size_of::<GpuCounters>() as u64, copy),
            dispatch_args: storage(device, "emit dispatch args", 16, U::INDIRECT),
            draw_args: storage(
                device,
                "draw args",
                size_of::<DrawIndexedArgs>() as u64,
                U::INDIRECT | U::COPY_SRC,
            ),
            partials: storage(device, "area/volume partials", 256 * 8, U::empty()),
            mc_tables: uniform(device, "mc tables", &*mc_tables),
        };
        (buffers, error)
    }

    /// Grows the per-atom buffers for `atoms`; true when any was replaced.
    pub fn ensure_atoms(&mut self, device: &wgpu::Device, atoms: u64) -> bool {
        let mut replaced = false;
        replaced |= self.positions.ensure(device, atoms * 12);
        replaced |= self.radii.ensure(device, atoms * 4);
        replaced |= self.colours.ensure(device, atoms * 8);
        self.sorted_atoms.ensure(device, atoms * 16);
        self.sorted_colours.ensure(device, atoms * 8);
        replaced
    }

    /// Grows the cell and slab buffers for `plan` (colour volume only when `with_colour`).
    pub fn ensure_plan(&mut self, device: &wgpu::Device, plan: &FramePlan, with_colour: bool) {
        let cells = plan.cell_count();
        self.cell_start.ensure(device, cells * 4);
        self.cell_end.ensure(device, cells * 4);
        let voxels = plan.slab_voxels();
        self.density.ensure(device, voxels * 4);
        if with_colour {
            self.colour.ensure(device, voxels * 12);
        }
        let points = plan.class_points();
        self.classes.ensure(device, points * 4);
        self.vertex_base.ensure(device, points * 4);
        self.active.ensure(device, points * 8);
        for b in &mut self.block_sums {
            b.ensure(device, plan.class_blocks() * 4);
        }
    }

    /// Grows the mesh buffers to hold `vertices` and `triangles`.
    pub fn ensure_mesh(&mut self, device: &wgpu::Device, vertices: u64, triangles: u64) {
        self.vertices
            .ensure(device, vertices * size_of::<GpuVertex>() as u64);
        self.indices.ensure(device, triangles * 12);
    }

    /// Vertex and triangle capacity of the mesh buffers.
    pub fn mesh_capacity(&self) -> (u32, u32) {
        let v = self.vertices.size() / size_of::<GpuVertex>() as u64;
        let t = self.indices.size() / 12;
        (v.min(u32::MAX as u64) as u32, t.min(u32::MAX as u64) as u32)
    }

    /// Bytes of GPU memory held (all buffers).
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
            &self.vertices,
            &self.indices,
        ];
        let fixed = [
            &self.counters,
            &self.dispatch_args,
            &self.draw_args,
            &self.partials,
            &self.mc_tables,
        ];
        grows.iter().map(|g| g.size()).sum::<u64>()
            + self.block_sums.iter().map(|g| g.size()).sum::<u64>()
            + fixed.iter().map(|b| b.size()).sum::<u64>()
    }
}
