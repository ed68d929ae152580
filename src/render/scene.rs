//! What the renderer draws, living in GPU buffers: the surface meshes, one layer per surface
//! representation (positions, normals, colours, indices, or the GPU engine's own surface buffers,
//! drawn in place and never read back), and the atom/bond instances. Buffers are reused from frame to frame and grow only
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

/// One surface of the scene: an uploaded mesh or the GPU engine's buffers, with its own look.
#[derive(Debug, Default)]
pub struct SurfaceLayer {
    pub(crate) positions: Option<GrowBuffer>,
    pub(crate) normals: Option<GrowBuffer>,
    pub(crate) colours: Option<GrowBuffer>,
    pub(crate) indices: Option<GrowBuffer>,
    pub(crate) index_count: u32,
    /// The GPU engine's surface, drawn instead of the uploaded mesh when set.
    pub(crate) gpu_surface: Option<crate::gpu::GpuSurface>,
    /// Box around the surface in Å (for the GPU engine's, its grid), when known.
    pub(crate) bounds: Option<(Vec3, Vec3)>,
    /// True when the surface is closed, counter-clockwise seen from outside (the GPU engine's,
    /// or an uploaded mesh said to be: not the periodic engine's, open at the cell faces), so
    /// that its back faces may be culled where no plane cuts it.
    pub closed: bool,
    /// Opacity 0..1 of this surface; `None` takes [`crate::render::RenderSettings`]'s.
    pub opacity: Option<f32>,
    /// A single linear RGB colour for this surface; `None` takes the settings' choice.
    pub colour: Option<[f32; 3]>,
}

impl SurfaceLayer {
    /// True when there is something to draw (uploaded mesh or GPU buffers).
    pub fn has_surface(&self) -> bool {
        self.index_count > 0 || self.gpu_surface.is_some()
    }

    /// The opacity this layer is drawn with under `settings`.
    pub fn effective_opacity(&self, settings: &crate::render::RenderSettings) -> f32 {
        self.opacity
            .unwrap_or(settings.surface_opacity)
            .clamp(0.0, 1.0)
    }

    fn set_mesh(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, mesh: &Mesh) {
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
        self.bounds = mesh.bounds();
        self.gpu_surface = None;
        self.closed = false;
    }

    fn clear(&mut self) {
        self.index_count = 0;
        self.bounds = None;
        self.gpu_surface = None;
    }

    fn triangle_count(&self) -> u32 {
        match &self.gpu_surface {
            Some(g) => g.stats.map_or(0, |s| s.triangle_count),
            None => self.index_count / 3,
        }
    }
}

/// The renderer's view of one scene, on the GPU: any number of surfaces (one per surface
/// representation, each with its own opacity) and one set of atom and bond instances (every
/// atom representation's, concatenated).
#[derive(Debug, Default)]
pub struct GpuScene {
    pub(crate) surfaces: Vec<SurfaceLayer>,
    pub(crate) spheres: Option<GrowBuffer>,
    pub(crate) sphere_count: u32,
    pub(crate) cylinders: Option<GrowBuffer>,
    pub(crate) cylinder_count: u32,
    atom_bounds: Option<(Vec3, Vec3)>,
}

impl GpuScene {
    /// An empty scene.
    pub fn new() -> Self {
        GpuScene::default()
    }

    /// Keeps `count` surface layers (new ones empty; extra ones dropped).
    pub fn set_surface_count(&mut self, count: usize) {
        self.surfaces.resize_with(count, SurfaceLayer::default);
    }

    /// Number of surface layers.
    pub fn surface_count(&self) -> usize {
        self.surfaces.len()
    }

    /// Surface layer `k` (created, with the layers before it, when missing).
    pub fn layer_mut(&mut self, k: usize) -> &mut SurfaceLayer {
        if self.surfaces.len() <= k {
            self.set_surface_count(k + 1);
        }
        &mut self.surfaces[k]
    }

    /// Uploads the mesh of surface layer `k`. A mesh without colours is drawn white.
    pub fn set_layer_mesh(
        &mut self,
        k: usize,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &Mesh,
    ) {
        self.layer_mut(k).set_mesh(device, queue, mesh);
    }

    /// Draws the GPU engine's surface as layer `k`: its vertex and index buffers with
    /// `draw_indexed_indirect` on the arguments the engine wrote (no readback). `bounds` (Å) are
    /// those of the surface, for fitting the camera (e.g. the grid's box).
    pub fn set_layer_gpu_surface(
        &mut self,
        k: usize,
        surface: crate::gpu::GpuSurface,
        bounds: Option<(Vec3, Vec3)>,
    ) {
        let layer = self.layer_mut(k);
        layer.gpu_surface = Some(surface);
        layer.index_count = 0;
        layer.bounds = bounds;
        layer.closed = true;
    }

    /// Removes the surface of layer `k` (keeping its buffers for reuse).
    pub fn clear_layer(&mut self, k: usize) {
        if let Some(layer) = self.surfaces.get_mut(k) {
            layer.clear();
        }
    }

    /// Uploads a single surface mesh, replacing every surface. A mesh without colours is
    /// drawn white; its look follows the render settings.
    pub fn set_mesh(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, mesh: &Mesh) {
        self.set_surface_count(1);
        let layer = &mut self.surfaces[0];
        layer.opacity = None;
        layer.colour = None;
        layer.set_mesh(device, queue, mesh);
    }

    /// Draws the GPU engine's surface as the only surface (see
    /// [`GpuScene::set_layer_gpu_surface`]).
    pub fn set_gpu_surface(
        &mut self,
        surface: crate::gpu::GpuSurface,
        bounds: Option<(Vec3, Vec3)>,
    ) {
        self.set_surface_count(1);
        self.surfaces[0].opacity = None;
        self.surfaces[0].colour = None;
        self.set_layer_gpu_surface(0, surface, bounds);
    }

    /// Removes every surface.
    pub fn clear_mesh(&mut self) {
        self.surfaces.iter_mut().for_each(SurfaceLayer::clear);
    }

    /// True when there is a surface to draw (uploaded mesh or GPU buffers).
    pub fn has_surface(&self) -> bool {
        self.surfaces.iter().any(SurfaceLayer::has_surface)
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
        // Each sphere and both ends of each cylinder, widened by their radii.
        let balls = spheres.iter().map(|s| (Vec3::from(s.centre), s.radius));
        let ends = cylinders.iter().flat_map(|c| {
            let end = Vec3::new(c.end[0], c.end[1], c.end[2]);
            [(Vec3::from(c.start), c.radius), (end, c.radius)]
        });
        self.atom_bounds = balls.chain(ends).fold(None, |acc, (c, r)| {
            let r = Vec3::splat(r);
            Some(match acc {
                None => (c - r, c + r),
                Some((lo, hi)) => (lo.min(c - r), hi.max(c + r)),
            })
        });
    }

    /// Number of surface triangles uploaded, all layers together (for GPU buffers: the newest
    /// counters, if any).
    pub fn triangle_count(&self) -> u32 {
        self.surfaces.iter().map(SurfaceLayer::triangle_count).sum()
    }

    /// Number of atom spheres uploaded.
    pub fn sphere_count(&self) -> u32 {
        self.sphere_count
    }

    /// Bounds (Å) of everything drawn, for clipping the full-screen passes: `None` when a
    /// surface's bounds are not known (draw everywhere).
    pub(crate) fn drawn_bounds(&self) -> Option<(Vec3, Vec3)> {
        let surfaces = self.surfaces.iter().filter(|l| l.has_surface());
        if surfaces.clone().any(|l| l.bounds.is_none()) {
            return None;
        }
        surfaces
            .filter_map(|l| l.bounds)
            .chain(self.atom_bounds)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }

    /// Bounds (Å) of everything in the scene, for fitting the camera; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.surfaces
            .iter()
            .filter_map(|l| l.bounds)
            .chain(self.atom_bounds)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    }
}
