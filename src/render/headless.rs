//! A wgpu device without a window, for `mdsurf render` and tests: the device the GPU engine
//! opens ([`GpuContext::new_headless`], the one device-opening function), so `render` draws the
//! engine's buffers in place on the device that computed them.

use super::RenderError;
use crate::gpu::{GpuContext, GpuError};

/// A device and its queue, with a line describing the adapter.
#[derive(Debug)]
pub struct HeadlessGpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name and backend, for messages (`llvmpipe (Vulkan)`).
    pub adapter_name: String,
    /// The same device as the GPU engine sees it (limits, timestamps, software adapter).
    pub context: GpuContext,
}

impl HeadlessGpu {
    /// Opens the best available adapter with its own limits (so large screenshots fit).
    pub fn new() -> Result<HeadlessGpu, RenderError> {
        let context = GpuContext::new_headless().map_err(|e| match e {
            GpuError::NoAdapter(reason) => RenderError::NoAdapter(reason),
            other => RenderError::NoAdapter(other.to_string()),
        })?;
        Ok(HeadlessGpu {
            device: context.device.clone(),
            queue: context.queue.clone(),
            adapter_name: context.adapter_name.clone(),
            context,
        })
    }
}
