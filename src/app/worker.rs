//! The compute worker: one background thread around the [`SceneEngine`], so the UI thread never
//! waits for I/O or for a surface. It reads the requested frame (keeping a few around the
//! playhead), hands it to the scene engine, which computes every visible representation (see
//! [`crate::scene::engine`] for what is reused and what a GPU engine is told), and sends the
//! result back. Requests replace each other (latest wins): when computing falls behind
//! playback, the frames in between are dropped instead of queueing up.
//!
//! The GPU path never blocks the window: the scene engine submits every surface before it
//! waits for any counters, while the window keeps drawing the previous frame. The GPU engines
//! alternate between two output sets, so the surface on screen is never the one being written;
//! before writing again into the set the window may still draw, the worker waits until the
//! window has taken the previous reply (`Worker::try_recv`), so what is drawn (surface, atoms,
//! readouts) belongs to one frame.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use super::source::FrameSource;
use crate::model::{ParticleOptions, RadiusOverrides};
use crate::scene::representation::{RepStyle, Representation};
pub use crate::scene::{LayerResult, ParticleData, RepRequest};
use crate::scene::{SceneEngine, SceneFrame};
use crate::surface::{SurfaceEngine, SurfaceParams};

/// Frames kept in the worker's cache (around the playhead; oldest evicted first).
const FRAME_CACHE: usize = 16;

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

/// A finished frame: every visible representation, with the request's generation and the
/// worker's timings. The representations themselves are in [`SceneFrame`] (reached through
/// `Deref`: `computed.layers`, `computed.frame`).
#[derive(Debug, Clone)]
pub struct Computed {
    /// Generation of the request.
    pub generation: u64,
    /// Time to read the frame in ms.
    pub read_ms: f64,
    /// Wall-clock time the worker spent on this request in ms: reading, particles, and every
    /// surface submitted and its counters waited for (not the wait for the window to take the
    /// previous reply).
    pub compute_ms: f64,
    /// The frame's representations.
    pub scene: SceneFrame,
}

impl std::ops::Deref for Computed {
    type Target = SceneFrame;
    fn deref(&self) -> &SceneFrame {
        &self.scene
    }
}

impl Computed {
    /// Triangles of every surface together.
    pub fn triangle_count(&self) -> usize {
        self.surfaces().map(LayerResult::triangle_count).sum()
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

/// Why the worker could not compute a frame (one line).
#[derive(Debug, thiserror::Error)]
pub enum ComputeError {
    /// The frame could not be read.
    #[error(transparent)]
    Source(#[from] super::source::SourceError),
    /// A representation could not be computed.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The computation panicked (a bug, never a user's file).
    #[error("frame {frame}: internal error: {message}")]
    Panic {
        /// The frame asked for.
        frame: usize,
        /// The panic's message.
        message: String,
    },
}

/// The engine the worker runs (the scene engine's backend).
pub use crate::scene::SceneBackend as Engine;

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

/// Per-source state the worker keeps between requests.
struct Cache {
    source: Option<Arc<dyn FrameSource>>,
    frames: HashMap<usize, Arc<crate::model::Frame>>,
    order: Vec<usize>,
    radius_overrides: RadiusOverrides,
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
    engine: Engine,
    slot: Slot,
    mut channel: Channel,
    busy: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    notify: Box<dyn Fn() + Send>,
) {
    let on_gpu = matches!(engine, Engine::Gpu(_));
    let mut scene = SceneEngine::new(engine);
    let mut cache = Cache {
        source: None,
        frames: HashMap::new(),
        order: Vec::new(),
        radius_overrides: RadiusOverrides::default(),
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
        if on_gpu {
            channel.wait_taken(&stop);
        }
        // A panic (a bug, never a user's file) fails this request only: the window keeps its
        // last good frame and the next request starts over from a fresh cache.
        let computed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            compute(&mut scene, &mut cache, &request)
        }))
        .unwrap_or_else(|panic| {
            cache.source = None;
            cache.frames.clear();
            cache.order.clear();
            Err(ComputeError::Panic {
                frame,
                message: panic_text(&*panic),
            })
        });
        let reply = match computed {
            Ok(c) => {
                scene.hold_shown(&c.scene);
                Reply::Done(Box::new(c))
            }
            Err(e) => Reply::Failed {
                generation,
                frame,
                message: e.to_string(),
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

/// The message of a caught panic, on one line.
fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    let text = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into());
    text.replace('\n', " ")
}

/// Frame `req.frame` of the request's source, from the cache or read (with the read time in
/// ms); a new source or new radius overrides start the scene engine over.
fn frame_of(
    scene: &mut SceneEngine,
    cache: &mut Cache,
    req: &Request,
) -> Result<(Arc<crate::model::Frame>, f64), super::source::SourceError> {
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
        scene.reset(req.source.topology(), &req.radius_overrides);
    }
    scene.set_periodic(req.source.periodic());
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

fn compute(
    scene: &mut SceneEngine,
    cache: &mut Cache,
    req: &Request,
) -> Result<Computed, ComputeError> {
    let started = Instant::now();
    let (frame, read_ms) = frame_of(scene, cache, req)?;
    let computed = scene.frame(req.source.topology(), req.frame, &frame, &req.reps)?;
    Ok(Computed {
        generation: req.generation,
        read_ms,
        compute_ms: started.elapsed().as_secs_f64() * 1e3,
        scene: computed,
    })
}
