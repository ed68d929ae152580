//! The compute worker: one background thread that reads a frame, turns it into the particles of
//! each representation (atoms or beads of its selection) and runs the surface engine for each
//! visible surface representation, so the UI thread never waits for I/O or for a surface.
//! Requests replace each other (latest wins): when computing falls behind playback, the frames
//! in between are dropped instead of queueing up.
//!
//! Each representation keeps its own slot between requests: its bound selection, its particles,
//! its last result and, with the GPU engine, its own [`GpuEngine`] on the window's device (so
//! every surface keeps its own buffers and all share one device). A representation whose inputs
//! did not change (same frame, selection, style, colours and parameters) reuses its last result,
//! so a change to one representation recomputes that one only; and the worker tells its GPU
//! engine only what changed since its last frame (frame, radii, colours; the engine compares the
//! parameters), so an isovalue change re-runs only Marching Cubes and a colour scheme only the
//! colour pass. With the GPU engine the mesh stays on the GPU: the reply carries the engine's
//! [`GpuSurface`] buffers for the renderer and the counters (triangles, area, volume).
//!
//! The GPU path never blocks the window and never times stages: every surface of a request is
//! submitted first ([`GpuEngine::submit`], one submit each, while the window keeps drawing the
//! previous frame), then their counters are collected ([`GpuEngine::wait_stats`]); a surface
//! that overflowed its mesh buffers is submitted again with nothing changed, so only Marching
//! Cubes re-runs, with grown buffers. The engine alternates between two output sets, so the
//! surface on screen is never the one being written; before writing again into the set the
//! window may still draw, the worker waits until the window has taken the previous reply
//! (`Worker::try_recv`), so what is drawn (surface, atoms, readouts) belongs to one frame.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use glam::Vec3;

use super::source::FrameSource;
use crate::gpu::{Changes, GpuEngine, GpuSurface, Work};
use crate::model::{ParticleOptions, RadiusOverrides};
use crate::scene::layer::{Layer, LayerFrame};
use crate::scene::representation::{RepStyle, Representation};
use crate::surface::{
    AtomSet, Mesh, MeshCounts, SurfaceEngine, SurfaceOutput, SurfaceParams, VertexMode,
};

/// Frames kept in the worker's cache (around the playhead; oldest evicted first).
const FRAME_CACHE: usize = 16;

/// A representation as the worker gets it: a stable id (slots and GPU engines are kept per id,
/// so reordering or renaming representations recomputes nothing) and the representation.
#[derive(Debug, Clone, PartialEq)]
pub struct RepRequest {
    /// Stable identity of the representation for the life of the window.
    pub id: u64,
    /// The representation (hidden ones are not computed).
    pub rep: Representation,
}

/// One unit of work: the representations of `frame` of `source`.
#[derive(Clone)]
pub struct Request {
    /// Increases whenever the data, representations or parameters change; replies carry it back.
    pub generation: u64,
    /// Frame index.
    pub frame: usize,
    /// The trajectory.
    pub source: Arc<dyn FrameSource>,
    /// The representations, in drawing order.
    pub reps: Vec<RepRequest>,
    /// Radius overrides (Å per element or type) for every representation.
    pub radius_overrides: RadiusOverrides,
}

impl Request {
    /// A request for one surface representation of every atom with `params` and `options`
    /// (beads, colours, radius overrides), as the viewer computed before representations.
    pub fn single(
        generation: u64,
        frame: usize,
        source: Arc<dyn FrameSource>,
        params: SurfaceParams,
        options: ParticleOptions,
    ) -> Request {
        let style = if options.beads {
            RepStyle::Beads
        } else {
            RepStyle::Surface
        };
        let mut rep = Representation::new("all", "all", style);
        rep.set_params(&params);
        rep.colour = options.colours;
        Request {
            generation,
            frame,
            source,
            reps: vec![RepRequest { id: 0, rep }],
            radius_overrides: options.radius_overrides,
        }
    }
}

/// Particles of one computed representation, for drawing atoms or beads.
#[derive(Debug, Clone)]
pub struct ParticleData {
    /// Positions in Å.
    pub positions: Vec<Vec3>,
    /// Radii in Å.
    pub radii: Arc<Vec<f32>>,
    /// Linear RGB colours.
    pub colours: Arc<Vec<[f32; 3]>>,
    /// Bonds between particles (file bonds or guessed; empty for beads and surfaces).
    pub bonds: Arc<Vec<[u32; 2]>>,
}

/// One representation of a finished frame.
#[derive(Debug, Clone)]
pub struct LayerResult {
    /// The representation's id ([`RepRequest::id`]).
    pub id: u64,
    /// The representation as it was computed.
    pub rep: Representation,
    /// Mesh, area, volume, stage times (empty for atom styles). With the GPU engine the mesh is
    /// empty: the surface is in [`LayerResult::gpu_surface`].
    pub output: SurfaceOutput,
    /// The GPU engine's surface buffers (drawn in place), when the GPU engine computed it.
    pub gpu_surface: Option<GpuSurface>,
    /// The particles the surface or atoms were built from.
    pub particles: ParticleData,
    /// True when the particles are residue beads.
    pub beads: bool,
    /// Which stages the GPU engine ran for this representation (its last submit; `None` for
    /// host engines or a reused result). An isovalue change alone gives [`Work::Mc`].
    pub gpu_work: Option<Work>,
    /// True when this result was reused from an earlier request (nothing recomputed).
    pub reused: bool,
}

impl LayerResult {
    /// Triangles of the surface (from the GPU counters when the mesh stayed on the GPU).
    pub fn triangle_count(&self) -> usize {
        match &self.gpu_surface {
            Some(g) => g.stats.map_or(0, |s| s.triangle_count as usize),
            None => self.output.mesh.triangle_count(),
        }
    }

    /// True for surface representations.
    pub fn is_surface(&self) -> bool {
        self.rep.style.is_surface()
    }
}

/// A finished frame: every visible representation.
#[derive(Debug, Clone)]
pub struct Computed {
    /// Generation of the request.
    pub generation: u64,
    /// Frame index.
    pub frame: usize,
    /// Simulation time in ps, when known.
    pub time_ps: Option<f64>,
    /// Time to read the frame in ms.
    pub read_ms: f64,
    /// Wall-clock time the worker spent on this request in ms: reading, particles, and every
    /// surface submitted and its counters waited for (not the wait for the window to take the
    /// previous reply).
    pub compute_ms: f64,
    /// GPU memory the worker's surface engines hold after this frame, in bytes (0 on the host
    /// engines).
    pub gpu_bytes: u64,
    /// The visible representations, in drawing order (shared with the worker's cache).
    pub layers: Vec<Arc<LayerResult>>,
}

impl Computed {
    /// The surface representations.
    pub fn surfaces(&self) -> impl Iterator<Item = &LayerResult> {
        self.layers
            .iter()
            .map(Arc::as_ref)
            .filter(|l| l.is_surface())
    }

    /// Triangles of every surface together.
    pub fn triangle_count(&self) -> usize {
        self.surfaces().map(LayerResult::triangle_count).sum()
    }

    /// The result of representation `id`, when it is visible.
    pub fn layer(&self, id: u64) -> Option<&LayerResult> {
        self.layers.iter().map(Arc::as_ref).find(|l| l.id == id)
    }
}

/// What the worker sends back.
#[derive(Debug, Clone)]
pub enum Reply {
    /// A frame's representations.
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

/// The engine the worker runs.
pub enum Engine {
    /// Any engine through [`SurfaceEngine::compute`] (the mesh comes back to the host); one
    /// engine serves every representation.
    Host(Box<dyn SurfaceEngine + Send>),
    /// The GPU engine on the window's device: the mesh stays in its buffers. Each further
    /// surface representation gets its own engine on the same device.
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
}

/// A new GPU engine on the same device as `engine` (for a further surface representation).
fn sibling_of(engine: &GpuEngine) -> Box<GpuEngine> {
    let ctx = engine.context();
    Box::new(GpuEngine::from_device(
        ctx.device.clone(),
        ctx.queue.clone(),
    ))
}

/// Computes one surface on a host engine (the mesh comes back to the host).
fn compute_on_host(
    e: &mut (dyn SurfaceEngine + Send),
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    vertices: VertexMode,
) -> Result<SurfaceOutput, String> {
    e.set_vertices(vertices);
    e.compute(atoms, params).map_err(|e| e.to_string())
}

/// Collects a surface submitted on `e` as frame `frame` ([`GpuEngine::finish`]: counters
/// waited for, overflows re-run as Marching Cubes only) and returns the readouts and buffers.
fn collect_gpu(
    e: &mut GpuEngine,
    frame: u64,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<(SurfaceOutput, GpuSurface), String> {
    let stats = e.finish(frame, atoms, params).map_err(|e| e.to_string())?;
    let mut surface = e.surface();
    surface.stats = Some(stats);
    let output = SurfaceOutput {
        grid: surface.grid,
        mesh: Mesh::default(),
        area: stats.area,
        volume: stats.volume,
        timings: stats.timings,
        // The mesh stays in the engine's buffers.
        counts_without_mesh: Some(MeshCounts {
            vertices: stats.vertex_count as usize,
            triangles: stats.triangle_count as usize,
        }),
    };
    Ok((output, surface))
}

/// A surface submitted to a GPU engine whose counters are not collected yet.
struct Submitted {
    /// The engine's frame number.
    frame: u64,
    /// Which stages the submit ran.
    work: Work,
}

/// A representation's result while a request is computed: reused as it was, or new (with a
/// GPU submit still to collect).
enum Entry {
    Reused(Arc<LayerResult>),
    New(Box<LayerResult>, Option<Submitted>),
}

/// The GPU engine of representation `id`, when the worker runs the GPU engine.
fn gpu_engine_of<'a>(
    engine: &'a mut Engine,
    cache: &'a mut Cache,
    id: u64,
) -> Option<&'a mut GpuEngine> {
    let Engine::Gpu(main) = engine else {
        return None;
    };
    if cache.main_engine_owner == Some(id) {
        Some(main.as_mut())
    } else {
        cache.slots.get_mut(&id)?.gpu.as_deref_mut()
    }
}

/// Tells each GPU engine behind a surface of `c` (about to be sent to the window) that its
/// output set is now on screen, so that no later frame writes it, even one that fails.
fn hold_shown_sets(engine: &mut Engine, cache: &mut Cache, c: &Computed) {
    for layer in c.layers.iter().filter(|l| l.gpu_surface.is_some()) {
        if let Some(e) = gpu_engine_of(engine, cache, layer.id) {
            e.hold_output_set();
        }
    }
}

type Slot = Arc<(Mutex<Option<Request>>, Condvar)>;

/// How many replies the window has taken, so the worker knows when an output set is no longer
/// drawn.
type Taken = Arc<(Mutex<u64>, Condvar)>;

/// Handle to the worker thread. Dropping it stops the thread after its current job.
pub struct Worker {
    slot: Slot,
    replies: Receiver<Reply>,
    taken: Taken,
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
        let taken: Taken = Arc::default();
        let channel = Channel {
            tx,
            taken: taken.clone(),
            sent: 0,
        };
        let (s, b, st) = (slot.clone(), busy.clone(), stop.clone());
        std::thread::Builder::new()
            .name("mdsurf compute".into())
            .spawn(move || run(engine, s, channel, b, st, notify))
            .ok();
        Worker {
            slot,
            replies,
            taken,
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

    /// The next reply, if one is ready (never blocks). Taking a reply tells the worker that
    /// the window no longer draws the GPU buffers of the reply before it.
    pub fn try_recv(&self) -> Option<Reply> {
        self.took(self.replies.try_recv().ok())
    }

    /// Waits up to `timeout` for the next reply (for scripted runs and tests).
    pub fn recv_timeout(&self, timeout: std::time::Duration) -> Option<Reply> {
        self.took(self.replies.recv_timeout(timeout).ok())
    }

    fn took(&self, reply: Option<Reply>) -> Option<Reply> {
        if reply.is_some()
            && let Ok(mut n) = self.taken.0.lock()
        {
            *n += 1;
            self.taken.1.notify_all();
        }
        reply
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

/// What one representation keeps between requests.
struct RepSlot {
    /// The bound selection and its particles.
    layer: Layer,
    /// Its own GPU engine (GPU backend only; the first representation uses the main engine).
    gpu: Option<Box<GpuEngine>>,
    /// The inputs and result of its last successful frame (shared with the reply, not copied).
    last: Option<(usize, Arc<LayerResult>)>,
    /// What its engine's last frame was computed from, to send only what changed since.
    sent: Option<Sent>,
}

/// Per-source state the worker keeps between requests.
struct Cache {
    source: Option<Arc<dyn FrameSource>>,
    frames: HashMap<usize, Arc<crate::model::Frame>>,
    order: Vec<usize>,
    radius_overrides: RadiusOverrides,
    slots: HashMap<u64, RepSlot>,
    /// The id of the representation computing on the main GPU engine.
    main_engine_owner: Option<u64>,
    /// The CPU engine of periodic surfaces (`--periodic`), whatever the main engine.
    periodic: crate::surface::periodic::PeriodicEngine,
}

/// Inputs of an engine's last successful frame.
struct Sent {
    /// Frame index: positions follow from it and the particles.
    frame: usize,
    /// Which atoms the particles were (`None`: all) and whether they were beads.
    atoms: (Option<Vec<u32>>, bool),
    radii: Arc<Vec<f32>>,
    colours: Arc<Vec<[f32; 3]>>,
}

/// Which atoms `lf`'s particles come from, and whether they are beads.
fn atoms_key(lf: &LayerFrame) -> (Option<Vec<u32>>, bool) {
    (
        lf.particles.subset().map(<[u32]>::to_vec),
        lf.particles.is_beads(),
    )
}

impl Sent {
    /// What differs between this and the next frame's inputs (the surface parameters are
    /// compared by the engine itself).
    fn changes(&self, frame: usize, lf: &LayerFrame, data: &ParticleData) -> Changes {
        let same_atoms = !lf.rebuilt || self.atoms == atoms_key(lf);
        Changes {
            positions: self.frame != frame || !same_atoms,
            radii: !Arc::ptr_eq(&self.radii, &data.radii) && self.radii != data.radii,
            colours: !Arc::ptr_eq(&self.colours, &data.colours) && self.colours != data.colours,
        }
    }
}

/// The parts of a representation that change what is computed (not its name, opacity or
/// visibility, which only change how it is drawn).
fn compute_key(rep: &Representation) -> impl PartialEq + '_ {
    (
        &rep.selection,
        rep.style,
        rep.colour,
        rep.style.is_surface().then(|| (rep.params(), rep.vertices)),
    )
}

/// The worker's end of the reply channel, counting what it sent against what was taken.
struct Channel {
    tx: Sender<Reply>,
    taken: Taken,
    sent: u64,
}

impl Channel {
    /// Waits until the window has taken every reply sent (or `stop`): after that, no output
    /// set of an earlier reply but the last is drawn, so the engines may write into it again.
    fn wait_taken(&self, stop: &AtomicBool) {
        let Ok(mut n) = self.taken.0.lock() else {
            return;
        };
        while *n < self.sent && !stop.load(Ordering::SeqCst) {
            n = match self
                .taken
                .1
                .wait_timeout(n, std::time::Duration::from_millis(50))
            {
                Ok((n, _)) => n,
                Err(_) => return,
            };
        }
    }
}

fn run(
    mut engine: Engine,
    slot: Slot,
    mut channel: Channel,
    busy: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    notify: Box<dyn Fn() + Send>,
) {
    let mut cache = Cache {
        source: None,
        frames: HashMap::new(),
        order: Vec::new(),
        radius_overrides: RadiusOverrides::default(),
        slots: HashMap::new(),
        main_engine_owner: None,
        periodic: Default::default(),
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
        if matches!(engine, Engine::Gpu(_)) {
            channel.wait_taken(&stop);
        }
        let reply = match compute(&mut engine, &mut cache, &request) {
            Ok(c) => {
                hold_shown_sets(&mut engine, &mut cache, &c);
                Reply::Done(Box::new(c))
            }
            Err(message) => Reply::Failed {
                generation,
                frame,
                message,
            },
        };
        if let Ok(pending) = slot.0.lock() {
            busy.store(pending.is_some(), Ordering::SeqCst);
        }
        if channel.tx.send(reply).is_err() {
            return;
        }
        channel.sent += 1;
        notify();
    }
}

fn frame_of(cache: &mut Cache, req: &Request) -> Result<(Arc<crate::model::Frame>, f64), String> {
    let same = cache
        .source
        .as_ref()
        .is_some_and(|s| Arc::ptr_eq(s, &req.source));
    if !same || cache.radius_overrides != req.radius_overrides {
        if !same {
            cache.frames.clear();
            cache.order.clear();
        }
        cache.source = Some(req.source.clone());
        cache.radius_overrides = req.radius_overrides.clone();
        // Keep the GPU engines (they are expensive to build); forget what they computed.
        for slot in cache.slots.values_mut() {
            slot.last = None;
            slot.sent = None;
        }
        let topology = req.source.topology();
        let overrides = req.radius_overrides.clone();
        cache.slots.retain(
            |_, s| match Layer::new(s.layer.rep().clone(), topology, &overrides) {
                Ok(layer) => {
                    s.layer = layer;
                    true
                }
                Err(_) => false,
            },
        );
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
    let started = Instant::now();
    let (frame, read_ms) = frame_of(cache, req)?;
    let topology = req.source.topology();
    // Forget representations that are gone (their GPU engines are dropped with them).
    let wanted: Vec<u64> = req.reps.iter().map(|r| r.id).collect();
    cache.slots.retain(|id, _| wanted.contains(id));
    if cache
        .main_engine_owner
        .is_some_and(|id| !cache.slots.contains_key(&id))
    {
        cache.main_engine_owner = None;
    }
    // First every representation: host surfaces computed, GPU surfaces only submitted.
    let mut entries = Vec::new();
    for RepRequest { id, rep } in req.reps.iter().filter(|r| r.rep.visible) {
        let slot = match cache.slots.get_mut(id) {
            // Same selection: keep the binding, the engine and what it was last sent.
            Some(s) if s.layer.rep().selection == rep.selection => {
                s.layer.set_rep(rep.clone());
                s
            }
            _ => {
                let layer = Layer::new(rep.clone(), topology, &req.radius_overrides)
                    .map_err(|e| e.to_string())?;
                let old = cache.slots.remove(id);
                let gpu = old.and_then(|o| o.gpu);
                cache.slots.insert(
                    *id,
                    RepSlot {
                        layer,
                        gpu,
                        last: None,
                        sent: None,
                    },
                );
                cache.slots.get_mut(id).ok_or("internal: slot missing")?
            }
        };
        if let Some((f, last)) = &slot.last
            && *f == req.frame
            && !slot.layer.is_dynamic()
            && compute_key(&last.rep) == compute_key(rep)
        {
            entries.push(Entry::Reused(Arc::new(LayerResult {
                rep: rep.clone(),
                reused: true,
                gpu_work: None,
                ..(**last).clone()
            })));
            continue;
        }
        let lf = slot
            .layer
            .frame(topology, &frame)
            .map_err(|e| format!("frame {}: {e}", req.frame))?;
        // The particles' radii and colours change only when they were rebuilt (radii that
        // follow exposure: every frame): otherwise keep the same Arcs (no copy per frame, and
        // the engine sees no change).
        let last = slot
            .last
            .as_ref()
            .map(|(_, l)| &l.particles)
            .filter(|_| !lf.rebuilt);
        let radii = match last {
            Some(l) if lf.frame_radii.is_none() => l.radii.clone(),
            _ => Arc::new(lf.radii().to_vec()),
        };
        let colours = match last {
            Some(l) => l.colours.clone(),
            None => Arc::new(lf.particles.colours().to_vec()),
        };
        let mut submitted = None;
        let mut result = LayerResult {
            id: *id,
            rep: rep.clone(),
            output: SurfaceOutput::default(),
            gpu_surface: None,
            particles: ParticleData {
                positions: Vec::new(),
                radii,
                colours,
                bonds: lf.bonds.clone(),
            },
            beads: lf.particles.is_beads(),
            gpu_work: None,
            reused: false,
        };
        if rep.style.is_surface()
            && !lf.positions.is_empty()
            && let Some(replicate) = req.source.periodic()
        {
            // Periodic surfaces come from the CPU periodic engine for every backend.
            result.output = cache
                .periodic
                .compute_in_cell(
                    frame.cell.as_ref(),
                    &lf.atom_set(),
                    &rep.params(),
                    replicate,
                )
                .map_err(|e| format!("frame {}: representation '{}': {e}", req.frame, rep.name))?;
            slot.sent = None;
        } else if rep.style.is_surface() && !lf.positions.is_empty() {
            let changes = match slot.sent.take() {
                Some(sent) => sent.changes(req.frame, &lf, &result.particles),
                None => Changes::ALL,
            };
            let failed =
                |e: String| format!("frame {}: representation '{}': {e}", req.frame, rep.name);
            let atoms = lf.atom_set();
            match engine {
                Engine::Host(e) => {
                    result.output =
                        compute_on_host(e.as_mut(), &atoms, &rep.params(), rep.vertices)
                            .map_err(failed)?;
                }
                Engine::Gpu(main) => {
                    // The main engine serves one representation (one that never had an engine
                    // of its own, so its change tracking stays valid); each other gets its own.
                    if cache.main_engine_owner.is_none() && slot.gpu.is_none() {
                        cache.main_engine_owner = Some(*id);
                    }
                    let e = if cache.main_engine_owner == Some(*id) {
                        main.as_mut()
                    } else {
                        slot.gpu.get_or_insert_with(|| sibling_of(main)).as_mut()
                    };
                    e.set_vertices(rep.vertices);
                    let info = e
                        .submit(&atoms, &rep.params(), changes)
                        .map_err(|e| failed(e.to_string()))?;
                    submitted = Some(Submitted {
                        frame: info.frame,
                        work: info.work,
                    });
                }
            }
            slot.sent = Some(Sent {
                frame: req.frame,
                atoms: atoms_key(&lf),
                radii: result.particles.radii.clone(),
                colours: result.particles.colours.clone(),
            });
        }
        result.particles.positions = lf.positions;
        entries.push(Entry::New(Box::new(result), submitted));
    }
    // Then the GPU counters, in the same order; each result is kept for reuse.
    let mut layers = Vec::with_capacity(entries.len());
    for entry in entries {
        let (mut result, submitted) = match entry {
            Entry::Reused(r) => {
                layers.push(r);
                continue;
            }
            Entry::New(r, s) => (r, s),
        };
        let id = result.id;
        if let Some(Submitted { frame: f, work }) = submitted {
            let e = gpu_engine_of(engine, cache, id).ok_or("internal: GPU engine missing")?;
            let p = &result.particles;
            let atoms = AtomSet {
                positions: &p.positions,
                radii: &p.radii,
                colours: Some(&p.colours),
            };
            match collect_gpu(e, f, &atoms, &result.rep.params()) {
                Ok((output, surface)) => {
                    result.output = output;
                    result.gpu_surface = Some(surface);
                    result.gpu_work = Some(work);
                }
                Err(message) => {
                    if let Some(slot) = cache.slots.get_mut(&id) {
                        slot.sent = None;
                    }
                    return Err(format!(
                        "frame {}: representation '{}': {message}",
                        req.frame, result.rep.name
                    ));
                }
            }
        }
        let result: Arc<LayerResult> = Arc::from(result);
        if let Some(slot) = cache.slots.get_mut(&id) {
            slot.last = Some((req.frame, result.clone()));
        }
        layers.push(result);
    }
    let main_bytes = match engine {
        Engine::Gpu(e) => e.gpu_bytes(),
        Engine::Host(_) => 0,
    };
    let sibling_bytes: u64 = cache
        .slots
        .values()
        .filter_map(|s| s.gpu.as_ref().map(|e| e.gpu_bytes()))
        .sum();
    Ok(Computed {
        generation: req.generation,
        frame: req.frame,
        time_ps: frame.time_ps,
        read_ms,
        compute_ms: started.elapsed().as_secs_f64() * 1e3,
        gpu_bytes: main_bytes + sibling_bytes,
        layers,
    })
}
