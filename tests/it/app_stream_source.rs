//! The viewer's file source ([`StreamedSource`]) reads through the io module's `FrameStreamer`:
//! frames equal the trajectory's own, reading one prefetches the frames after it (so the next
//! playback step is served from the cache without touching the file), and a frame that fails
//! to read comes back from the compute worker as a one-line failure naming it, while the frames
//! around it still compute (playback goes on).

use crate::data_support::{data, nan_trajectory};

use std::sync::Arc;
use std::time::{Duration, Instant};

use mdsurf::app::source::{FrameSource, SourceError, StreamedSource};
use mdsurf::app::worker::{Reply, Request, Worker};
use mdsurf::io::{self, StreamerOptions, Trajectory};
use mdsurf::model::ParticleOptions;
use mdsurf::surface::{CpuEngine, SurfaceParams};

fn rhodopsin() -> Trajectory {
    io::open(&data("md_1u19.gro"), Some(&data("md_1u19.xtc"))).expect("open rhodopsin")
}

fn options() -> StreamerOptions {
    StreamerOptions {
        capacity: 16,
        ahead: 3,
        behind: 1,
        ..Default::default()
    }
}

#[test]
fn streamed_source_prefetches_after_each_read() {
    let direct = rhodopsin();
    let source = StreamedSource::new(rhodopsin(), options());
    assert_eq!(source.len(), direct.len());
    assert_eq!(source.topology().len(), direct.topology().len());
    let f5 = source.read_frame(5).expect("frame 5");
    assert_eq!(
        f5.positions,
        direct.read_frame(5).expect("direct").positions
    );
    // The window around frame 5 is 4..=8 (one behind, three ahead): wait for all of it, so no
    // read of that window is still in flight when the count is taken.
    wait_cached(&source, 4..=8);
    let reads = source.streamer().reads();
    for i in 6..=8 {
        let f = source.read_frame(i).expect("prefetched frame");
        assert_eq!(f.positions, direct.read_frame(i).expect("direct").positions);
    }
    // Reading 6, 7 and 8 moved the window on to 9-11: exactly those three are new reads.
    wait_cached(&source, 9..=11);
    assert_eq!(
        source.streamer().reads(),
        reads + 3,
        "prefetched frames were read from the file again"
    );
    let e = source.read_frame(direct.len()).expect_err("past the end");
    assert!(
        matches!(e, SourceError::Skipped { index, .. } if index == direct.len()),
        "{e:?}"
    );
    assert!(!e.to_string().contains('\n'), "{e}");
}

/// Waits (up to 30 s) until the reader has prefetched `frames` without being asked.
fn wait_cached(source: &StreamedSource, frames: std::ops::RangeInclusive<usize>) {
    let start = Instant::now();
    while !frames
        .clone()
        .all(|i| source.streamer().cached_frames().contains(&i))
    {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "frames {frames:?} were not prefetched: cache {:?}",
            source.streamer().cached_frames()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn a_failed_frame_is_reported_and_the_next_one_computes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let source: Arc<dyn FrameSource> =
        Arc::new(StreamedSource::new(nan_trajectory(dir.path()), options()));
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    for frame in [0, 1, 2, 1] {
        worker.submit(Request::single(
            1,
            frame,
            source.clone(),
            SurfaceParams::default(),
            ParticleOptions::default(),
        ));
        let reply = worker
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|| panic!("frame {frame}: no reply in 60 s"));
        match (frame, reply) {
            (
                1,
                Reply::Failed {
                    frame: f, message, ..
                },
            ) => {
                assert_eq!(f, 1);
                assert!(message.contains("frame 1"), "{message}");
                assert!(!message.contains('\n'), "{message}");
            }
            (1, Reply::Done(_)) => panic!("frame 1 has a NaN coordinate but computed"),
            (_, Reply::Done(c)) => {
                assert_eq!(c.frame, frame);
                assert!(c.triangle_count() > 0, "frame {frame}: empty surface");
            }
            (_, Reply::Failed { message, .. }) => panic!("frame {frame}: {message}"),
        }
    }
}

/// A source whose frame `at` panics (a bug somewhere below the worker, not a user's file).
struct PanicsAt {
    inner: Trajectory,
    at: usize,
}

impl FrameSource for PanicsAt {
    fn topology(&self) -> &mdsurf::model::Topology {
        self.inner.topology()
    }
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn read_frame(&self, index: usize) -> Result<Arc<mdsurf::model::Frame>, SourceError> {
        assert_ne!(index, self.at, "injected bug at frame {index}");
        FrameSource::read_frame(&self.inner, index)
    }
    fn name(&self) -> String {
        "panics".into()
    }
}

#[test]
fn a_panic_on_the_compute_thread_fails_one_frame_and_the_worker_goes_on() {
    let source: Arc<dyn FrameSource> = Arc::new(PanicsAt {
        inner: rhodopsin(),
        at: 1,
    });
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    for frame in [0, 1, 2] {
        worker.submit(Request::single(
            1,
            frame,
            source.clone(),
            SurfaceParams::default(),
            ParticleOptions::default(),
        ));
        match worker.recv_timeout(Duration::from_secs(60)) {
            Some(Reply::Failed { message, .. }) if frame == 1 => {
                assert!(message.contains("frame 1: internal error"), "{message}");
                assert!(message.contains("injected bug") && !message.contains('\n'));
            }
            Some(Reply::Done(c)) if frame != 1 => assert!(c.triangle_count() > 0),
            other => panic!("frame {frame}: {other:?}"),
        }
    }
}
