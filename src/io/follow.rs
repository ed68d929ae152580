//! Following a trajectory file while an engine writes it (`--follow`): a thread watches the
//! file's size and, when it has grown, opens it again, so that the frames appended since appear
//! (XTC, TRR, DCD, LAMMPS dump, GRO, any format [`super::open`] reads). A frame the engine is
//! still writing is the damaged last frame of that reopened file, so it is not read: it is
//! waited for until the file grows past it. When the file has not grown for the idle time the
//! run is over: the frames read stay, and the next is [`IoError::LiveEnded`].
//!
//! Each growth costs one [`super::open`] of the files (the topology is read again and an XTC's
//! frame headers walked again), at most once per poll interval.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::live::{LIVE_FRAMES_UNBOUNDED, LiveCount, LiveProgress};
use super::native::NativeFrames;
use super::{IoError, Trajectory};
use crate::model::Frame;

/// How to follow a growing file.
#[derive(Debug, Clone)]
pub struct FollowOptions {
    /// The file the engine appends frames to.
    pub path: PathBuf,
    /// The run is over when the file has not grown for this long.
    pub idle: Duration,
    /// How often the file's size is looked at.
    pub poll: Duration,
}

impl FollowOptions {
    /// Follows `path`, looking every 0.5 s, until it has not grown for 60 s.
    pub fn new(path: &Path) -> FollowOptions {
        FollowOptions {
            path: path.to_path_buf(),
            idle: Duration::from_secs(60),
            poll: Duration::from_millis(500),
        }
    }
}

/// What the watching thread last found.
struct Watched {
    /// The file as last opened (its readable frames are the whole ones).
    frames: Arc<Trajectory>,
    /// Its size then (bytes).
    size: u64,
    /// Why following stopped, once it has.
    ended: Option<String>,
}

struct Shared {
    watched: Mutex<Watched>,
    grew: Condvar,
    stop: AtomicBool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Watched> {
        self.watched
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl LiveProgress for Shared {
    fn received(&self) -> usize {
        self.lock().frames.len()
    }

    fn ended(&self) -> Option<String> {
        self.lock().ended.clone()
    }
}

/// A trajectory file that grows while it is read.
pub(crate) struct FollowedFrames {
    path: PathBuf,
    base: &'static str,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl FollowedFrames {
    /// Starts watching `options.path` (its frames so far: `opened`, the file opened with the
    /// structure `top`).
    pub(crate) fn start(
        top: &Path,
        opened: Trajectory,
        options: &FollowOptions,
    ) -> Result<FollowedFrames, IoError> {
        let path = options.path.clone();
        let base = super::detect(&path)?.base;
        let size = file_size(&path).map_err(|e| IoError::unreadable(&path, e))?;
        let shared = Arc::new(Shared {
            watched: Mutex::new(Watched {
                frames: Arc::new(opened),
                size,
                ended: None,
            }),
            grew: Condvar::new(),
            stop: AtomicBool::new(false),
        });
        let thread = {
            let (shared, top, options) = (Arc::clone(&shared), top.to_path_buf(), options.clone());
            std::thread::Builder::new()
                .name("mdsurf-follow".into())
                .spawn(move || watch(&top, &options, &shared))
                .map_err(|e| IoError::unreadable(&path, format!("cannot start a thread: {e}")))?
        };
        Ok(FollowedFrames {
            path,
            base,
            shared,
            thread: Some(thread),
        })
    }

    /// A handle on how many frames are readable.
    pub(crate) fn count(&self) -> LiveCount {
        Arc::clone(&self.shared) as LiveCount
    }
}

/// Why the followed file cannot be looked at.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum FollowError {
    /// Its size cannot be had (the operating system's message): it was removed or moved.
    #[error("the file is gone ({0})")]
    Gone(String),
}

/// The size of `path` in bytes, or why it cannot be had.
fn file_size(path: &Path) -> Result<u64, FollowError> {
    std::fs::metadata(path)
        .map(|m| m.len())
        .map_err(|e| FollowError::Gone(e.to_string()))
}

/// The watching thread: reopens the file when it grows, until it stops growing or the reader
/// side goes away.
fn watch(top: &Path, options: &FollowOptions, shared: &Shared) {
    let mut last_growth = Instant::now();
    while !shared.stop.load(Ordering::Relaxed) {
        std::thread::sleep(options.poll);
        let size = file_size(&options.path);
        let mut watched = shared.lock();
        match size {
            Ok(size) if size != watched.size => {
                last_growth = Instant::now();
                drop(watched);
                // Opened outside the lock: readers keep reading the frames known so far. A
                // file caught in the middle of a header may not open: the next look retries.
                let reopened = super::open(top, Some(&options.path)).ok();
                let mut watched = shared.lock();
                watched.size = size;
                if let Some(reopened) = reopened.filter(|t| t.len() >= watched.frames.len()) {
                    watched.frames = Arc::new(reopened);
                    shared.grew.notify_all();
                }
            }
            Ok(_) if last_growth.elapsed() >= options.idle => {
                let damage = watched
                    .frames
                    .damage()
                    .map(|d| format!("; {}", d.error))
                    .unwrap_or_default();
                watched.ended = Some(format!(
                    "the file has not grown for {} s{damage}",
                    options.idle.as_secs()
                ));
                shared.grew.notify_all();
                return;
            }
            Ok(_) => {}
            Err(reason) => {
                watched.ended = Some(reason.to_string());
                shared.grew.notify_all();
                return;
            }
        }
    }
}

impl NativeFrames for FollowedFrames {
    fn path(&self) -> &Path {
        &self.path
    }

    fn base(&self) -> &'static str {
        self.base
    }

    fn len(&self) -> usize {
        LIVE_FRAMES_UNBOUNDED
    }

    fn damage(&self) -> Option<&IoError> {
        None
    }

    fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        let frames = {
            let mut watched = self.shared.lock();
            loop {
                if index < watched.frames.len() {
                    break Arc::clone(&watched.frames);
                }
                if let Some(reason) = &watched.ended {
                    return Err(IoError::LiveEnded {
                        path: self.path.clone(),
                        frames: watched.frames.len(),
                        reason: reason.clone(),
                    });
                }
                watched = self
                    .shared
                    .grew
                    .wait_timeout(watched, Duration::from_secs(1))
                    .map(|(guard, _)| guard)
                    .unwrap_or_else(|poisoned| poisoned.into_inner().0);
            }
        };
        frames.read_frame(index)
    }
}

impl Drop for FollowedFrames {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_removed_file_is_gone() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("t.xtc");
        std::fs::write(&path, b"1234").expect("write");
        assert_eq!(file_size(&path), Ok(4));
        std::fs::remove_file(&path).expect("remove");
        let error = file_size(&path).unwrap_err();
        assert!(matches!(error, FollowError::Gone(_)));
        assert!(error.to_string().starts_with("the file is gone ("));
    }
}
