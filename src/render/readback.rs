//! Getting pictures out: render offscreen at a given size and copy the pixels back to memory
//! ([`render_to_rgba`], used by screenshots, movies, `mdsurf render` and tests), and write them as
//! PNG atomically (temporary file in the same folder, then rename).

use std::path::Path;

use super::RenderError;
use super::camera::Camera;
use super::progressive::SampleMean;
use super::renderer::Renderer;
use super::scene::GpuScene;
use super::settings::RenderSettings;
use super::targets::RenderTargets;

/// An 8-bit sRGB RGBA image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub pixels: Vec<u8>,
}

/// Image comparison tolerance (goldens, CPU-mesh vs GPU-buffer renders): mean absolute
/// difference per channel (0..255) ...
pub const MEAN_TOLERANCE: f64 = 1.5;
/// ... and the fraction of pixels allowed to differ by more than [`OUTLIER_LEVEL`] in some
/// channel.
pub const OUTLIER_FRACTION: f64 = 0.01;
/// Channel difference (0..255) above which a pixel counts as an outlier.
pub const OUTLIER_LEVEL: u8 = 24;

impl RgbaImage {
    /// Mean absolute channel difference (0..255) and fraction of outlier pixels against
    /// `other`, or `None` when the sizes differ.
    pub fn difference(&self, other: &RgbaImage) -> Option<(f64, f64)> {
        if (self.width, self.height) != (other.width, other.height) {
            return None;
        }
        let mut sum = 0u64;
        let mut outliers = 0usize;
        for (a, b) in self
            .pixels
            .chunks_exact(4)
            .zip(other.pixels.chunks_exact(4))
        {
            let d = [0, 1, 2, 3].map(|i| a[i].abs_diff(b[i]));
            sum += d.iter().map(|&x| x as u64).sum::<u64>();
            outliers += usize::from(d.iter().any(|&x| x > OUTLIER_LEVEL));
        }
        let n = (self.width as f64 * self.height as f64).max(1.0);
        Some((sum as f64 / (n * 4.0), outliers as f64 / n))
    }

    /// True when `other` is within [`MEAN_TOLERANCE`] and [`OUTLIER_FRACTION`] of this image.
    pub fn close_to(&self, other: &RgbaImage) -> bool {
        self.difference(other)
            .is_some_and(|(m, f)| m <= MEAN_TOLERANCE && f <= OUTLIER_FRACTION)
    }
    /// The RGBA value at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.pixels[i],
            self.pixels[i + 1],
            self.pixels[i + 2],
            self.pixels[i + 3],
        ]
    }

    /// Number of distinct colours (a uniform image has 1).
    pub fn distinct_colours(&self) -> usize {
        let mut set: Vec<u32> = self
            .pixels
            .chunks_exact(4)
            .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]]))
            .collect();
        set.sort_unstable();
        set.dedup();
        set.len()
    }

    /// Reads a PNG written by [`write_png`] (8-bit RGBA or RGB).
    pub fn read_png(path: &Path) -> Result<RgbaImage, RenderError> {
        let err = |e: String| RenderError::Png(path.display().to_string(), e);
        let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .map_err(|e| err(e.to_string()))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| err("image too large".into()))?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| err(e.to_string()))?;
        buf.truncate(info.buffer_size());
        let pixels = match (info.color_type, info.bit_depth) {
            (png::ColorType::Rgba, png::BitDepth::Eight) => buf,
            (png::ColorType::Rgb, png::BitDepth::Eight) => buf
                .chunks_exact(3)
                .flat_map(|c| [c[0], c[1], c[2], 255])
                .collect(),
            (c, d) => return Err(err(format!("unsupported PNG format {c:?} {d:?}"))),
        };
        Ok(RgbaImage {
            width: info.width,
            height: info.height,
            pixels,
        })
    }
}

/// Renders `scene` offscreen at `size` = [width, height] pixels and returns the image.
/// Sizes are clamped to 1..the device's largest texture.
pub fn render_to_rgba(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    renderer: &Renderer,
    scene: &GpuScene,
    camera: &Camera,
    settings: &RenderSettings,
    size: [u32; 2],
) -> Result<RgbaImage, RenderError> {
    let mut targets = RenderTargets::new(device, size);
    if settings.samples <= 1 {
        renderer.render(device, queue, &mut targets, scene, camera, settings);
        return read_texture(device, queue, targets.colour_texture());
    }
    // Progressive samples: each drawn and added to their running mean on the GPU (as the
    // window's still view does), which is read back once.
    let mean = SampleMean::new(device, targets.size());
    for sample in 0..settings.samples {
        let one = RenderSettings {
            sample,
            ..*settings
        };
        renderer.render(device, queue, &mut targets, scene, camera, &one);
        mean.add(device, queue, renderer, &targets, sample);
    }
    read_texture(device, queue, mean.shown_texture())
}

/// Copies an RGBA8 texture back to memory (blocking until the GPU is done).
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<RgbaImage, RenderError> {
    let (w, h) = (texture.width(), texture.height());
    let row = w * 4;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: padded as u64 * h as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("readback"),
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let data = buffer
        .slice(..)
        .get_mapped_range()
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut pixels = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        let start = y * padded as usize;
        pixels.extend_from_slice(&data[start..start + row as usize]);
    }
    drop(data);
    buffer.unmap();
    Ok(RgbaImage {
        width: w,
        height: h,
        pixels,
    })
}

/// Writes `image` as an 8-bit RGBA PNG. The file appears complete or not at all: the data goes
/// to a temporary file beside `path`, which is then renamed over it. A missing folder is an
/// error, as for every other output (a mistyped path never leaves new folders behind).
pub fn write_png(path: &Path, image: &RgbaImage) -> Result<(), RenderError> {
    let err = |e: String| RenderError::Png(path.display().to_string(), e);
    // Written to a temporary file and renamed, with the permissions of the file it replaces
    // (or rw-r--r--), like every other output.
    crate::export::write_atomic(path, |w| {
        let mut enc = png::Encoder::new(w, image.width, image.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(&image.pixels)
            .map_err(std::io::Error::other)?;
        w.finish().map_err(std::io::Error::other)
    })
    .map_err(|e| match e {
        crate::export::ExportError::Io { source, .. } => err(source.to_string()),
        other => err(other.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, v: u8) -> RgbaImage {
        RgbaImage {
            width: w,
            height: h,
            pixels: vec![v; (w * h * 4) as usize],
        }
    }

    #[test]
    fn difference_counts_mean_and_outliers() {
        let a = image(2, 2, 100);
        assert_eq!(a.difference(&a), Some((0.0, 0.0)));
        let mut b = a.clone();
        b.pixels[5] = 130; // one channel of pixel 1 differs by 30 > OUTLIER_LEVEL
        let (mean, frac) = a.difference(&b).expect("same size");
        assert!((mean - 30.0 / 16.0).abs() < 1e-12, "{mean}");
        assert!((frac - 0.25).abs() < 1e-12, "{frac}");
        assert!(!a.close_to(&b));
        b.pixels[5] = 101;
        assert!(a.close_to(&b));
        assert_eq!(a.difference(&image(4, 1, 100)), None);
    }
}
