//! What comes out of the GPU engine: the GPU-resident surface the renderer draws from
//! ([`GpuSurface`]: vertex and index buffers plus indirect draw arguments), the per-frame
//! counters that come back asynchronously ([`FrameStats`], through a small pool of mappable
//! [`Readbacks`] slots, reused frame after frame), and blocking readback of buffers for
//! `mdsurf surface` and the tests (the engine's through one persistent [`Staging`] buffer).

use std::sync::{Arc, Mutex};

use glam::Vec3;

use super::GpuError;
use super::context::GpuContext;
use super::timing::{Stage, Timer};
use super::types::{GpuCounters, GpuVertex};
use crate::surface::{GridSpec, Mesh, StageTimings};

/// Counters of one finished frame, read back asynchronously (they may arrive a frame late).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Frame number as returned by [`super::GpuEngine::submit`].
    pub frame: u64,
    /// Vertices of the surface.
    pub vertex_count: u32,
    /// Triangles of the surface.
    pub triangle_count: u32,
    /// True when the mesh did not fit its buffers (nothing is drawn; the next frame grows them).
    pub overflow: bool,
    /// Surface area in Å² (GPU reduction in f32).
    pub area: f64,
    /// Enclosed volume in Å³ (GPU reduction in f32).
    pub volume: f64,
    /// GPU timestamp times per stage in ms (all 0 without timestamp queries; upload is wall-clock).
    pub timings: StageTimings,
    /// Sparse bricks some atom reaches (sampled and classified); 0 on the dense path.
    pub reached_bricks: u32,
    /// True when the reached bricks did not fit the brick slots of the density and colour
    /// buffers (then `overflow` is set too; the next frame grows them and re-runs density).
    pub brick_overflow: bool,
    /// Brick slots the frame's density pass needed (the most reached bricks of one slab); 0 on
    /// the dense path and on frames that did not run density.
    pub brick_slots: u32,
}

/// The surface as it lives on the GPU, for the renderer: draw with
/// `set_vertex_buffer(0, vertices)`, `set_index_buffer(indices, Uint32)` and
/// `draw_indexed_indirect(draw_args, 0)`. Buffers are shared handles (cheap to clone); the engine
/// replaces them when they grow, so fetch a fresh `GpuSurface` after each submit.
#[derive(Debug, Clone)]
pub struct GpuSurface {
    /// [`GpuVertex`] records (layout: [`GpuSurface::vertex_layout`]).
    pub vertices: wgpu::Buffer,
    /// u32 indices, three per triangle, counter-clockwise seen from outside.
    pub indices: wgpu::Buffer,
    /// `DrawIndexedIndirectArgs` (20 bytes) written by the GPU at the end of each frame.
    pub draw_args: wgpu::Buffer,
    /// The grid of the frame that filled the buffers.
    pub grid: GridSpec,
    /// Frame number of the last submitted frame.
    pub frame: u64,
    /// Newest counters that have arrived (possibly of an earlier frame).
    pub stats: Option<FrameStats>,
}

impl GpuSurface {
    /// Vertex attributes: position (location 0), normal (1), colour (2), all `Float32x3`.
    pub const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];

    /// The vertex buffer layout of [`GpuSurface::vertices`] (stride 36 bytes).
    pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: size_of::<GpuVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// Where a buffer map's callback leaves its outcome (`None` until it has run).
type MapResult = Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>;

#[derive(Debug)]
struct Slot {
    buffer: wgpu::Buffer,
    busy: bool,
    frame: u64,
    passes: Vec<Stage>,
    result: MapResult,
}

/// Mappable buffers the frame counters and timestamps are copied into; each frame takes a free
/// slot (at most [`Readbacks::MAX_SLOTS`] in flight; later frames skip their readback).
#[derive(Debug, Default)]
pub struct Readbacks {
    slots: Vec<Slot>,
}

impl Readbacks {
    /// Most frames whose counters can be in flight at once.
    pub const MAX_SLOTS: usize = 4;
    const BYTES: u64 = 64 + 16 * 2048;

    /// Records the copy of `counters` and this frame's timestamps into a free slot; returns the
    /// slot index to pass to [`Readbacks::map`] after submitting, or None when all are busy.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        counters: &wgpu::Buffer,
        timer: &Timer,
        frame: u64,
    ) -> Option<usize> {
        let index = match self.slots.iter().position(|s| !s.busy) {
            Some(i) => i,
            None if self.slots.len() < Self::MAX_SLOTS => {
                self.slots.push(Slot {
                    buffer: ctx.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("counter readback"),
                        size: Self::BYTES,
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    busy: false,
                    frame: 0,
                    passes: Vec::new(),
                    result: Arc::default(),
                });
                self.slots.len() - 1
            }
            None => return None,
        };
        let slot = &mut self.slots[index];
        encoder.copy_buffer_to_buffer(counters, 0, &slot.buffer, 0, Some(64));
        timer.resolve(encoder, &slot.buffer, 64);
        slot.busy = true;
        slot.frame = frame;
        slot.passes = timer.frame_passes();
        Some(index)
    }

    /// Starts the asynchronous map of slot `index` (call right after the submit).
    pub fn map(&mut self, index: usize) {
        let slot = &mut self.slots[index];
        let result = Arc::clone(&slot.result);
        if let Ok(mut r) = result.lock() {
            *r = None;
        }
        slot.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            if let Ok(mut guard) = result.lock() {
                *guard = Some(r);
            }
        });
    }

    /// Collects every slot whose map finished (call after `device.poll`), oldest frame first.
    pub fn collect(&mut self, timer: &Timer) -> Result<Vec<FrameStats>, GpuError> {
        let mut out = Vec::new();
        for slot in self.slots.iter_mut().filter(|s| s.busy) {
            let done = slot.result.lock().ok().and_then(|mut r| r.take());
            let Some(done) = done else { continue };
            slot.busy = false;
            done.map_err(|e| GpuError::Readback(e.to_string()))?;
            let stats = {
                let view = slot
                    .buffer
                    .get_mapped_range(..)
                    .map_err(|e| GpuError::Readback(e.to_string()))?;
                let c: GpuCounters = bytemuck::pod_read_unaligned(&view[..64]);
                let n = slot.passes.len() * 2;
                let ticks: Vec<u64> = view[64..64 + 8 * n]
                    .chunks_exact(8)
                    .map(bytemuck::pod_read_unaligned)
                    .collect();
                FrameStats {
                    frame: slot.frame,
                    vertex_count: c.vertex_count,
                    triangle_count: c.triangle_count,
                    overflow: c.overflow
                        & (super::types::OVERFLOW_VERTICES
                            | super::types::OVERFLOW_TRIANGLES
                            | super::types::OVERFLOW_BRICKS)
                        != 0,
                    area: c.area as f64,
                    volume: c.volume as f64,
                    timings: timer.stage_ms(&slot.passes, &ticks),
                    reached_bricks: c.reached_bricks,
                    brick_overflow: c.overflow & super::types::OVERFLOW_BRICKS != 0,
                    brick_slots: c.brick_slots,
                }
            };
            slot.buffer.unmap();
            out.push(stats);
        }
        out.sort_by_key(|s| s.frame);
        Ok(out)
    }

    /// True when any slot waits for its map.
    pub fn pending(&self) -> bool {
        self.slots.iter().any(|s| s.busy)
    }
}

/// A mappable buffer the engine's blocking readbacks (the mesh, test hooks) go through: kept
/// across frames and replaced, with a quarter to spare, only when a readback needs more.
#[derive(Debug, Default)]
pub struct Staging {
    buffer: Option<wgpu::Buffer>,
}

impl Staging {
    /// Copies the first `bytes` of each `(buffer, bytes)` (buffers need `COPY_SRC`) back to
    /// the host, in one submit and one map; returns one byte vector per part.
    pub fn read(
        &mut self,
        ctx: &GpuContext,
        parts: &[(&wgpu::Buffer, u64)],
    ) -> Result<Vec<Vec<u8>>, GpuError> {
        self.with_mapped(ctx, parts, |bytes| {
            bytes.iter().map(|b| b.to_vec()).collect()
        })
    }

    /// Copies the first `bytes` of each `(buffer, bytes)` into the staging buffer in one
    /// submit, maps it once and hands `read` the parts as slices of the mapped memory (each
    /// part starts at a multiple of 4 bytes), so a large readback is copied out only once.
    fn with_mapped<R>(
        &mut self,
        ctx: &GpuContext,
        parts: &[(&wgpu::Buffer, u64)],
        read: impl FnOnce(&[&[u8]]) -> R,
    ) -> Result<R, GpuError> {
        let sizes: Vec<u64> = parts.iter().map(|p| p.1.next_multiple_of(4)).collect();
        let total: u64 = sizes.iter().sum();
        if total == 0 {
            return Ok(read(&vec![&[][..]; parts.len()]));
        }
        if self.buffer.as_ref().is_none_or(|b| b.size() < total) {
            self.buffer = Some(ctx.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback staging"),
                size: (total + total / 4).next_multiple_of(256),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let Some(staging) = &self.buffer else {
            unreachable!("staging buffer created above")
        };
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = device.create_command_encoder(&Default::default());
        let mut at = 0;
        for ((src, _), &size) in parts.iter().zip(&sizes) {
            if size > 0 {
                encoder.copy_buffer_to_buffer(src, 0, staging, at, Some(size));
            }
            at += size;
        }
        ctx.queue.submit([encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            let msg = e
                .to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            return Err(GpuError::Readback(msg));
        }
        map_and_wait(device, staging, 0..total)?;
        let out = {
            let view = staging
                .get_mapped_range(0..total)
                .map_err(|e| GpuError::Readback(e.to_string()))?;
            let mut at = 0usize;
            let slices: Vec<&[u8]> = parts
                .iter()
                .zip(&sizes)
                .map(|((_, bytes), &size)| {
                    let part = &view[at..at + *bytes as usize];
                    at += size as usize;
                    part
                })
                .collect();
            read(&slices)
        };
        staging.unmap();
        Ok(out)
    }

    /// Reads `n` plain values of type `T` from the start of `src`.
    pub fn read_pod<T: bytemuck::Pod>(
        &mut self,
        ctx: &GpuContext,
        src: &wgpu::Buffer,
        n: u64,
    ) -> Result<Vec<T>, GpuError> {
        self.with_mapped(ctx, &[(src, n * size_of::<T>() as u64)], |parts| {
            pod_vec(parts[0], n)
        })
    }

    /// Reads the first `vertices` vertices and `triangles` triangles of `surface` into a
    /// [`Mesh`] (one copy, one map).
    pub fn read_mesh(
        &mut self,
        ctx: &GpuContext,
        surface: &GpuSurface,
        vertices: u32,
        triangles: u32,
    ) -> Result<Mesh, GpuError> {
        let v_bytes = vertices as u64 * size_of::<GpuVertex>() as u64;
        let i_bytes = 3 * triangles as u64 * 4;
        self.with_mapped(
            ctx,
            &[(&surface.vertices, v_bytes), (&surface.indices, i_bytes)],
            |parts| mesh_of_bytes(parts[0], parts[1]),
        )
    }
}

/// A [`Mesh`] straight from mapped vertex and index bytes: one pass over the vertices (split
/// into positions, normals and colours on every core) and one copy of the indices. Reading the
/// 7.5 M-triangle mesh of a million atoms back through two intermediate copies took most of a
/// GPU frame on an H100.
fn mesh_of_bytes(vertex_bytes: &[u8], index_bytes: &[u8]) -> Mesh {
    use rayon::prelude::*;
    use std::borrow::Cow;
    // Mapped memory is aligned in practice; a copy only if it is not.
    let verts: Cow<[GpuVertex]> = match bytemuck::try_cast_slice(vertex_bytes) {
        Ok(verts) => Cow::Borrowed(verts),
        Err(_) => Cow::Owned(pod_vec(
            vertex_bytes,
            (vertex_bytes.len() / size_of::<GpuVertex>()) as u64,
        )),
    };
    let indices = match bytemuck::try_cast_slice::<u8, u32>(index_bytes) {
        Ok(words) => words.to_vec(),
        Err(_) => pod_vec(index_bytes, (index_bytes.len() / 4) as u64),
    };
    Mesh {
        positions: verts.par_iter().map(|v| Vec3::from(v.position)).collect(),
        normals: verts.par_iter().map(|v| Vec3::from(v.normal)).collect(),
        colours: verts.par_iter().map(|v| v.colour).collect(),
        indices,
    }
}

fn pod_vec<T: bytemuck::Pod>(bytes: &[u8], n: u64) -> Vec<T> {
    bytes
        .chunks_exact(size_of::<T>())
        .take(n as usize)
        .map(bytemuck::pod_read_unaligned)
        .collect()
}

/// Blocking copy of `size` bytes at `offset` of `src` (needs `COPY_SRC`) back to the host.
pub fn read_bytes(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    src: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>, GpuError> {
    let size = size.next_multiple_of(4);
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(src, offset, &staging, 0, Some(size));
    queue.submit([encoder.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        let msg = e
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        return Err(GpuError::Readback(msg));
    }
    map_and_wait(device, &staging, 0..staging.size())?;
    let bytes = staging
        .get_mapped_range(..)
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Reads `n` plain values of type `T` from the start of `src`.
pub fn read_pod<T: bytemuck::Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    src: &wgpu::Buffer,
    n: u64,
) -> Result<Vec<T>, GpuError> {
    let bytes = read_bytes(device, queue, src, 0, n * size_of::<T>() as u64)?;
    Ok(pod_vec(&bytes, n))
}

/// Reads the first `vertices` vertices and `triangles` triangles of a surface into a [`Mesh`]
/// (any output set, not only the engine's current one).
pub fn read_mesh(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    surface: &GpuSurface,
    vertices: u32,
    triangles: u32,
) -> Result<Mesh, GpuError> {
    let v_bytes = vertices as u64 * size_of::<GpuVertex>() as u64;
    let verts = read_bytes(device, queue, &surface.vertices, 0, v_bytes)?;
    let indices = read_bytes(device, queue, &surface.indices, 0, 3 * triangles as u64 * 4)?;
    Ok(mesh_of_bytes(&verts[..v_bytes as usize], &indices))
}

/// Maps `range` of `staging` for reading and waits for the device until it is mapped.
fn map_and_wait(
    device: &wgpu::Device,
    staging: &wgpu::Buffer,
    range: std::ops::Range<u64>,
) -> Result<(), GpuError> {
    let result: MapResult = Arc::default();
    let r2 = Arc::clone(&result);
    staging.map_async(wgpu::MapMode::Read, range, move |r| {
        if let Ok(mut g) = r2.lock() {
            *g = Some(r);
        }
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Device(e.to_string()))?;
    let done = result.lock().ok().and_then(|mut r| r.take());
    match done {
        Some(Ok(())) => Ok(()),
        Some(Err(e)) => Err(GpuError::Readback(e.to_string())),
        None => Err(GpuError::Readback("map did not complete".into())),
    }
}
