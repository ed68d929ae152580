//! Recovery from a lost GPU device (driver reset, GPU removed, `Device::destroy`). eframe keeps
//! one wgpu device for the life of its window and cannot replace it, so the viewer watches the
//! device, and when it is lost closes the window and [`super::run`] opens a new one (with a new
//! device) on the same files, surface parameters and particle options.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use crate::model::ParticleOptions;
use crate::surface::SurfaceParams;

/// Reopens allowed in one run before the viewer gives up (a device that keeps getting lost).
pub const MAX_REOPENS: usize = 3;

/// Watches one wgpu device; [`DeviceWatch::lost`] says whether (and why) it was lost.
#[derive(Debug, Clone, Default)]
pub struct DeviceWatch {
    reason: Arc<Mutex<Option<String>>>,
}

impl DeviceWatch {
    /// Registers the device-lost callback of `device`; `wake` is called when it fires (the
    /// window asks for a repaint so it notices at once).
    pub fn attach(device: &wgpu::Device, wake: impl Fn() + Send + 'static) -> DeviceWatch {
        let watch = DeviceWatch::default();
        let reason = watch.reason.clone();
        device.set_device_lost_callback(move |why, message| {
            if let Ok(mut slot) = reason.lock() {
                *slot = Some(format!("{why:?}: {message}"));
            }
            wake();
        });
        watch
    }

    /// The reason, one line, once the device has been lost.
    pub fn lost(&self) -> Option<String> {
        self.reason.lock().ok().and_then(|r| r.clone())
    }
}

/// What a reopened window restores.
#[derive(Debug, Clone)]
pub struct Reopen {
    /// Topology and trajectory that were open (`None`: the bundled demo).
    pub files: Option<(PathBuf, Option<PathBuf>)>,
    /// Applied surface parameters.
    pub params: SurfaceParams,
    /// Beads, colours and radius overrides.
    pub particles: ParticleOptions,
    /// Why the device was lost, for the message.
    pub reason: String,
}

/// Filled by the window that lost its device, read by [`super::run`] after it closed.
pub type ReopenSlot = Arc<Mutex<Option<Reopen>>>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};

    #[test]
    fn a_destroyed_device_is_reported_lost() {
        let gpu = match crate::render::HeadlessGpu::new() {
            Ok(gpu) => gpu,
            Err(err) if !crate::gpu::gpu_required() => {
                eprintln!("note: no GPU adapter ({err}); skipping");
                return;
            }
            Err(err) => panic!("REQUIRE_GPU=1 but no adapter: {err}"),
        };
        let woken = Arc::new(AtomicBool::new(false));
        let flag = woken.clone();
        let watch = DeviceWatch::attach(&gpu.device, move || flag.store(true, Ordering::SeqCst));
        assert_eq!(watch.lost(), None, "a fresh device is not lost");
        gpu.device.destroy();
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
        let reason = watch.lost().expect("the destroyed device is reported lost");
        assert!(reason.contains("Destroyed"), "{reason}");
        assert!(woken.load(Ordering::SeqCst), "the window is woken");
    }
}
