//! What the viewer draws, without a window: the device, our renderer, the GPU copy of the shown
//! surfaces and particles ([`GpuScene`]) and the offscreen targets the picture lands in. The
//! window ([`super::viewport::GpuView`]) shows its colour texture through egui; `mdsurf bench
//! --viewer` ([`super::offscreen`]) draws through it with no window at all, so both run the same
//! code from a computed frame to pixels.

use crate::render::{
    Camera, GpuScene, RenderError, RenderSettings, RenderTargets, Renderer, RgbaImage,
    render_to_rgba,
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
        // Each layer with the representation as it is now (its opacity may have changed
        // since); hidden ones are not drawn.
        let now = |id: u64| {
            core.rep_ids
                .iter()
                .position(|&i| i == id)
                .and_then(|i| core.reps.get(i))
                .filter(|r| r.visible)
        };
        let layers = shown
            .computed
            .layers
            .iter()
            .filter_map(|l| Some((l.as_ref(), now(l.id)?)));
        self.scene
            .show_layers(&self.device, &self.queue, layers, &core.render);
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
