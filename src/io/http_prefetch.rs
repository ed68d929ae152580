//! Fetching a header walk's next frame headers ahead, in parallel, over HTTP
//! ([`super::http::RangeSource`]). Walking the headers of an XTC or TRR file whose frames are
//! large costs one request per frame, and where the next header lies is known only once this
//! one is read: one round trip after the other. Frames of one trajectory are of nearly the same
//! size, so once four headers have come at a steady stride, the byte windows where the next
//! [`PREFETCH_FRAMES`] headers should lie are fetched together and kept as spans; the walk's
//! header reads that fall inside a span cost nothing. A window that misses costs only its
//! bytes: the walk fetches that header itself, and the stride, refined by the frames in between,
//! predicts again from there.
//!
//! Window placement: after `k` frames of mean size `m` (bytes), a header lies near
//! `last + k m`; its window reaches `HEADER_MARGIN + 3 sigma sqrt(k) + 3 k sigma / sqrt(n)`
//! either side, for strides of standard deviation `sigma` and a mean taken over `n` frames
//! (the sizes' own scatter, and the mean's error growing with the distance).

use std::collections::VecDeque;

/// Frames whose headers are fetched ahead (16; [`PREFETCH_VAR`] sets another number, at most
/// 64, and 0 turns prefetching off).
pub(crate) const PREFETCH_FRAMES: u64 = 16;
/// The environment variable that sets how many frames are fetched ahead.
pub(crate) const PREFETCH_VAR: &str = "MDSURF_HTTP_PREFETCH";
/// Bytes a window reaches beyond its predicted header on either side, at the least (a TRR
/// header with its name is under 200 bytes).
const HEADER_MARGIN: f64 = 256.0;
/// Widest reach of a window either side of its predicted header (32 KiB).
const MAX_REACH: f64 = 32.0 * 1024.0;
/// Smallest standard deviation assumed for the frame sizes (bytes).
const MIN_SIGMA: f64 = 16.0;
/// Spans kept at most (the oldest go first).
const MAX_SPANS: usize = 256;

/// How many frames to fetch ahead: [`PREFETCH_VAR`] when set to a number, else
/// [`PREFETCH_FRAMES`].
pub(crate) fn prefetch_frames() -> u64 {
    std::env::var(PREFETCH_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map_or(PREFETCH_FRAMES, |n| n.min(64))
}

/// The stride of a walk whose frames are of nearly one size (bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Stride {
    /// Mean frame size.
    pub mean: f64,
    /// Standard deviation of the frame sizes seen one after the other.
    pub sigma: f64,
    /// Frames the mean is taken over.
    pub frames: f64,
}

impl Stride {
    /// The stride of the walk reads that started at `starts` (ascending, one frame apart):
    /// `None` unless there are at least three strides, all positive, and they differ by at
    /// most a quarter of their mean.
    pub fn of(starts: &[u64]) -> Option<Stride> {
        if starts.len() < 4 || starts.windows(2).any(|w| w[1] <= w[0]) {
            return None;
        }
        let strides: Vec<f64> = starts.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
        let n = strides.len() as f64;
        let mean = strides.iter().sum::<f64>() / n;
        let (low, high) = strides
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &s| (l.min(s), h.max(s)));
        if high - low > mean / 4.0 {
            return None;
        }
        let variance = strides.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / n;
        Some(Stride {
            mean,
            sigma: variance.sqrt().max(MIN_SIGMA),
            frames: n,
        })
    }

    /// How far (bytes) the header `k` frames on may lie from its prediction.
    fn reach(&self, k: f64) -> f64 {
        let scatter = 3.0 * self.sigma * k.sqrt();
        let mean_error = 3.0 * k * self.sigma / self.frames.sqrt();
        (HEADER_MARGIN + scatter + mean_error).min(MAX_REACH)
    }

    /// When the walk read at `start` lies a whole number of frames after the one at `last`
    /// (within the reach of that distance), takes those frames into the mean and says so.
    pub fn continues(&mut self, last: u64, start: u64) -> bool {
        if start <= last {
            return false;
        }
        let gap = (start - last) as f64;
        let k = (gap / self.mean).round();
        if k < 1.0 || (gap - k * self.mean).abs() > self.reach(k) {
            return false;
        }
        self.mean = (self.mean * self.frames + gap) / (self.frames + k);
        self.frames += k;
        true
    }

    /// The byte ranges `[first, end)` where the `count` headers after the one at `last` should
    /// lie, within a file of `size` bytes.
    pub fn windows(&self, last: u64, count: u64, size: u64) -> Vec<(u64, u64)> {
        (1..=count)
            .map(|k| {
                let k = k as f64;
                let centre = last as f64 + k * self.mean;
                let reach = self.reach(k);
                let first = (centre - reach).max(0.0) as u64;
                let end = ((centre + reach).ceil() as u64).min(size);
                (first, end)
            })
            .filter(|&(first, end)| first < end)
            .collect()
    }
}

/// The prefetching state of one source: the last walk reads, the stride once steady, and the
/// spans fetched ahead.
#[derive(Debug)]
pub(crate) struct Prefetcher {
    /// Frames fetched ahead per prediction (0: none).
    count: u64,
    /// Where the reads that made the last few walk fetches started (bytes).
    starts: Vec<u64>,
    stride: Option<Stride>,
    /// Bytes fetched ahead, by their first byte's offset.
    spans: VecDeque<(u64, Vec<u8>)>,
}

impl Prefetcher {
    /// A prefetcher that fetches `count` frames ahead.
    pub fn new(count: u64) -> Prefetcher {
        Prefetcher {
            count,
            starts: Vec::new(),
            stride: None,
            spans: VecDeque::new(),
        }
    }

    /// After a walk read at byte `start` had to fetch: the byte ranges to fetch ahead (none
    /// until the stride is steady) in a file of `size` bytes.
    pub fn plan(&mut self, start: u64, size: u64) -> Vec<(u64, u64)> {
        if self.count == 0 {
            return Vec::new();
        }
        let last = self.starts.last().copied();
        let kept = match (&mut self.stride, last) {
            (Some(stride), Some(last)) => stride.continues(last, start),
            _ => false,
        };
        if kept {
            self.starts = vec![start];
        } else {
            if last.is_some_and(|last| start <= last) {
                self.starts.clear();
            }
            self.starts.push(start);
            if self.starts.len() > 4 {
                self.starts.remove(0);
            }
            self.stride = Stride::of(&self.starts);
        }
        match self.stride {
            Some(stride) => stride.windows(start, self.count, size),
            None => Vec::new(),
        }
    }

    /// Keeps `bytes` fetched ahead from byte `first`.
    pub fn keep(&mut self, first: u64, bytes: Vec<u8>) {
        self.spans.push_back((first, bytes));
        while self.spans.len() > MAX_SPANS {
            self.spans.pop_front();
        }
    }

    /// Fills `buf` with the bytes at `at` when one span holds them all.
    pub fn read(&self, at: u64, buf: &mut [u8]) -> bool {
        let end = at + buf.len() as u64;
        let held = self
            .spans
            .iter()
            .find(|(first, bytes)| *first <= at && end <= first + bytes.len() as u64);
        match held {
            Some((first, bytes)) => {
                let from = (at - first) as usize;
                buf.copy_from_slice(&bytes[from..from + buf.len()]);
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame starts of frames of about 21 kB whose sizes vary by up to 500 bytes (the sizes
    /// of `tests/data/md_1u19.xtc`'s first frames).
    fn starts() -> Vec<u64> {
        let sizes = [
            21_168u64, 20_744, 20_720, 21_172, 20_752, 20_732, 21_188, 21_172,
        ];
        let mut starts = vec![0u64];
        for size in sizes.into_iter().cycle().take(40) {
            starts.push(starts.last().unwrap() + size);
        }
        starts
    }

    #[test]
    fn a_steady_walk_predicts_windows_around_the_next_headers() {
        let starts = starts();
        let stride = Stride::of(&starts[..4]).expect("steady");
        assert!((stride.mean - 20_877.3).abs() < 0.1, "{stride:?}");
        let windows = stride.windows(starts[3], 16, u64::MAX);
        assert_eq!(windows.len(), 16);
        for (k, &(first, end)) in windows.iter().enumerate() {
            let header = starts[4 + k];
            assert!(
                first <= header && header + 92 <= end,
                "frame {}: header at {header} outside {first}..{end}",
                4 + k
            );
            assert!(
                end - first < 20_000,
                "window {}: {} bytes",
                4 + k,
                end - first
            );
        }
        assert_eq!(Stride::of(&[0, 1_000, 5_000, 6_000]), None, "unsteady");
        assert_eq!(Stride::of(&[0, 21_000, 42_000]), None, "too few strides");
    }

    #[test]
    fn a_miss_whole_frames_on_keeps_and_refines_the_stride() {
        let starts = starts();
        let mut prefetcher = Prefetcher::new(16);
        for &s in &starts[..3] {
            assert!(prefetcher.plan(s, u64::MAX).is_empty());
        }
        assert_eq!(prefetcher.plan(starts[3], u64::MAX).len(), 16);
        // The walk next fetches 17 frames on: the stride holds, over 20 frames now.
        assert_eq!(prefetcher.plan(starts[20], u64::MAX).len(), 16);
        let stride = prefetcher.stride.expect("kept");
        assert_eq!(stride.frames, 20.0);
        assert!((stride.mean - (starts[20] - starts[0]) as f64 / 20.0).abs() < 1e-6);
        // A jump that is no whole number of frames starts over.
        assert!(prefetcher.plan(starts[30] + 9_000, u64::MAX).is_empty());
    }

    #[test]
    fn spans_serve_reads_they_hold_whole() {
        let mut prefetcher = Prefetcher::new(16);
        prefetcher.keep(1_000, (0..=255u8).collect());
        let mut buf = [0u8; 4];
        assert!(prefetcher.read(1_010, &mut buf));
        assert_eq!(buf, [10, 11, 12, 13]);
        assert!(!prefetcher.read(1_253, &mut buf), "past the span's end");
        assert!(!prefetcher.read(999, &mut buf), "before its start");
    }
}
