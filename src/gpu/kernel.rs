//! Helpers shared by every stage: explicit bind-group layouts built from the binding tables of
//! [`super::layout`], compute pipelines on them, bind groups cached across frames (rebuilt only
//! when a buffer they bind was replaced), 1-D dispatch sizes within the device limit, buffers
//! that grow, and uniform buffers written in place. Every object is created through
//! [`GpuContext`], which counts them.

use std::num::NonZeroU64;

use super::context::GpuContext;
use super::layout::{Kind, Slot};

/// An explicit bind-group layout for group 0, from a binding table.
#[derive(Debug, Clone)]
pub struct Layout {
    bgl: wgpu::BindGroupLayout,
    slots: &'static [Slot],
}

impl Layout {
    /// The layout of `slots` (visible to compute).
    pub fn new(ctx: &GpuContext, label: &str, slots: &'static [Slot]) -> Layout {
        let entries: Vec<wgpu::BindGroupLayoutEntry> = slots
            .iter()
            .map(|s| {
                let ty = match s.kind {
                    Kind::Uniform => wgpu::BufferBindingType::Uniform,
                    Kind::DynamicUniform(_) => wgpu::BufferBindingType::Uniform,
                    Kind::Read => wgpu::BufferBindingType::Storage { read_only: true },
                    Kind::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
                };
                let (dynamic, min) = match s.kind {
                    Kind::DynamicUniform(size) => (true, NonZeroU64::new(size)),
                    _ => (false, None),
                };
                wgpu::BindGroupLayoutEntry {
                    binding: s.binding,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty,
                        has_dynamic_offset: dynamic,
                        min_binding_size: min,
                    },
                    count: None,
                }
            })
            .collect();
        let storage = slots
            .iter()
            .filter(|s| matches!(s.kind, Kind::Read | Kind::ReadWrite))
            .count();
        ctx.note_storage_layout(storage as u32);
        let bgl = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            });
        Layout { bgl, slots }
    }
}

/// A bind group kept across frames: rebuilt only when a buffer it binds is not the one it was
/// built with (the buffer grew and was replaced).
#[derive(Debug, Default)]
pub struct Bound {
    buffers: Vec<wgpu::Buffer>,
    group: Option<wgpu::BindGroup>,
}

impl Bound {
    /// The bind group (panics before the first [`Kernel::bind`]; stages bind before recording).
    pub fn group(&self) -> &wgpu::BindGroup {
        self.group
            .as_ref()
            .expect("bind group prepared before recording")
    }
}

/// One compute entry point on an explicit layout.
#[derive(Debug)]
pub struct Kernel {
    pipeline: wgpu::ComputePipeline,
    layout: Layout,
    label: &'static str,
}

impl Kernel {
    /// Compiles `entry` of `module` on `layout`, with pipeline-overridable `constants`.
    pub fn new(
        ctx: &GpuContext,
        module: &wgpu::ShaderModule,
        entry: &'static str,
        constants: &[(&str, f64)],
        layout: &Layout,
    ) -> Kernel {
        let device = &ctx.device;
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &[Some(&layout.bgl)],
            immediate_size: 0,
        });
        let _compiling = super::context::compile_lock();
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                zero_initialize_workgroup_memory: false,
            },
            cache: None,
        });
        Kernel {
            pipeline,
            layout: layout.clone(),
            label: entry,
        }
    }

    /// A kernel with its own layout of `slots`.
    pub fn with_slots(
        ctx: &GpuContext,
        module: &wgpu::ShaderModule,
        entry: &'static str,
        slots: &'static [Slot],
    ) -> Kernel {
        Self::new(ctx, module, entry, &[], &Layout::new(ctx, entry, slots))
    }

    /// Keeps `cache` bound to `entries` (one buffer per slot of the layout, in its order):
    /// creates a bind group only when a buffer differs from the cached one. Dynamic uniforms
    /// are bound with their struct size; everything else whole.
    pub fn bind(&self, ctx: &GpuContext, cache: &mut Bound, entries: &[(Slot, &wgpu::Buffer)]) {
        debug_assert!(
            entries.len() == self.layout.slots.len()
                && entries
                    .iter()
                    .zip(self.layout.slots)
                    .all(|(e, s)| e.0 == *s),
            "{}: bind entries do not follow the layout",
            self.label
        );
        let same = cache.group.is_some()
            && cache.buffers.len() == entries.len()
            && cache.buffers.iter().zip(entries).all(|(b, e)| b == e.1);
        if same {
            return;
        }
        let list: Vec<wgpu::BindGroupEntry<'_>> = entries
            .iter()
            .map(|(slot, buffer)| wgpu::BindGroupEntry {
                binding: slot.binding,
                resource: match slot.kind {
                    Kind::DynamicUniform(size) => {
                        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer,
                            offset: 0,
                            size: NonZeroU64::new(size),
                        })
                    }
                    _ => buffer.as_entire_binding(),
                },
            })
            .collect();
        cache.group = Some(ctx.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout.bgl,
            entries: &list,
        }));
        cache.buffers = entries.iter().map(|e| e.1.clone()).collect();
    }

    /// Records one dispatch of `groups` workgroups with `bind` (at `offsets` when it has a
    /// dynamic uniform).
    pub fn dispatch(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &Bound,
        offsets: &[u32],
        groups: [u32; 3],
    ) {
        if groups.contains(&0) {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind.group(), offsets);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }

    /// Records an indirect dispatch with arguments at the start of `args`.
    pub fn dispatch_indirect(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        bind: &Bound,
        offsets: &[u32],
        args: &wgpu::Buffer,
    ) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind.group(), offsets);
        pass.dispatch_workgroups_indirect(args, 0);
    }
}

/// Compiles a WGSL source.
pub fn module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    let _compiling = super::context::compile_lock();
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// Workgroup counts `[x, y, 1]` covering `groups` workgroups when each dimension is limited to
/// `max_per_dim`; the shaders linearise `x + y * num_workgroups.x` and skip the excess.
pub fn groups_1d(groups: u64, max_per_dim: u32) -> [u32; 3] {
    if groups == 0 {
        return [0, 0, 0];
    }
    let max = max_per_dim.max(1) as u64;
    let x = groups.min(max);
    let y = groups.div_ceil(x);
    [x as u32, y.min(u32::MAX as u64) as u32, 1]
}

/// A storage buffer of `size` bytes (at least 16) with `usage` plus STORAGE.
pub fn storage(
    ctx: &GpuContext,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(4),
        usage: usage | wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

/// A uniform buffer of `size` bytes (rounded up to 16), written later with `queue.write_buffer`.
pub fn uniform_buffer(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(16),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A uniform buffer holding `value`.
pub fn uniform<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    ctx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

/// A persistent uniform of type `T`, rewritten in place each frame (no new buffer).
#[derive(Debug)]
pub struct Uniform<T> {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    _t: std::marker::PhantomData<T>,
}

impl<T: bytemuck::Pod> Uniform<T> {
    /// A zeroed uniform.
    pub fn new(ctx: &GpuContext, label: &str) -> Uniform<T> {
        Uniform {
            buffer: uniform_buffer(ctx, label, size_of::<T>() as u64),
            _t: std::marker::PhantomData,
        }
    }

    /// Queues `value` for the next submit.
    pub fn write(&self, queue: &wgpu::Queue, value: &T) {
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(value));
    }
}
