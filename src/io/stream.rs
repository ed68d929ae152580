//! [`FrameStreamer`]: the viewer's frame source. A reader thread owns the (shared)
//! [`Trajectory`] and fills a bounded least-recently-used cache of frames: first frames the
//! caller asked for, then a window around the playhead (more ahead than behind, for playback).
//! The UI thread never blocks: [`FrameStreamer::get`] answers from the cache or queues a
//! request. Per-frame errors are kept, so a corrupt frame can be shown and skipped.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{IoError, Trajectory};
use crate::model::Frame;

/// The outcome of reading one frame: the shared frame, or why it could not be read.
pub type FrameResult = Result<Arc<Frame>, IoError>;

/// Called on the reader thread with each frame index as it lands in the cache (ok or error);
/// the viewer uses it to request a repaint. Must be quick and must not call back into the
/// streamer's blocking methods.
pub type ReadyCallback = Box<dyn Fn(usize) + Send + 'static>;

/// Runs on the reader thread on each frame right after it is read, before it is cached (the
/// viewer's per-frame transformations, see [`crate::transform`]); an error (one line, without
/// the file and frame) makes the frame fail.
pub type FrameHook = Arc<dyn Fn(&mut Frame) -> Result<(), FrameHookError> + Send + Sync>;

/// Why a [`FrameHook`] refused a frame: any error, displayed as one line without the file and
/// frame (the streamer adds them).
pub type FrameHookError = Box<dyn std::error::Error + Send + Sync>;

/// Cache and prefetch sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamerOptions {
    /// Most frames kept in memory (at least 1; lowered further to fit `max_bytes`).
    pub capacity: usize,
    /// Bytes the cached positions may take (12 bytes per atom per frame).
    pub max_bytes: usize,
    /// Frames prefetched after the playhead.
    pub ahead: usize,
    /// Frames prefetched before the playhead.
    pub behind: usize,
}

impl Default for StreamerOptions {
    fn default() -> Self {
        StreamerOptions {
            capacity: 64,
            max_bytes: 512 << 20,
            ahead: 8,
            behind: 2,
        }
    }
}

/// What the streamer knows about one frame, see [`FrameStreamer::status`].
#[derive(Debug, Clone, PartialEq)]
pub enum FrameStatus {
    /// In the cache.
    Ready,
    /// Reading it failed (kept until the streamer is dropped).
    Failed(IoError),
    /// Not in the cache (never read, or evicted); [`FrameStreamer::request`] queues it.
    Missing,
    /// Past the last readable frame.
    OutOfRange,
}

/// A trajectory read by a background thread into a bounded cache, with prefetch around a
/// playhead. Dropping it stops and joins the thread.
pub struct FrameStreamer {
    shared: Arc<Shared>,
    trajectory: Arc<Trajectory>,
    thread: Option<JoinHandle<()>>,
}

struct Shared {
    state: Mutex<State>,
    /// Wakes the reader (new request, playhead moved, shutdown).
    work: Condvar,
    /// Wakes waiters (a frame landed).
    landed: Condvar,
    notify: Mutex<Option<ReadyCallback>>,
}

struct State {
    cache: HashMap<usize, (Arc<Frame>, u64)>,
    errors: HashMap<usize, IoError>,
    requests: VecDeque<usize>,
    playhead: usize,
    clock: u64,
    reads: u64,
    shutdown: bool,
}

impl FrameStreamer {
    /// Starts a reader thread on `trajectory`. The window `behind + 1 + ahead` is shrunk to one
    /// less than the cache capacity, so prefetching never evicts its own frames and a requested
    /// frame outside the window always fits.
    pub fn new(trajectory: impl Into<Arc<Trajectory>>, options: StreamerOptions) -> Self {
        Self::with_hook(trajectory, options, None)
    }

    /// Like [`FrameStreamer::new`], with `hook` run on every frame before it is cached, so the
    /// cache holds transformed frames.
    pub fn with_hook(
        trajectory: impl Into<Arc<Trajectory>>,
        options: StreamerOptions,
        hook: Option<FrameHook>,
    ) -> Self {
        let trajectory = trajectory.into();
        let frame_bytes = (trajectory.topology().len() * 12).max(1);
        let capacity = options.capacity.min(options.max_bytes / frame_bytes).max(1);
        // The window leaves one slot free for a requested frame outside it.
        let room = capacity.saturating_sub(1).max(1);
        let ahead = options.ahead.min(room - 1);
        let behind = options.behind.min(room - 1 - ahead);
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                cache: HashMap::new(),
                errors: HashMap::new(),
                requests: VecDeque::new(),
                playhead: 0,
                clock: 0,
                reads: 0,
                shutdown: false,
            }),
            work: Condvar::new(),
            landed: Condvar::new(),
            notify: Mutex::new(None),
        });
        let reader = Reader {
            shared: shared.clone(),
            trajectory: trajectory.clone(),
            hook,
            capacity,
            ahead,
            behind,
        };
        let thread = std::thread::Builder::new()
            .name("mdsurf-frames".into())
            .spawn(move || reader.run())
            .ok();
        if thread.is_none() {
            // No thread: every request fails instead of hanging.
            lock(&shared.state).shutdown = true;
        }
        FrameStreamer {
            shared,
            trajectory,
            thread,
        }
    }

    /// The trajectory being streamed (for its topology and length).
    pub fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    /// Number of readable frames (of a running simulation: those received so far, a number
    /// that grows).
    pub fn len(&self) -> usize {
        self.trajectory.available()
    }

    /// True when there are no readable frames.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sets `callback` to run (on the reader thread) whenever a frame lands.
    pub fn set_ready_callback(&self, callback: ReadyCallback) {
        *self.shared.notify.lock().unwrap_or_else(|p| p.into_inner()) = Some(callback);
    }

    /// Moves the playhead to frame `index` (clamped); prefetching recentres around it.
    pub fn set_playhead(&self, index: usize) {
        let mut state = lock(&self.shared.state);
        state.playhead = index.min(self.len().saturating_sub(1));
        self.shared.work.notify_one();
    }

    /// The cached frame `index`, or `None` (never blocks). A miss on a readable frame that has
    /// not failed queues a request for it, so polling `get` each repaint is enough.
    pub fn get(&self, index: usize) -> Option<Arc<Frame>> {
        let mut state = lock(&self.shared.state);
        state.clock += 1;
        let now = state.clock;
        if let Some((frame, used)) = state.cache.get_mut(&index) {
            *used = now;
            return Some(frame.clone());
        }
        if index < self.len() && !state.errors.contains_key(&index) {
            push_request(&mut state, index);
            self.shared.work.notify_one();
        }
        None
    }

    /// Asks for frame `index` to be read before any prefetching (most recent request first).
    /// Out-of-range indices and cached or failed frames are ignored.
    pub fn request(&self, index: usize) {
        let mut state = lock(&self.shared.state);
        if index < self.len()
            && !state.cache.contains_key(&index)
            && !state.errors.contains_key(&index)
        {
            push_request(&mut state, index);
            self.shared.work.notify_one();
        }
    }

    /// What is known about frame `index` right now.
    pub fn status(&self, index: usize) -> FrameStatus {
        let state = lock(&self.shared.state);
        if let Some(e) = state.errors.get(&index) {
            FrameStatus::Failed(e.clone())
        } else if state.cache.contains_key(&index) {
            FrameStatus::Ready
        } else if index >= self.len() {
            FrameStatus::OutOfRange
        } else {
            FrameStatus::Missing
        }
    }

    /// The error reading frame `index` gave, if it failed.
    pub fn error(&self, index: usize) -> Option<IoError> {
        lock(&self.shared.state).errors.get(&index).cloned()
    }

    /// Indices of the frames that failed so far, ascending.
    pub fn failed_frames(&self) -> Vec<usize> {
        let mut v: Vec<usize> = lock(&self.shared.state).errors.keys().copied().collect();
        v.sort_unstable();
        v
    }

    /// Indices of the cached frames, ascending.
    pub fn cached_frames(&self) -> Vec<usize> {
        let mut v: Vec<usize> = lock(&self.shared.state).cache.keys().copied().collect();
        v.sort_unstable();
        v
    }

    /// How many frames the reader thread has read from disk so far (cache misses served).
    pub fn reads(&self) -> u64 {
        lock(&self.shared.state).reads
    }

    /// Blocks up to `timeout` for frame `index` (requesting it first). `None` on timeout; an
    /// out-of-range index fails at once. For headless callers and tests; the UI uses `get`.
    pub fn wait(&self, index: usize, timeout: Duration) -> Option<FrameResult> {
        if index >= self.len() {
            let path = self.trajectory.path().to_path_buf();
            return Some(Err(IoError::FrameOutOfRange {
                path,
                frame: index,
                len: self.len(),
            }));
        }
        self.request(index);
        let deadline = Instant::now() + timeout;
        let mut state = lock(&self.shared.state);
        loop {
            if let Some((frame, _)) = state.cache.get(&index) {
                return Some(Ok(frame.clone()));
            }
            if let Some(e) = state.errors.get(&index) {
                return Some(Err(e.clone()));
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            if state.shutdown {
                return None;
            }
            // Evicted again before this thread woke up (a tiny cache): ask once more.
            if !state.requests.contains(&index) {
                push_request(&mut state, index);
                self.shared.work.notify_one();
            }
            state = match self.shared.landed.wait_timeout(state, left) {
                Ok((guard, _)) => guard,
                Err(poisoned) => poisoned.into_inner().0,
            };
        }
    }
}

impl Drop for FrameStreamer {
    fn drop(&mut self) {
        lock(&self.shared.state).shutdown = true;
        self.shared.work.notify_all();
        self.shared.landed.notify_all();
        if let Some(thread) = self.thread.take() {
            // The reader finishes at most the one frame it is reading.
            let _ = thread.join();
        }
    }
}

fn lock(state: &Mutex<State>) -> MutexGuard<'_, State> {
    state
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Queues `index` as the most urgent request (at most once; the queue stays short).
fn push_request(state: &mut State, index: usize) {
    state.requests.retain(|&r| r != index);
    state.requests.push_front(index);
    state.requests.truncate(64);
}

/// The reader thread's side.
struct Reader {
    shared: Arc<Shared>,
    trajectory: Arc<Trajectory>,
    hook: Option<FrameHook>,
    capacity: usize,
    ahead: usize,
    behind: usize,
}

impl Reader {
    fn run(self) {
        loop {
            let index = {
                let mut state = lock(&self.shared.state);
                loop {
                    if state.shutdown {
                        return;
                    }
                    if let Some(index) = self.next_job(&mut state) {
                        break index;
                    }
                    state = match self.shared.work.wait(state) {
                        Ok(guard) => guard,
                        Err(poisoned) => poisoned.into_inner(),
                    };
                }
            };
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut frame = self.trajectory.read_frame(index)?;
                if let Some(hook) = &self.hook {
                    hook(&mut frame)
                        .map_err(|e| IoError::bad_frame(self.trajectory.path(), index, e))?;
                }
                Ok(frame)
            }))
            .unwrap_or_else(|_| {
                Err(IoError::bad_frame(
                    self.trajectory.path(),
                    index,
                    "the reader crashed",
                ))
            });
            {
                let mut state = lock(&self.shared.state);
                state.reads += 1;
                match result {
                    Ok(frame) => self.insert(&mut state, index, Arc::new(frame)),
                    Err(e) => {
                        state.errors.insert(index, e);
                    }
                }
            }
            if let Some(callback) = self
                .shared
                .notify
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .as_ref()
            {
                callback(index);
            }
            self.shared.landed.notify_all();
        }
    }

    /// The prefetch window around the playhead, nearest first, ahead before behind.
    fn window(&self, playhead: usize) -> impl Iterator<Item = usize> + use<> {
        let len = self.trajectory.available();
        let ahead = (1..=self.ahead)
            .map(move |d| playhead + d)
            .filter(move |&i| i < len);
        let behind = (1..=self.behind).filter_map(move |d| playhead.checked_sub(d));
        std::iter::once(playhead)
            .filter(move |&i| i < len)
            .chain(ahead)
            .chain(behind)
    }

    /// The next frame to read: a request, else the first missing frame of the window.
    fn next_job(&self, state: &mut State) -> Option<usize> {
        while let Some(index) = state.requests.pop_front() {
            if !state.cache.contains_key(&index) && !state.errors.contains_key(&index) {
                return Some(index);
            }
        }
        self.window(state.playhead)
            .find(|i| !state.cache.contains_key(i) && !state.errors.contains_key(i))
    }

    /// Caches `frame`, evicting least-recently-used frames outside the playhead window.
    fn insert(&self, state: &mut State, index: usize, frame: Arc<Frame>) {
        state.clock += 1;
        let now = state.clock;
        state.cache.insert(index, (frame, now));
        while state.cache.len() > self.capacity {
            let keep: Vec<usize> = self.window(state.playhead).collect();
            let victim = state
                .cache
                .iter()
                .filter(|(i, _)| **i != index && !keep.contains(i))
                .min_by_key(|(_, (_, used))| *used)
                .map(|(i, _)| *i);
            let Some(victim) = victim.or_else(|| state.cache.keys().copied().find(|&i| i != index))
            else {
                break;
            };
            state.cache.remove(&victim);
        }
    }
}
