//! Device setup: the wgpu device and queue every GPU stage runs on, created headless (CLI,
//! tests, benchmarks) or shared with the viewer's eframe device, with the adapter's real limits
//! and timestamp queries where the adapter has them.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use super::GpuError;

/// A wgpu device plus what the engine needs to know about it.
#[derive(Debug, Clone)]
pub struct GpuContext {
    /// The device (cheap to clone).
    pub device: wgpu::Device,
    /// Its queue (cheap to clone).
    pub queue: wgpu::Queue,
    /// The limits the device was created with.
    pub limits: wgpu::Limits,
    /// True when the device has `TIMESTAMP_QUERY` (per-pass GPU timings).
    pub timestamps: bool,
    /// Adapter name and backend, for messages.
    pub adapter_name: String,
    /// True when the adapter is a software rasterizer on the CPU (Mesa lavapipe, WARP):
    /// correct but slower than the CPU engine, so `--backend auto` passes it over.
    pub software_adapter: bool,
    /// GPU objects created through this context (shared by its clones); see
    /// [`GpuContext::objects`].
    counter: Arc<ObjectCounter>,
}

/// How many GPU objects of each kind were created through one [`GpuContext`] (and its clones):
/// the engine creates every buffer, bind group, texture and query set through the context, so
/// the difference of two snapshots is what the frames in between allocated.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GpuObjects {
    /// Buffers.
    pub buffers: u64,
    /// Bind groups.
    pub bind_groups: u64,
    /// Textures.
    pub textures: u64,
    /// Query sets (timestamps).
    pub query_sets: u64,
}

impl GpuObjects {
    /// All objects together.
    pub fn total(&self) -> u64 {
        self.buffers + self.bind_groups + self.textures + self.query_sets
    }
}

impl std::ops::Sub for GpuObjects {
    type Output = GpuObjects;
    fn sub(self, o: GpuObjects) -> GpuObjects {
        GpuObjects {
            buffers: self.buffers.saturating_sub(o.buffers),
            bind_groups: self.bind_groups.saturating_sub(o.bind_groups),
            textures: self.textures.saturating_sub(o.textures),
            query_sets: self.query_sets.saturating_sub(o.query_sets),
        }
    }
}

#[derive(Debug, Default)]
struct ObjectCounter {
    buffers: AtomicU64,
    bind_groups: AtomicU64,
    textures: AtomicU64,
    query_sets: AtomicU64,
    /// The most storage buffers one compute layout made so far binds.
    widest_storage_layout: AtomicU64,
}

/// Said after "no GPU adapter" where a picture is needed (`render`, the window): what a machine
/// without a GPU needs.
pub const SOFTWARE_ADAPTER: &str =
    "a software one is enough: Mesa's lavapipe, Debian's and Ubuntu's mesa-vulkan-drivers";

/// What in wgpu's "no adapter" message says why: its list of backends without those the
/// instance did not ask for and, when others remain, those this build does not have ("No
/// suitable graphics adapter found; noop not requested, vulkan drivers/libraries could not be
/// loaded, metal support not compiled in, ..." gives "vulkan drivers/libraries could not be
/// loaded"). A message of another form is kept whole.
fn adapter_failure(message: &str) -> String {
    let Some((_, backends)) = message.split_once("; ") else {
        return message.to_string();
    };
    let tried: Vec<&str> = backends
        .split(", ")
        .filter(|reason| !reason.ends_with(" not requested"))
        .collect();
    let built: Vec<&str> = tried
        .iter()
        .copied()
        .filter(|reason| !reason.ends_with(" support not compiled in"))
        .collect();
    match (built.is_empty(), tried.is_empty()) {
        (false, _) => built.join(", "),
        (true, false) => tried.join(", "),
        (true, true) => message.to_string(),
    }
}

impl GpuContext {
    /// Opens the best adapter without a window, requesting its full storage-buffer, buffer-size,
    /// workgroup and texture-size limits and timestamp queries when supported. The only place
    /// mdsurf opens a headless device: the engine, `render` and the tests share it
    /// ([`crate::render::HeadlessGpu`] wraps one).
    pub fn new_headless() -> Result<GpuContext, GpuError> {
        pollster::block_on(Self::new_headless_async())
    }

    async fn new_headless_async() -> Result<GpuContext, GpuError> {
        // Vulkan, Metal or DX12 first; OpenGL only where none of them has an adapter. An instance
        // that also opened OpenGL (EGL) deadlocked NVIDIA's driver when it was dropped on one
        // thread while another thread compiled a Vulkan pipeline. `WGPU_BACKEND` still chooses.
        let adapter = match Self::headless_adapter(wgpu::Backends::PRIMARY).await {
            Ok(adapter) => adapter,
            Err(GpuError::NoAdapter(primary)) if std::env::var_os("WGPU_BACKEND").is_none() => {
                match Self::headless_adapter(wgpu::Backends::SECONDARY).await {
                    Ok(adapter) => adapter,
                    // Both tries' reasons: the second alone would say "vulkan not requested".
                    Err(GpuError::NoAdapter(secondary)) => {
                        return Err(GpuError::NoAdapter(format!("{primary}; {secondary}")));
                    }
                    Err(e) => return Err(e),
                }
            }
            Err(e) => return Err(e),
        };
        let info = adapter.get_info();
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let limits = Self::wanted_limits(&adapter.limits());
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("mdsurf compute"),
                required_features: features,
                required_limits: limits.clone(),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(Self::from_device(device, queue, String::new()).with_adapter(&info))
    }

    /// The backends a window's wgpu instance (eframe's, or a test harness's) may open: what
    /// `WGPU_BACKEND` names; else Vulkan, Metal or DX12 when one of them has an adapter, OpenGL
    /// only where none has. egui's default adds OpenGL beside them, and an instance that opened
    /// EGL on NVIDIA's driver deadlocked it when dropped while another thread compiled a Vulkan
    /// pipeline (as in [`GpuContext::new_headless`]); the window test hung that way on an H100.
    pub fn window_backends() -> wgpu::Backends {
        if let Some(named) = wgpu::Backends::from_env() {
            return named;
        }
        match pollster::block_on(Self::headless_adapter(wgpu::Backends::PRIMARY)) {
            Ok(_) => wgpu::Backends::PRIMARY,
            Err(_) => wgpu::Backends::PRIMARY | wgpu::Backends::GL,
        }
    }

    /// The high-performance adapter of an instance limited to `backends` (or to what
    /// `WGPU_BACKEND` names).
    async fn headless_adapter(backends: wgpu::Backends) -> Result<wgpu::Adapter, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = backends;
        let instance = wgpu::Instance::new(descriptor.with_env());
        instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(adapter_failure(&e.to_string())))
    }

    /// The limits mdsurf asks for: the adapter's own maxima for what bounds problem size and
    /// picture size (`using_resolution`), the WebGPU defaults elsewhere, each no better than
    /// the adapter has (Mesa 21.2's lavapipe, Ubuntu 20.04's, offers 2 colour attachments
    /// where the defaults ask for 8, and a request for 8 failed the whole device; the renderer
    /// draws into at most 2).
    pub fn wanted_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
        wgpu::Limits {
            max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
            max_buffer_size: adapter.max_buffer_size,
            max_compute_workgroups_per_dimension: adapter.max_compute_workgroups_per_dimension,
            max_storage_buffers_per_shader_stage: adapter
                .max_storage_buffers_per_shader_stage
                .min(16),
            // The renderer's order-independent transparency writes several targets at once.
            max_color_attachment_bytes_per_sample: adapter.max_color_attachment_bytes_per_sample,
            ..wgpu::Limits::default().using_resolution(adapter.clone())
        }
        .or_worse_values_from(adapter)
    }

    /// Names the adapter the device came from (`llvmpipe (Vulkan)`) and notes whether it is a
    /// software rasterizer ([`GpuContext::software_adapter`]).
    pub fn with_adapter(mut self, info: &wgpu::AdapterInfo) -> GpuContext {
        self.adapter_name = format!("{} ({:?})", info.name, info.backend);
        self.software_adapter = info.device_type == wgpu::DeviceType::Cpu;
        self
    }

    /// Wraps a device created elsewhere (the viewer's eframe device). `name` is for messages.
    /// Timestamps are used when the device was created with `TIMESTAMP_QUERY`.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, name: String) -> GpuContext {
        let limits = device.limits();
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        GpuContext {
            device,
            queue,
            limits,
            timestamps,
            adapter_name: name,
            software_adapter: false,
            counter: Arc::default(),
        }
    }

    /// Objects created through this context so far.
    pub fn objects(&self) -> GpuObjects {
        let c = &self.counter;
        GpuObjects {
            buffers: c.buffers.load(Ordering::Relaxed),
            bind_groups: c.bind_groups.load(Ordering::Relaxed),
            textures: c.textures.load(Ordering::Relaxed),
            query_sets: c.query_sets.load(Ordering::Relaxed),
        }
    }

    /// Notes a compute layout that binds `storage` storage buffers.
    pub(crate) fn note_storage_layout(&self, storage: u32) {
        (self.counter.widest_storage_layout).fetch_max(u64::from(storage), Ordering::Relaxed);
    }

    /// The most storage buffers one compute layout made through this context binds: what the
    /// device's `max_storage_buffers_per_shader_stage` must allow.
    pub fn widest_storage_layout(&self) -> u32 {
        self.counter.widest_storage_layout.load(Ordering::Relaxed) as u32
    }

    fn count(n: &AtomicU64) {
        n.fetch_add(1, Ordering::Relaxed);
    }

    /// Creates a buffer (counted).
    pub fn create_buffer(&self, desc: &wgpu::BufferDescriptor<'_>) -> wgpu::Buffer {
        Self::count(&self.counter.buffers);
        self.device.create_buffer(desc)
    }

    /// Creates a buffer holding `contents` (counted).
    pub fn create_buffer_init(&self, desc: &wgpu::util::BufferInitDescriptor<'_>) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        Self::count(&self.counter.buffers);
        self.device.create_buffer_init(desc)
    }

    /// Creates a bind group (counted).
    pub fn create_bind_group(&self, desc: &wgpu::BindGroupDescriptor<'_>) -> wgpu::BindGroup {
        Self::count(&self.counter.bind_groups);
        self.device.create_bind_group(desc)
    }

    /// Creates a texture (counted).
    pub fn create_texture(&self, desc: &wgpu::TextureDescriptor<'_>) -> wgpu::Texture {
        Self::count(&self.counter.textures);
        self.device.create_texture(desc)
    }

    /// Creates a query set (counted).
    pub fn create_query_set(&self, desc: &wgpu::QuerySetDescriptor<'_>) -> wgpu::QuerySet {
        Self::count(&self.counter.query_sets);
        self.device.create_query_set(desc)
    }

    /// For tests and `--backend auto`: a headless context, or `Ok(None)` with a note on stderr
    /// when no adapter exists, except under `REQUIRE_GPU=1`, where a missing adapter is an error.
    pub fn headless_or_skip() -> Result<Option<GpuContext>, GpuError> {
        match Self::new_headless() {
            Ok(ctx) => Ok(Some(ctx)),
            Err(e) if !gpu_required() => {
                eprintln!(
                    "note: no GPU adapter ({e}); skipping GPU work (set REQUIRE_GPU=1 to fail instead)"
                );
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    /// The limits that size the engine's buffers ([`super::plan::DeviceLimits`]).
    pub fn device_limits(&self) -> super::plan::DeviceLimits {
        super::plan::DeviceLimits::of(&self.limits)
    }

    /// Largest single storage binding in bytes.
    pub fn max_binding(&self) -> u64 {
        self.device_limits().max_binding()
    }

    /// Runs `f` inside validation and out-of-memory error scopes, so a GPU error becomes a
    /// [`GpuError::Device`] instead of wgpu's default panic.
    pub fn scoped<T>(&self, f: impl FnOnce() -> Result<T, GpuError>) -> Result<T, GpuError> {
        match self.capture(f) {
            (Err(e), _) => Err(e),
            (Ok(_), Some(e)) => Err(e),
            (Ok(t), None) => Ok(t),
        }
    }

    /// Runs `f` inside validation and out-of-memory error scopes and returns its value with the
    /// first GPU error it caused (objects created with errors exist but are invalid).
    pub fn capture<T>(&self, f: impl FnOnce() -> T) -> (T, Option<GpuError>) {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        let error = v.or(o).map(|e| GpuError::Device(one_line(&e.to_string())));
        (value, error)
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Device(e.to_string()))
    }
}

/// Serialises shader compilation (shader modules, compute and render pipelines) across the
/// whole process, whatever the device. NVIDIA's Vulkan driver (580.159 on an H100) deadlocked
/// inside `vkCreateComputePipelines` when several threads compiled pipelines at once on their
/// own devices (eight test threads each building an engine; every thread stopped in the
/// driver's locks, for minutes, at 0 % GPU use). Compiling is once per engine or renderer, so
/// holding one lock around it costs nothing per frame.
pub fn compile_lock() -> MutexGuard<'static, ()> {
    static COMPILING: Mutex<()> = Mutex::new(());
    // A panic while compiling leaves no state behind the lock, so a poisoned lock is usable.
    COMPILING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Joins a multi-line wgpu error into one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// True when the environment variable `REQUIRE_GPU` is set to `1` (CI).
pub fn gpu_required() -> bool {
    std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1")
}

#[cfg(test)]
mod tests {
    use super::{GpuContext, adapter_failure};

    /// An adapter below the WebGPU defaults (Mesa 21.2's lavapipe: 2 colour attachments) gets
    /// a request it can grant; one above them gets its own maxima where mdsurf wants them.
    #[test]
    fn wanted_limits_never_exceed_the_adapter() {
        let old_lavapipe = wgpu::Limits {
            max_color_attachments: 2,
            max_storage_buffers_per_shader_stage: 8,
            ..wgpu::Limits::default()
        };
        let wanted = GpuContext::wanted_limits(&old_lavapipe);
        assert_eq!(wanted.max_color_attachments, 2);
        assert_eq!(wanted.max_storage_buffers_per_shader_stage, 8);
        assert!(wanted.check_limits(&old_lavapipe));
        let large = wgpu::Limits {
            max_buffer_size: 1 << 40,
            max_texture_dimension_2d: 32768,
            max_storage_buffers_per_shader_stage: 64,
            ..wgpu::Limits::default()
        };
        let wanted = GpuContext::wanted_limits(&large);
        assert_eq!(wanted.max_buffer_size, 1 << 40);
        assert_eq!(wanted.max_texture_dimension_2d, 32768);
        assert_eq!(wanted.max_storage_buffers_per_shader_stage, 16);
        assert!(wanted.check_limits(&large));
    }

    /// wgpu 30's messages on machines without a Vulkan loader or libEGL (Ubuntu 16.04), for
    /// the try of the primary backends, of Vulkan alone (`WGPU_BACKEND=vulkan`) and of OpenGL:
    /// only the backends that were tried and that this build has remain.
    #[test]
    fn an_adapter_failure_keeps_the_backends_that_were_tried() {
        let primary = "No suitable graphics adapter found; noop not requested, vulkan \
            drivers/libraries could not be loaded, metal support not compiled in, dx12 support \
            not compiled in, gl not requested, webgpu support not compiled in";
        assert_eq!(
            adapter_failure(primary),
            "vulkan drivers/libraries could not be loaded"
        );
        let vulkan = "No suitable graphics adapter found; noop not requested, vulkan \
            drivers/libraries could not be loaded, metal not requested, dx12 not requested, gl \
            not requested, webgpu not requested";
        assert_eq!(
            adapter_failure(vulkan),
            "vulkan drivers/libraries could not be loaded"
        );
        let gl = "No suitable graphics adapter found; noop not requested, vulkan not requested, \
            metal not requested, dx12 not requested, gl drivers/libraries could not be loaded, \
            webgpu not requested";
        assert_eq!(
            adapter_failure(gl),
            "gl drivers/libraries could not be loaded"
        );
        assert_eq!(adapter_failure("lost"), "lost");
        // `WGPU_BACKEND=metal` on Linux: only a backend this build lacks was asked for.
        let metal = "No suitable graphics adapter found; noop not requested, vulkan not \
            requested, metal support not compiled in, dx12 not requested, gl not requested, \
            webgpu not requested";
        assert_eq!(adapter_failure(metal), "metal support not compiled in");
        let none_tried = "No suitable graphics adapter found; vulkan not requested";
        assert_eq!(adapter_failure(none_tried), none_tried);
    }
}
