//! A wgpu device without a window, for `mdsurf render` and tests: the high-performance adapter
//! when there is one, else whatever wgpu offers (Mesa lavapipe on machines without a GPU).

use super::RenderError;

/// A device and its queue, with a line describing the adapter.
#[derive(Debug)]
pub struct HeadlessGpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name and backend, for messages (`llvmpipe (Vulkan)`).
    pub adapter_name: String,
}

impl HeadlessGpu {
    /// Opens the best available adapter with its own limits (so large screenshots fit).
    pub fn new() -> Result<HeadlessGpu, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("mdsurf headless"),
            required_features: wgpu::Features::empty(),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        Ok(HeadlessGpu {
            device,
            queue,
            adapter_name: format!("{} ({:?})", info.name, info.backend),
        })
    }
}
