//! The 3D view inside the window: the viewer's renderer ([`ViewRenderer`]: the GPU copy of the
//! shown surface and particles, drawn offscreen) shown as a texture through egui, and mouse
//! input turned into camera commands ([`viewport_ui`]). Screenshots and movie frames come from
//! the same scene through `render_to_rgba`.

use std::sync::Arc;
use std::time::Instant;

use super::state::{AppCore, Command};
use super::view_renderer::ViewRenderer;
use crate::render::{Camera, RenderError, RenderSettings, RgbaImage};

/// The window's GPU side: the viewer's renderer ([`ViewRenderer`]) on eframe's device, and
/// the egui texture its picture is shown through.
pub struct GpuView {
    view: ViewRenderer,
    egui_renderer: Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
    texture: Option<egui::TextureId>,
    /// Time of the last render in ms (CPU side: encoding and submission).
    pub render_ms: f64,
    /// True while the still view has more progressive samples to draw: the window repaints.
    pub sampling: bool,
}

impl GpuView {
    /// Destroys the window's wgpu device, as a driver reset would: the fault injected by
    /// [`crate::app::device_loss::LOSE_DEVICE_ENV`] to test the recovery path.
    pub fn destroy_device(&self) {
        self.view.device().0.destroy();
    }

    /// Uses eframe's wgpu device.
    pub fn new(state: &egui_wgpu::RenderState) -> GpuView {
        GpuView {
            view: ViewRenderer::new(state.device.clone(), state.queue.clone()),
            egui_renderer: state.renderer.clone(),
            texture: None,
            render_ms: 0.0,
            sampling: false,
        }
    }

    /// The device (to share with the GPU surface engine).
    pub fn device(&self) -> (&wgpu::Device, &wgpu::Queue) {
        self.view.device()
    }

    /// Uploads the shown surfaces and particles when they changed ([`ViewRenderer::sync`]).
    pub fn sync(&mut self, core: &mut AppCore) {
        self.view.sync(core);
    }

    /// Renders the scene at `size` pixels into the window texture and returns its egui id.
    pub fn render(
        &mut self,
        camera: &Camera,
        settings: &RenderSettings,
        size: [u32; 2],
    ) -> Option<egui::TextureId> {
        let t0 = Instant::now();
        let drawn = self.view.draw(camera, settings, size);
        self.sampling = drawn.more;
        let (_, shown) = self.view.shown()?;
        if drawn.new_texture || self.texture.is_none() {
            let device = self.view.device().0;
            let mut r = self.egui_renderer.write();
            match self.texture {
                Some(id) => r.update_egui_texture_from_wgpu_texture(
                    device,
                    shown,
                    wgpu::FilterMode::Linear,
                    id,
                ),
                None => {
                    self.texture =
                        Some(r.register_native_texture(device, shown, wgpu::FilterMode::Linear))
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
        self.view.snapshot(camera, settings, size)
    }

    /// The egui id of the window texture, once rendered.
    pub fn texture_id(&self) -> Option<egui::TextureId> {
        self.texture
    }

    /// Size in pixels of the last window render.
    pub fn size(&self) -> Option<[u32; 2]> {
        self.view.size()
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
