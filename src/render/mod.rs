//! Drawing: an orbit [`Camera`], the GPU-side [`GpuScene`] (surface mesh, atom spheres, bond
//! cylinders), the [`Renderer`] with its one render-to-texture function [`Renderer::render`], and
//! [`render_to_rgba`] + [`write_png`] for pictures, progressive samples averaged on the GPU
//! ([`SampleMean`], and [`StillView`] for the window). Used by the viewer window, `mdsurf render`,
//! screenshots, movies and tests; it never imports the app.

pub(crate) mod atoms;
pub(crate) mod camera;
pub mod colour_bar;
pub(crate) mod headless;
pub(crate) mod pipelines;
pub(crate) mod progressive;
pub(crate) mod readback;
pub(crate) mod renderer;
pub(crate) mod scene;
mod scene_layers;
pub(crate) mod screen_rect;
pub(crate) mod setting_error;
pub mod settings;
pub mod shapes;
pub(crate) mod targets;
mod view_uniform;

pub use atoms::atom_instances;
pub use camera::{Camera, Projection, bounding_sphere};
pub use headless::HeadlessGpu;
pub use pipelines::{AO_WGSL, LOOK_WGSL, POST_WGSL, SCENE_WGSL};

/// Every render shader as `(file name, full source)` as the device compiles it.
pub const SHADERS: &[(&str, &str)] = pipelines::ALL;
pub use progressive::{SampleMean, StillDraw, StillView};
pub use readback::{
    MEAN_TOLERANCE, OUTLIER_FRACTION, OUTLIER_LEVEL, RgbaImage, read_texture, render_to_rgba,
    write_png,
};
pub use renderer::Renderer;
pub use scene::{CylinderInstance, GpuScene, SphereInstance};
pub use settings::{AtomStyle, Background, RenderSettings, Stereo};
pub use targets::{COLOUR_FORMAT, RenderTargets};

/// Why a picture could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// No usable GPU adapter or device (not even a software one).
    #[error("no GPU adapter for rendering: {0}")]
    NoAdapter(String),
    /// Copying the image back from the GPU failed.
    #[error("reading the rendered image back failed: {0}")]
    Readback(String),
    /// A PNG could not be written or read.
    #[error("PNG {0}: {1}")]
    Png(String, String),
    /// The window has no GPU device to draw a screenshot with.
    #[error("no GPU device for screenshots")]
    NoDevice,
}
