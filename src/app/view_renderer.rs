//! What the viewer draws, without a window: the device, our renderer, the GPU copy of the shown
//! surfaces and particles ([`GpuScene`]) and the offscreen targets the picture lands in. The
//! window ([`super::viewport::GpuView`]) shows its colour texture through egui; `mdsurf bench
//! --viewer` ([`super::offscreen`]) draws through it with no window at all, so both run the same
//! code from a computed frame to pixels.

use crate::render::{
    Camera, GpuScene, RenderError, RenderSettings, RenderTargets, Renderer, RgbaImage,
    atom_instances, render_to_rgba,
};

use super::state::AppCore;

/// The renderer side of the viewer on one device.
pub struct ViewRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: Renderer,
    scene: GpuScene,
    targets: Option<RenderTargets>,
}

impl ViewRenderer {
    /// A renderer on `device` (shared with the GPU surface engine), with nothing to draw yet.
    pub fn new(device: wgpu::Device, queue: wgpu::Queue) -> ViewRenderer {
        ViewRenderer {
            renderer: Renderer::new(&device),
            device,
            queue,
            scene: GpuScene::new(),
            targets: None,
        }
    }

    /// The device and its queue.
    pub fn device(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.device, &self.queue)
    }

    /// Uploads the shown surfaces and particles when they changed: one surface layer per
    /// visible surface representation (with its current opacity, so an opacity change redraws
    /// without recomputing), and the atoms of every atom representation in one instance list.
    /// Returns true when the scene changed.
    pub fn sync(&mut self, core: &mut AppCore) -> bool {
        let Some(shown) = core.shown.as_mut() else {
            return false;
        };
        if !shown.dirty {
            return false;
        }
        shown.dirty = false;
        let c = &shown.computed;
        let mut k = 0;
        let mut spheres = Vec::new();
        let mut cylinders = Vec::new();
        for l in &c.layers {
            // The representation as it is now (its opacity may have changed since).
            let now = core
                .rep_ids
                .iter()
                .position(|&id| id == l.id)
                .and_then(|i| core.reps.get(i));
            let Some(rep) = now.filter(|r| r.visible) else {
                continue;
            };
            if let Some(style) = rep.style.atom_style() {
                let look = RenderSettings {
                    atom_style: style,
                    ..core.render
                };
                let p = &l.particles;
                let (s, cyl) =
                    atom_instances(&p.positions, &p.radii, Some(&p.colours), &p.bonds, &look);
                spheres.extend(s);
                cylinders.extend(cyl);
                continue;
            }
            match &l.gpu_surface {
                Some(g) => {
                    let grid = &l.output.grid;
                    let far = glam::UVec3::from(grid.dims).saturating_sub(glam::UVec3::ONE);
                    let hi = grid.origin + far.as_vec3() * grid.spacing;
                    self.scene
                        .set_layer_gpu_surface(k, g.clone(), Some((grid.origin, hi)));
                }
                None => self
                    .scene
                    .set_layer_mesh(k, &self.device, &self.queue, &l.output.mesh),
            }
            self.scene.layer_mut(k).opacity = Some(rep.opacity);
            k += 1;
        }
        self.scene.set_surface_count(k);
        self.scene
            .set_atoms(&self.device, &self.queue, &spheres, &cylinders);
        true
    }

    /// Draws the scene at `size` pixels (at least 1 x 1) into the offscreen targets, made anew
    /// when the size changed; returns true when they were. Submits and does not wait.
    pub fn draw(&mut self, camera: &Camera, settings: &RenderSettings, size: [u32; 2]) -> bool {
        let size = [size[0].max(1), size[1].max(1)];
        let resized = self.targets.as_ref().is_none_or(|t| t.size() != size);
        if resized {
            self.targets = Some(RenderTargets::new(&self.device, size));
        }
        if let Some(targets) = self.targets.as_mut() {
            self.renderer.render(
                &self.device,
                &self.queue,
                targets,
                &self.scene,
                camera,
                settings,
            );
        }
        resized
    }

    /// The targets of the last draw.
    pub fn targets(&self) -> Option<&RenderTargets> {
        self.targets.as_ref()
    }

    /// Renders the current scene offscreen at `size` and reads it back (screenshots, movies).
    pub fn snapshot(
        &self,
        camera: &Camera,
        settings: &RenderSettings,
        size: [u32; 2],
    ) -> Result<RgbaImage, RenderError> {
        render_to_rgba(
            &self.device,
            &self.queue,
            &self.renderer,
            &self.scene,
            camera,
            settings,
            size,
        )
    }
}
