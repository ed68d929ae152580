//! `FrameStreamer`: frames equal the trajectory's, prefetch fills the window around the
//! playhead without requests, the cache stays bounded and evicts least-recently-used frames,
//! per-frame errors are kept (and not retried), and dropping the streamer ends its thread.

use crate::data_support::{data, nan_trajectory};

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use mdsurf::io::{self, FrameStatus, FrameStreamer, IoError, StreamerOptions, Trajectory};

const LONG: Duration = Duration::from_secs(30);

fn rhodopsin() -> Arc<Trajectory> {
    Arc::new(io::open(&data("md_1u19.gro"), Some(&data("md_1u19.xtc"))).expect("open"))
}

fn options(capacity: usize, ahead: usize, behind: usize) -> StreamerOptions {
    StreamerOptions {
        capacity,
        ahead,
        behind,
        ..Default::default()
    }
}

/// Polls until `done` holds (the reader works in the background), failing after 30 s.
fn eventually(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < LONG, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn frames_equal_direct_reads() {
    let t = rhodopsin();
    let s = FrameStreamer::new(t.clone(), options(8, 2, 1));
    assert_eq!(s.len(), 51);
    for k in [0, 10, 50, 3] {
        let f = s.wait(k, LONG).expect("in time").expect("readable");
        assert_eq!(*f, t.read_frame(k).expect("direct"));
    }
    let e = s
        .wait(51, LONG)
        .expect("immediate")
        .expect_err("past the end");
    assert!(matches!(e, IoError::FrameOutOfRange { frame: 51, .. }));
    assert_eq!(s.status(51), FrameStatus::OutOfRange);
}

#[test]
fn prefetch_fills_the_window_around_the_playhead() {
    let s = FrameStreamer::new(rhodopsin(), options(16, 3, 1));
    s.set_playhead(20);
    let window = [19, 20, 21, 22, 23];
    eventually("the window", || {
        window.iter().all(|&k| s.status(k) == FrameStatus::Ready)
    });
    // Nothing else needs reading: the reader goes idle.
    std::thread::sleep(Duration::from_millis(100));
    let reads = s.reads();
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(s.reads(), reads, "idle reader must not keep reading");
    for k in window {
        assert_eq!(s.get(k).expect("cached").index, k);
    }
    assert_eq!(s.status(30), FrameStatus::Missing);
    // A get miss queues the frame.
    assert!(s.get(40).is_none());
    eventually("frame 40 after a get miss", || s.get(40).is_some());
}

#[test]
fn cache_is_bounded_and_least_recently_used_goes_first() {
    let s = FrameStreamer::new(rhodopsin(), options(4, 0, 0));
    for k in 0..4 {
        s.wait(k, LONG).expect("in time").expect("readable");
    }
    assert_eq!(s.cached_frames(), vec![0, 1, 2, 3]);
    assert!(s.get(1).is_some()); // 1 is now more recent than 2 and 3
    s.wait(4, LONG).expect("in time").expect("readable");
    assert_eq!(
        s.cached_frames(),
        vec![0, 1, 3, 4],
        "2 was least recently used; 0 is the playhead"
    );
    for k in 0..51 {
        s.wait(k, LONG).expect("in time").expect("readable");
        assert!(s.cached_frames().len() <= 4);
    }
    // The byte budget lowers the capacity too: one 5,547-atom frame is 66,564 bytes.
    let small = StreamerOptions {
        capacity: 100,
        max_bytes: 3 * 66_564,
        ahead: 10,
        behind: 10,
    };
    let s = FrameStreamer::new(rhodopsin(), small);
    for k in 0..20 {
        s.wait(k, LONG).expect("in time").expect("readable");
        assert!(s.cached_frames().len() <= 3, "{:?}", s.cached_frames());
    }
}

#[test]
fn frame_errors_are_kept_and_not_retried() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = FrameStreamer::new(nan_trajectory(dir.path()), options(8, 2, 2));
    let e = s
        .wait(1, LONG)
        .expect("in time")
        .expect_err("frame 1 has a NaN");
    assert!(
        matches!(
            e,
            IoError::NonFiniteCoordinate {
                frame: 1,
                atom: 4,
                ..
            }
        ),
        "{e}"
    );
    assert!(matches!(s.status(1), FrameStatus::Failed(_)));
    assert_eq!(s.error(1), Some(e));
    s.set_playhead(1);
    eventually("frames around the bad one", || {
        s.get(0).is_some() && s.get(2).is_some()
    });
    assert_eq!(s.failed_frames(), vec![1]);
    let reads = s.reads();
    for _ in 0..10 {
        assert!(s.get(1).is_none());
        s.request(1);
    }
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(s.reads(), reads, "a failed frame is not read again");
}

#[test]
fn drop_stops_the_reader_and_callbacks_fire() {
    let t =
        Arc::new(io::open(&data("adk_oplsaa.gro"), Some(&data("adk_oplsaa.xtc"))).expect("open"));
    let landed = Arc::new(AtomicUsize::new(0));
    let s = FrameStreamer::new(t.clone(), options(10, 9, 0));
    let counter = landed.clone();
    s.set_ready_callback(Box::new(move |_| {
        counter.fetch_add(1, Ordering::SeqCst);
    }));
    s.wait(5, LONG).expect("in time").expect("readable");
    eventually("the callback when a frame lands", || {
        landed.load(Ordering::SeqCst) >= 1
    });
    s.set_playhead(0);
    drop(s); // mid-prefetch: must return, not hang
    assert_eq!(
        Arc::strong_count(&t),
        1,
        "the reader thread has let go of the trajectory"
    );
}

#[test]
fn trajectory_and_streamer_cross_threads() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Trajectory>();
    fn send<T: Send>() {}
    send::<FrameStreamer>();
    // Frames read from several threads at once equal sequential reads.
    let t = rhodopsin();
    let handles: Vec<_> = (0..4)
        .map(|k| {
            let t = t.clone();
            std::thread::spawn(move || t.read_frame(k * 10).expect("frame"))
        })
        .collect();
    for (k, h) in handles.into_iter().enumerate() {
        assert_eq!(
            h.join().expect("thread"),
            t.read_frame(k * 10).expect("frame")
        );
    }
}
