//! What the renderer draws, living in GPU buffers: the surface mesh (positions, normals, colours,
//! indices) or the GPU engine's own surface buffers (drawn in place, never read back), and the
//! atom/bond instances. Buffers are reused from frame to frame and grow only
//! when a frame needs more room, so playback does not reallocate.

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::surface::Mesh;

/// One atom drawn as a sphere impostor. Twin of `SphereIn` in shaders/render_scene.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SphereInstance {
    /// Centre in Å.
    pub centre: [f32; 3],
    /// Radius in Å.
    pub radius: f32,
    /// Linear RGB colour; the fourth value is unused.
    pub colour: [f32; 4],
}

/// One half-bond drawn as a cylinder. Twin of `CylinderIn` in shaders/render_scene.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CylinderInstance {
    /// Start point in Å.
    pub start: [f32; 3],
    /// Radius in Å.
    pub radius: f32,
    /// End point in Å; the fourth value is unused.
    pub end: [f32; 4],
    /// Linear RGB colour; the fourth value is unused.
    pub colour: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<SphereInstance>() == 32);
const _: () = assert!(std::mem::size_of::<CylinderInstance>() == 48);

/// A GPU buffer that keeps its allocation while the data fits.
#[derive(Debug)]
pub(crate) struct GrowBuffer {
    pub(crate) buffer: wgpu::Buffer,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    fn new(
        device: &wgpu::Device,
        label: &'static str,
        usage: wgpu::BufferUsages,
        data: &[u8],
    ) -> Self {
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: data,
            usage: usage | wgpu::BufferUsages::COPY_DST,
        });
        GrowBuffer {
            buffer,
            usage,
            label,
        }
    }

    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[u8]) {
        if (data.len() as u64) <= self.buffer.size() {
            if !data.is_empty() {
                queue.write_buffer(&self.buffer, 0, data);
            }
        } else {
            let size = (data.len() as u64 * 3 / 2).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
            self.buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: self.usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&self.buffer, 0, data);
        }
    }
}

fn write_or_create(
    slot: &mut Option<GrowBuffer>,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &'static str,
    usage: wgpu::BufferUsages,
    data: &[u8],
) {
    // wgpu buffers cannot be empty; keep at least one aligned word.
    let padded;
    let data = if data.len() < 16 {
        padded = {
            let mut v = data.to_vec();
            v.resize(16, 0);
            v
        };
        &padded[..]
    } else {
        data
    };
    match slot {
        Some(b) => b.write(device, queue, data),
        None => *slot = Some(GrowBuffer::new(device, label, usage, data)),
    }
}

/// The renderer's view of one scene, on the GPU.
#[derive(Debug, Default)]
pub struct GpuScene {
    pub(crate) positions: Option<GrowBuffer>,
    pub(crate) normals: Option<GrowBuffer>,
    pub(crate) colours: Option<GrowBuffer>,
    pub(crate) indices: Option<GrowBuffer>,
    pub(crate) index_count: u32,
    /// The GPU engine's surface, drawn instead of the uploaded mesh when set.
    pub(crate) gpu_surface: Option<crate::gpu::GpuSurface>,
    pub(crate) spheres: Option<GrowBuffer>,
    pub(crate) sphere_count: u32,
    pub(crate) cylinders: Option<GrowBuffer>,
    pub(crate) cylinder_count: u32,
    mesh_bounds: Option<(Vec3, Vec3)>,
    atom_bounds: Option<(Vec3, Vec3)>,
}

impl GpuScene {
    /// An empty scene.
    pub fn new() -> Self {
        GpuScene::default()
    }

    /// Uploads a surface mesh, replacing the previous one. A mesh without colours is drawn white.
    pub fn set_mesh(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, mesh: &Mesh) {
        let vertex = wgpu::BufferUsages::VERTEX;
        write_or_create(
            &mut self.positions,
            device,
            queue,
            "mesh positions",
            vertex,
            bytemuck::cast_slice(&mesh.positions),
        );
        write_or_create(
            &mut self.normals,
            device,
            queue,
            "mesh normals",
            vertex,
            bytemuck::cast_slice(&mesh.normals),
        );
        let white;
        let colours: &[[f32; 3]] = if mesh.colours.len() == mesh.positions.len() {
            &mesh.colours
        } else {
            white = vec![[1.0f32; 3]; mesh.positions.len()];
            &white
        };
        write_or_create(
            &mut self.colours,
            device,
            queue,
            "mesh colours",
            vertex,
            bytemuck::cast_slice(colours),
        );
        write_or_create(
            &mut self.indices,
            device,
            queue,
            "mesh indices",
            wgpu::BufferUsages::INDEX,
            bytemuck::cast_slice(&mesh.indices),
        );
        self.index_count = mesh.indices.len() as u32;
        self.mesh_bounds = mesh.bounds();
        self.gpu_surface = None;
    }

    /// Draws the GPU engine's surface in place of an uploaded mesh: its vertex and index buffers
    /// with `draw_indexed_indirect` on the arguments the engine wrote (no readback). `bounds`
    /// (Å) are those of the surface, for fitting the camera (e.g. the grid's box).
    pub fn set_gpu_surface(
        &mut self,
        surface: crate::gpu::GpuSurface,
        bounds: Option<(Vec3, Vec3)>,
    ) {
        self.gpu_surface = Some(surface);
        self.index_count = 0;
        self.mesh_bounds = bounds;
    }

    /// Removes the surface.
    pub fn clear_mesh(&mut self) {
        self.index_count = 0;
        self.mesh_bounds = None;
        self.gpu_surface = None;
    }

    /// True when there is a surface to draw (uploaded mesh or GPU buffers).
    pub fn has_surface(&self) -> bool {
        self.index_count > 0 || self.gpu_surface.is_some()
    }

    /// Uploads the atom spheres and bond cylinders, replacing the previous ones.
    pub fn set_atoms(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        spheres: &[SphereInstance],
        cylinders: &[CylinderInstance],
    ) {
        let inst = wgpu::BufferUsages::VERTEX;
        write_or_create(
            &mut self.spheres,
            device,
            queue,
            "atom spheres",
            inst,
            bytemuck::cast_slice(spheres),
        );
        write_or_create(
            &mut self.cylinders,
            device,
            queue,
            "bond cylinders",
            inst,
            bytemuck::cast_slice(cylinders),
        );
        self.sphere_count = spheres.len() as u32;
        self.cylinder_count = cylinders.len() as u32;
        self.atom_bounds = spheres.iter().fold(None, |acc, s| {
            let c = Vec3::from(s.centre);
            let r = Vec3::splat(s.radius);
            Some(match acc {
                None => (c - r, c + r),
                Some((lo, hi)) => (lo.min(c - r), hi.max(c + r)),
            })
        });
    }

    /// Number of surface triangles uploaded (for GPU buffers: the newest counters, if any).
    pub fn triangle_count(&self) -> u32 {
        match &self.gpu_surface {
            Some(g) => g.stats.map_or(0, |s| s.triangle_count),
            None => self.index_count / 3,
        }
    }

    /// Number of atom spheres uploaded.
    pub fn sphere_count(&self) -> u32 {
        self.sphere_count
    }

    /// Bounds (Å) of everything in the scene, for fitting the camera; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        match (self.mesh_bounds, self.atom_bounds) {
            (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1))),
            (a, b) => a.or(b),
        }
    }
}
