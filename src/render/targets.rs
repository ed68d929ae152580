//! The offscreen textures one image is rendered into: the output colour texture (what the window
//! shows, screenshots read back and the anaglyph pass writes), depth, the two transparency
//! accumulation targets, and, for the anaglyph stereo modes, one colour texture per eye.

/// Format of the output and eye images: 8-bit sRGB, so shaders work in linear colour and the
/// bytes read back are ready for PNG.
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Depth buffer format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Transparency accumulation target (premultiplied colour times weight, and weight).
pub const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Running mean of progressive samples (linear colour; blendable at half-float precision).
pub const MEAN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Transparency revealage target (product of 1 - alpha).
pub const REVEAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

pub(crate) fn texture(
    device: &wgpu::Device,
    label: &str,
    size: [u32; 2],
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> (wgpu::Texture, wgpu::TextureView) {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    });
    let v = t.create_view(&wgpu::TextureViewDescriptor::default());
    (t, v)
}

/// Offscreen targets of one size.
#[derive(Debug)]
pub struct RenderTargets {
    size: [u32; 2],
    colour: wgpu::Texture,
    pub(crate) colour_view: wgpu::TextureView,
    pub(crate) depth_view: wgpu::TextureView,
    pub(crate) accum_view: wgpu::TextureView,
    pub(crate) reveal_view: wgpu::TextureView,
    /// Left and right eye images, made on first use of an anaglyph mode.
    pub(crate) eyes: Option<[wgpu::TextureView; 2]>,
}

impl RenderTargets {
    /// Creates targets of `size` = [width, height] pixels (each clamped to 1..device limit).
    pub fn new(device: &wgpu::Device, size: [u32; 2]) -> Self {
        let max = device.limits().max_texture_dimension_2d;
        let size = [size[0].clamp(1, max), size[1].clamp(1, max)];
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let sampled = attach | wgpu::TextureUsages::TEXTURE_BINDING;
        let (colour, colour_view) = texture(
            device,
            "render output",
            size,
            COLOUR_FORMAT,
            sampled | wgpu::TextureUsages::COPY_SRC,
        );
        let (_, depth_view) = texture(device, "render depth", size, DEPTH_FORMAT, sampled);
        let (_, accum_view) = texture(device, "oit accum", size, ACCUM_FORMAT, sampled);
        let (_, reveal_view) = texture(device, "oit reveal", size, REVEAL_FORMAT, sampled);
        RenderTargets {
            size,
            colour,
            colour_view,
            depth_view,
            accum_view,
            reveal_view,
            eyes: None,
        }
    }

    /// Makes the per-eye images if they do not exist yet.
    pub(crate) fn ensure_eyes(&mut self, device: &wgpu::Device) {
        if self.eyes.is_none() {
            let usage =
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
            let (_, l) = texture(device, "left eye", self.size, COLOUR_FORMAT, usage);
            let (_, r) = texture(device, "right eye", self.size, COLOUR_FORMAT, usage);
            self.eyes = Some([l, r]);
        }
    }

    /// Size in pixels, [width, height].
    pub fn size(&self) -> [u32; 2] {
        self.size
    }

    /// The output image (sRGB RGBA8), for showing in a window or copying out.
    pub fn colour_texture(&self) -> &wgpu::Texture {
        &self.colour
    }

    /// A view of the output image.
    pub fn colour_view(&self) -> &wgpu::TextureView {
        &self.colour_view
    }
}
