//! The 3D view inside the window: keeps the GPU copy of the shown surface and particles,
//! renders it offscreen with [`crate::render::Renderer`] into a texture that egui shows, and turns
//! mouse input into camera commands ([`viewport_ui`]). Screenshots and movie frames come from
//! the same scene through `render_to_rgba`.

use std::sync::Arc;
use std::time::Instant;

use super::state::{AppCore, Command};
use crate::render::{
    Camera, GpuScene, RenderError, RenderSettings, RenderTargets, Renderer, RgbaImage,
    atom_instances, render_to_rgba,
};

/// The window's GPU side: eframe's device, our renderer, the scene and the output texture.
pub struct GpuView {
    device: wgpu::Device,
    queue: wgpu::Queue,
    egui_renderer: Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
    renderer: Renderer,
    scene: GpuScene,
    targets: Option<RenderTargets>,
    texture: Option<egui::TextureId>,
    /// Time of the last render in ms (CPU side: encoding and submission).
    pub render_ms: f64,
}

impl GpuView {
    /// Destroys the window's wgpu device, as a driver reset would: the fault injected by
    /// [`crate::app::device_loss::LOSE_DEVICE_ENV`] to test the recovery path.
    pub fn destroy_device(&self) {
        self.device.destroy();
    }

    /// Uses eframe's wgpu device.
    pub fn new(state: &egui_wgpu::RenderState) -> GpuView {
        GpuView {
            device: state.device.clone(),
            queue: state.queue.clone(),
            egui_renderer: state.renderer.clone(),
            renderer: Renderer::new(&state.device),
            scene: GpuScene::new(),
            targets: None,
            texture: None,
            render_ms: 0.0,
        }
    }

    /// The device (to share with the GPU surface engine).
    pub fn device(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.device, &self.queue)
    }

    /// Uploads the shown surfaces and particles when they changed: one surface layer per
    /// visible surface representation (with its current opacity, so an opacity change redraws
    /// without recomputing), and the atoms of every atom representation in one instance list.
    pub fn sync(&mut self, core: &mut AppCore) {
        let Some(shown) = core.shown.as_mut() else {
            return;
        };
        if !shown.dirty {
            return;
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
    }

    /// Renders the scene at `size` pixels into the window texture and returns its egui id.
    pub fn render(
        &mut self,
        camera: &Camera,
        settings: &RenderSettings,
        size: [u32; 2],
    ) -> Option<egui::TextureId> {
        let t0 = Instant::now();
        let size = [size[0].max(1), size[1].max(1)];
        let resized = self.targets.as_ref().is_none_or(|t| t.size() != size);
        if resized {
            self.targets = Some(RenderTargets::new(&self.device, size));
        }
        let targets = self.targets.as_mut()?;
        self.renderer.render(
            &self.device,
            &self.queue,
            targets,
            &self.scene,
            camera,
            settings,
        );
        if resized {
            let mut r = self.egui_renderer.write();
            match self.texture {
                Some(id) => r.update_egui_texture_from_wgpu_texture(
                    &self.device,
                    targets.colour_view(),
                    wgpu::FilterMode::Linear,
                    id,
                ),
                None => {
                    self.texture = Some(r.register_native_texture(
                        &self.device,
                        targets.colour_view(),
                        wgpu::FilterMode::Linear,
                    ))
                }
            }
        }
        self.render_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.texture
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

    /// The egui id of the window texture, once rendered.
    pub fn texture_id(&self) -> Option<egui::TextureId> {
        self.texture
    }

    /// Size in pixels of the last window render.
    pub fn size(&self) -> Option<[u32; 2]> {
        self.targets.as_ref().map(|t| t.size())
    }
}

/// The viewport: shows `texture` filling the available space and maps mouse input to camera
/// commands (left drag orbits, right/middle or shift drag pans, scroll zooms, double-click fits).
/// Returns the commands and the size in pixels to render at.
pub fn viewport_ui(
    ui: &mut egui::Ui,
    texture: Option<egui::TextureId>,
) -> (Vec<Command>, [u32; 2]) {
    let mut out = Vec::new();
    let rect = ui.available_rect_before_wrap();
    let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
    if let Some(id) = texture {
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        ui.painter().image(id, rect, uv, egui::Color32::WHITE);
    }
    let h = rect.height().max(1.0);
    let delta = response.drag_delta();
    let shift = ui.input(|i| i.modifiers.shift);
    if response.dragged_by(egui::PointerButton::Primary) && !shift {
        out.push(Command::Orbit(delta.x / h * 3.0, delta.y / h * 3.0));
    } else if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
        || (response.dragged_by(egui::PointerButton::Primary) && shift)
    {
        out.push(Command::Pan(delta.x / h, delta.y / h));
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            out.push(Command::Zoom((-scroll * 0.002).exp()));
        }
    }
    if response.double_clicked() {
        out.push(Command::FitCamera);
    }
    let ppp = ui.ctx().pixels_per_point();
    let size = [
        (rect.width() * ppp).round() as u32,
        (rect.height() * ppp).round() as u32,
    ];
    (out, size)
}
