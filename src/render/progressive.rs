//! Progressive samples on the GPU: the running mean of several draws of one view, each with its
//! sub-pixel offset and turned ambient-occlusion and shadow patterns
//! ([`RenderSettings::sample`]), which smooths their grain and anti-aliases edges.
//!
//! - [`SampleMean`] holds the mean (linear colour, half floats) and the image it is shown in;
//!   screenshots, movies and `render` draw all of a look's samples into one and read it back
//!   once ([`super::render_to_rgba`]).
//! - [`StillView`] is the window's picture: one sample per repaint while the view stays still
//!   (same camera, look, size and scene), so the window converges to the picture a screenshot
//!   of the same view gives, and starts again from one sample on any change.

use super::camera::Camera;
use super::renderer::Renderer;
use super::scene::GpuScene;
use super::settings::RenderSettings;
use super::targets::{COLOUR_FORMAT, MEAN_FORMAT, RenderTargets, texture};

/// The running mean of progressive samples at one size, and the image it is shown in.
#[derive(Debug)]
pub struct SampleMean {
    size: [u32; 2],
    mean: wgpu::TextureView,
    shown: wgpu::Texture,
    shown_view: wgpu::TextureView,
}

impl SampleMean {
    /// An empty mean of `size` pixels (the size of the targets its samples are drawn in).
    pub fn new(device: &wgpu::Device, size: [u32; 2]) -> SampleMean {
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let sampled = attach | wgpu::TextureUsages::TEXTURE_BINDING;
        let (_, mean) = texture(device, "sample mean", size, MEAN_FORMAT, sampled);
        let (shown, shown_view) = texture(
            device,
            "sample mean shown",
            size,
            COLOUR_FORMAT,
            sampled | wgpu::TextureUsages::COPY_SRC,
        );
        SampleMean {
            size,
            mean,
            shown,
            shown_view,
        }
    }

    /// Size in pixels.
    pub fn size(&self) -> [u32; 2] {
        self.size
    }

    /// Adds the colour image of `targets` (just drawn) as sample `k` (from 0: sample 0 starts
    /// the mean again) and writes the mean into the shown image. Submits and does not wait.
    pub fn add(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        targets: &RenderTargets,
        k: u32,
    ) {
        renderer.add_sample(
            device,
            queue,
            targets.colour_view(),
            (&self.mean, &self.shown_view),
            k,
        );
    }

    /// The shown image (sRGB RGBA8), to read back.
    pub fn shown_texture(&self) -> &wgpu::Texture {
        &self.shown
    }

    /// A view of the shown image, to show in a window.
    pub fn shown_view(&self) -> &wgpu::TextureView {
        &self.shown_view
    }
}

/// What a view is drawn from; a repaint with the same one adds a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ViewKey {
    camera: Camera,
    /// The look with [`RenderSettings::sample`] at 0.
    settings: RenderSettings,
    size: [u32; 2],
}

/// What a [`StillView::draw`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StillDraw {
    /// The image to show is a new texture (first draw, new size, or samples turned on or off):
    /// a window must register it again.
    pub new_texture: bool,
    /// More samples are to come: draw again while the view stays still.
    pub more: bool,
}

/// The window's picture with progressive samples while the view is still (see the module
/// documentation). With one sample per picture (the default look) it is the plain draw.
#[derive(Debug, Default)]
pub struct StillView {
    targets: Option<RenderTargets>,
    mean: Option<SampleMean>,
    /// The view of the samples in the mean, and how many there are.
    still: Option<(ViewKey, u32)>,
    /// True when the last draw showed the mean (not the targets' colour image).
    showing_mean: bool,
}

impl StillView {
    /// Draws the next picture of the view (`scene_changed`: the scene's contents changed
    /// since the last draw): sample 0 when anything changed, else the next sample until the
    /// look's [`RenderSettings::samples`] are in the mean, then nothing.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &Renderer,
        scene: &GpuScene,
        camera: &Camera,
        settings: &RenderSettings,
        size: [u32; 2],
        scene_changed: bool,
    ) -> StillDraw {
        let size = [size[0].max(1), size[1].max(1)];
        let resized = self.targets.as_ref().is_none_or(|t| t.size() != size);
        if resized {
            self.targets = Some(RenderTargets::new(device, size));
            self.mean = None;
        }
        let Some(targets) = self.targets.as_mut() else {
            return StillDraw::default();
        };
        let key = ViewKey {
            camera: *camera,
            settings: RenderSettings {
                sample: 0,
                ..*settings
            },
            size,
        };
        let samples = settings.samples.max(1);
        let k = match self.still {
            Some((last, drawn)) if last == key && !scene_changed && !resized => drawn,
            _ => 0,
        };
        let use_mean = samples > 1;
        let new_texture = resized || use_mean != self.showing_mean;
        self.showing_mean = use_mean;
        if k >= samples {
            return StillDraw {
                new_texture,
                more: false,
            };
        }
        let one = RenderSettings {
            sample: k,
            ..*settings
        };
        renderer.render(device, queue, targets, scene, camera, &one);
        if use_mean {
            let mean = self
                .mean
                .get_or_insert_with(|| SampleMean::new(device, targets.size()));
            mean.add(device, queue, renderer, targets, k);
        }
        self.still = Some((key, k + 1));
        StillDraw {
            new_texture,
            more: k + 1 < samples,
        }
    }

    /// The image to show: the mean of the samples so far, or with one sample per picture the
    /// targets' colour image.
    pub fn shown(&self) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        match (&self.mean, &self.targets) {
            (Some(m), _) if self.showing_mean => Some((m.shown_texture(), m.shown_view())),
            (_, Some(t)) => Some((t.colour_texture(), t.colour_view())),
            _ => None,
        }
    }

    /// Samples in the shown image (0 before the first draw).
    pub fn samples_shown(&self) -> u32 {
        self.still.map_or(0, |(_, n)| n)
    }

    /// The targets of the last draw.
    pub fn targets(&self) -> Option<&RenderTargets> {
        self.targets.as_ref()
    }
}
