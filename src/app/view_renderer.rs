//! What the viewer draws, without a window: the device, our renderer, the GPU copy of the shown
//! surfaces and particles ([`GpuScene`]) and the offscreen targets the picture lands in. The
//! window ([`super::viewport::GpuView`]) shows its colour texture through egui; `mdsurf bench
//! --viewer` ([`super::offscreen`]) draws through it with no window at all, so both run the same
//! code from a computed frame to pixels.

use crate::render::{
    Camera, GpuScene, RenderError, RenderSettings, Renderer, RgbaImage, StillDraw, StillView,
    render_to_rgba,
};

use super::state::AppCore;

/// The renderer side of the viewer on one device.
pub struct ViewRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: Renderer,
    scene: GpuScene,
    /// The picture, with progressive samples while the view is still.
    view: StillView,
    /// True when the scene changed since the last draw.
    scene_changed: bool,
}

impl ViewRenderer {
    /// A renderer on `device` (shared with the GPU surface engine), with nothing to draw yet.
    pub fn new(device: wgpu::Device, queue: wgpu::Queue) -> ViewRenderer {
        ViewRenderer {
            renderer: Renderer::new(&device),
            device,
            queue,
            scene: GpuScene::new(),
            view: StillView::default(),
            scene_changed: true,
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
        self.scene_changed = true;
        true
    }

    /// Draws the scene at `size` pixels (at least 1 x 1) into the offscreen targets, made anew
    /// when the size changed: the first sample of a view, then, while camera, look, size and
    /// scene stay the same, one more of the look's progressive samples per call
    /// ([`StillView`]). Submits and does not wait.
    pub fn draw(
        &mut self,
        camera: &Camera,
        settings: &RenderSettings,
        size: [u32; 2],
    ) -> StillDraw {
        let changed = std::mem::take(&mut self.scene_changed);
        self.view.draw(
            &self.device,
            &self.queue,
            &self.renderer,
            &self.scene,
            camera,
            settings,
            size,
            changed,
        )
    }

    /// Makes the next [`ViewRenderer::draw`] draw its first sample again even if nothing
    /// changed (a still view is otherwise not drawn again once its samples are in): for timing
    /// draws.
    pub fn redraw(&mut self) {
        self.scene_changed = true;
    }

    /// The picture to show (texture and view), once drawn.
    pub fn shown(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        self.view.shown()
    }

    /// Size in pixels of the last draw.
    pub fn size(&self) -> Option<[u32; 2]> {
        self.view.targets().map(|t| t.size())
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
