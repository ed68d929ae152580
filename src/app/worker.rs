//! The compute worker: one background thread that reads a frame, turns it into particles
//! (atoms or beads) and runs the surface engine, so the UI thread never waits for I/O or for a
//! surface. Requests replace each other (latest wins): when computing falls behind playback,
//! the frames in between are dropped instead of queueing up. With the GPU engine on the
//! window's device ([`Engine::Gpu`]) the mesh stays on the GPU: the reply carries the engine's
//! [`GpuSurface`] buffers for the renderer and the counters (triangles, area, volume) that came
//! back with the frame; a frame that overflowed its buffers is submitted again. The worker tells
//! the GPU engine only what changed since its last frame (frame, radii, colours; the engine
//! compares the parameters), so an isovalue change re-runs only Marching Cubes and a colour
//! scheme only the colour pass.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use glam::Vec3;

use super::source::FrameSource;
use crate::gpu::{Changes, GpuEngine, GpuSurface, Work};
use crate::model::{ParticleOptions, Particles};
use crate::render::guess_bonds;
use crate::surface::{AtomSet, Mesh, SurfaceEngine, SurfaceOutput, SurfaceParams};

/// Frames kept in the worker's cache (around the playhead; oldest evicted first).
const FRAME_CACHE: usize = 16;

/// One unit of work: the surface of `frame` of `source`.
#[derive(Clone)]
pub struct Request {
    /// Increases whenever the data, particles or parameters change; replies carry it back.
    pub generation: u64,
    /// Frame index.
    pub frame: usize,
    /// The trajectory.
    pub source: Arc<dyn FrameSource>,
    /// Surface parameters.
    pub params: SurfaceParams,
    /// Atoms or beads, radii and colours.
    pub options: ParticleOptions,
}

/// Particles of one computed frame, for drawing atoms or beads.
#[derive(Debug, Clone)]
pub struct ParticleData {
    /// Positions in Å.
    pub positions: Vec<Vec3>,
    /// Radii in Å.
    pub radii: Arc<Vec<f32>>,
    /// Linear RGB colours.
    pub colours: Arc<Vec<[f32; 3]>>,
    /// Bonds between particles (file bonds or guessed; empty for beads).
    pub bonds: Arc<Vec<[u32; 2]>>,
}

/// A finished surface.
#[derive(Debug, Clone)]
pub struct Computed {
    /// Generation of the request.
    pub generation: u64,
    /// Frame index.
    pub frame: usize,
    /// Simulation time in ps, when known.
    pub time_ps: Option<f64>,
    /// Mesh, area, volume, stage times. With the GPU engine the mesh is empty: the surface is
    /// in [`Computed::gpu_surface`].
    pub output: SurfaceOutput,
    /// The GPU engine's surface buffers (drawn in place), when the GPU engine computed it.
    pub gpu_surface: Option<GpuSurface>,
    /// The particles the surface was built from.
    pub particles: ParticleData,
    /// True when the particles are residue beads.
    pub beads: bool,
    /// Time to read the frame in ms.
    pub read_ms: f64,
    /// Which stages the GPU engine ran for this reply (its last submit; `None` for host
    /// engines). An isovalue change alone gives [`Work::Mc`].
    pub gpu_work: Option<Work>,
}

/// What the worker sends back.
#[derive(Debug, Clone)]
pub enum Reply {
    /// A surface.
    Done(Box<Computed>),
    /// The request failed; the message is one line.
    Failed {
        /// Generation of the request.
        generation: u64,
        /// Frame index.
        frame: usize,
        /// What went wrong.
        message: String,
    },
}

impl Computed {
    /// Triangles of the surface (from the GPU counters when the mesh stayed on the GPU).
    pub fn triangle_count(&self) -> usize {
        match &self.gpu_surface {
            Some(g) => g.stats.map_or(0, |s| s.triangle_count as usize),
            None => self.output.mesh.triangle_count(),
        }
    }
}

/// The engine the worker runs.
pub enum Engine {
    /// Any engine through [`SurfaceEngine::compute`] (the mesh comes back to the host).
    Host(Box<dyn SurfaceEngine + Send>),
    /// The GPU engine on the window's device: the mesh stays in its buffers.
    Gpu(Box<GpuEngine>),
}

impl Engine {
    /// Name of the engine (`cpu`, `gpu`).
    pub fn name(&self) -> &str {
        match self {
            Engine::Host(e) => e.name(),
            Engine::Gpu(e) => e.name(),
        }
    }

    /// Computes one surface. For [`Engine::Gpu`] it submits the frame, waits for its counters
    /// (resubmitting after an overflow, see [`GpuEngine::run_blocking`]) and returns an empty
    /// mesh plus the surface buffers.
    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        changes: Changes,
    ) -> Result<(SurfaceOutput, Option<GpuSurface>, Option<Work>), String> {
        match self {
            Engine::Host(e) => e
                .compute(atoms, params)
                .map(|o| (o, None, None))
                .map_err(|e| e.to_string()),
            Engine::Gpu(e) => {
                let stats = e
                    .run_blocking(atoms, params, changes)
                    .map_err(|e| e.to_string())?;
                let mut surface = e.surface();
                surface.stats = Some(stats);
                let output = SurfaceOutput {
                    grid: surface.grid,
                    mesh: Mesh::default(),
                    area: stats.area,
                    volume: stats.volume,
                    timings: stats.timings,
                };
                Ok((output, Some(surface), e.last_frame().map(|f| f.work)))
            }
        }
    }
}

type Slot = Arc<(Mutex<Option<Request>>, Condvar)>;

/// Handle to the worker thread. Dropping it stops the thread after its current job.
pub struct Worker {
    slot: Slot,
    replies: Receiver<Reply>,
    busy: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    engine_name: String,
}

impl Worker {
    /// Starts the worker with `engine`; `notify` is called after each reply (to wake the UI).
    pub fn spawn(engine: Box<dyn SurfaceEngine + Send>, notify: Box<dyn Fn() + Send>) -> Worker {
        Self::spawn_engine(Engine::Host(engine), notify)
    }

    /// Like [`Worker::spawn`] for either kind of [`Engine`].
    pub fn spawn_engine(engine: Engine, notify: Box<dyn Fn() + Send>) -> Worker {
        let slot: Slot = Arc::new((Mutex::new(None), Condvar::new()));
        let (tx, replies) = channel();
        let busy = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let engine_name = engine.name().to_string();
        let (s, b, st) = (slot.clone(), busy.clone(), stop.clone());
        std::thread::Builder::new()
            .name("mdsurf compute".into())
            .spawn(move || run(engine, s, tx, b, st, notify))
            .ok();
        Worker {
            slot,
            replies,
            busy,
            stop,
            engine_name,
        }
    }

    /// Queues `request`, replacing any request not yet started.
    pub fn submit(&self, request: Request) {
        let (lock, cv) = &*self.slot;
        if let Ok(mut pending) = lock.lock() {
            *pending = Some(request);
            self.busy.store(true, Ordering::SeqCst);
            cv.notify_one();
        }
    }

    /// The next reply, if one is ready (never blocks).
    pub fn try_recv(&self) -> Option<Reply> {
        self.replies.try_recv().ok()
    }

    /// Waits up to `timeout` for the next reply (for scripted runs and tests).
    pub fn recv_timeout(&self, timeout: std::time::Duration) -> Option<Reply> {
        self.replies.recv_timeout(timeout).ok()
    }

    /// True while a request is queued or running.
    pub fn is_busy(&self) -> bool {
        self.busy.load(Ordering::SeqCst)
    }

    /// Name of the engine (`cpu`, `gpu`).
    pub fn engine_name(&self) -> &str {
        &self.engine_name
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        self.slot.1.notify_all();
    }
}

/// Per-source state the worker keeps between requests.
struct Cache {
    source: Option<Arc<dyn FrameSource>>,
    frames: HashMap<usize, crate::model::Frame>,
    order: Vec<usize>,
    particles: Option<(ParticleOptions, Arc<Particles>, ParticleData)>,
    atom_bonds: Option<Arc<Vec<[u32; 2]>>>,
    /// What the engine's last frame was computed from, to send it only what changed since.
    sent: Option<Sent>,
}

/// Inputs of the engine's last successful frame (of the cached source).
struct Sent {
    /// Frame index: positions follow from it and the particle kind.
    frame: usize,
    /// Residue beads or atoms.
    beads: bool,
    radii: Arc<Vec<f32>>,
    colours: Arc<Vec<[f32; 3]>>,
}

impl Sent {
    /// What differs between this and the next frame's inputs (the surface parameters are
    /// compared by the engine itself).
    fn changes(&self, frame: usize, beads: bool, data: &ParticleData) -> Changes {
        Changes {
            positions: self.frame != frame || self.beads != beads,
            radii: !Arc::ptr_eq(&self.radii, &data.radii) && self.radii != data.radii,
            colours: !Arc::ptr_eq(&self.colours, &data.colours) && self.colours != data.colours,
        }
    }
}

fn run(
    mut engine: Engine,
    slot: Slot,
    tx: Sender<Reply>,
    busy: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    notify: Box<dyn Fn() + Send>,
) {
    let mut cache = Cache {
        source: None,
        frames: HashMap::new(),
        order: Vec::new(),
        particles: None,
        atom_bonds: None,
        sent: None,
    };
    loop {
        let request = {
            let (lock, cv) = &*slot;
            let Ok(mut pending) = lock.lock() else { return };
            loop {
                if stop.load(Ordering::SeqCst) {
                    return;
                }
                if let Some(r) = pending.take() {
                    break r;
                }
                pending = match cv.wait(pending) {
                    Ok(p) => p,
                    Err(_) => return,
                };
            }
        };
        let (generation, frame) = (request.generation, request.frame);
        let reply = match compute(&mut engine, &mut cache, &request) {
            Ok(c) => Reply::Done(Box::new(c)),
            Err(message) => Reply::Failed {
                generation,
                frame,
                message,
            },
        };
        if let Ok(pending) = slot.0.lock() {
            busy.store(pending.is_some(), Ordering::SeqCst);
        }
        if tx.send(reply).is_err() {
            return;
        }
        notify();
    }
}

fn frame_of(cache: &mut Cache, req: &Request) -> Result<(crate::model::Frame, f64), String> {
    let same = cache
        .source
        .as_ref()
        .is_some_and(|s| Arc::ptr_eq(s, &req.source));
    if !same {
        cache.source = Some(req.source.clone());
        cache.frames.clear();
        cache.order.clear();
        cache.particles = None;
        cache.sent = None;
        cache.atom_bonds = None;
    }
    if let Some(f) = cache.frames.get(&req.frame) {
        return Ok((f.clone(), 0.0));
    }
    let t = Instant::now();
    let frame = req.source.read_frame(req.frame)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    if cache.order.len() >= FRAME_CACHE {
        let old = cache.order.remove(0);
        cache.frames.remove(&old);
    }
    cache.order.push(req.frame);
    cache.frames.insert(req.frame, frame.clone());
    Ok((frame, ms))
}

fn compute(engine: &mut Engine, cache: &mut Cache, req: &Request) -> Result<Computed, String> {
    let (frame, read_ms) = frame_of(cache, req)?;
    let topology = req.source.topology();
    let rebuild = cache
        .particles
        .as_ref()
        .is_none_or(|(o, _, _)| *o != req.options);
    if rebuild {
        let particles = Particles::new(topology, &frame, &req.options)
            .map_err(|e| format!("frame {}: {e}", req.frame))?;
        let bonds = if particles.is_beads() {
            Arc::new(Vec::new())
        } else {
            cache
                .atom_bonds
                .get_or_insert_with(|| {
                    Arc::new(if topology.bonds.is_empty() {
                        guess_bonds(&frame.positions, particles.radii())
                    } else {
                        topology.bonds.clone()
                    })
                })
                .clone()
        };
        let data = ParticleData {
            positions: Vec::new(),
            radii: Arc::new(particles.radii().to_vec()),
            colours: Arc::new(particles.colours().to_vec()),
            bonds,
        };
        cache.particles = Some((req.options.clone(), Arc::new(particles), data));
    }
    let Some((_, particles, data)) = cache.particles.as_ref() else {
        return Err("internal: particles missing".into());
    };
    let mut positions = Vec::new();
    particles
        .positions_into(&frame, &mut positions)
        .map_err(|e| format!("frame {}: {e}", req.frame))?;
    // Send the engine only what changed since its last frame: an isovalue change alone
    // re-runs Marching Cubes, a colour scheme the colour pass (parameters it compares itself).
    let changes = match cache.sent.take() {
        Some(sent) => sent.changes(req.frame, particles.is_beads(), data),
        None => Changes::ALL,
    };
    let (output, gpu_surface, gpu_work) = engine
        .compute(&particles.atom_set(&positions), &req.params, changes)
        .map_err(|e| format!("frame {}: {e}", req.frame))?;
    cache.sent = Some(Sent {
        frame: req.frame,
        beads: particles.is_beads(),
        radii: data.radii.clone(),
        colours: data.colours.clone(),
    });
    Ok(Computed {
        generation: req.generation,
        frame: req.frame,
        time_ps: frame.time_ps,
        output,
        gpu_surface,
        particles: ParticleData {
            positions,
            ..data.clone()
        },
        beads: particles.is_beads(),
        read_ms,
        gpu_work,
    })
}
