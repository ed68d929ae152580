//! Animated GIF movies, for web pages, slides and chat, with no external program: rendered RGBA
//! images in, one looping GIF out. Each frame gets its own palette of at most 256 colours
//! (NeuQuant, the `gif` crate's `color_quant`); a pixel of alpha 0 (`render --transparent`)
//! becomes the frame's transparent colour. GIF delays are whole hundredths of a second: frame
//! `i` lasts `round((i + 1) * 100 / fps) - round(i * 100 / fps)`, so that the running time stays
//! within 5 ms of `i / fps` (30 frames/s gives 3, 4, 3, 3, 4, 3, ...). Players show delays under
//! 2/100 s as 1/10 s, so at most [`GIF_MAX_FPS`] frames per second.
//!
//! Frames are quantised and compressed on rayon's threads, several at once, and written in
//! order as they come back (a 1920x1080 frame takes about 0.13 s on one core).
//!
//! Written to a temporary file beside the target and renamed over it only by
//! [`GifMovie::finish`] ([`super::atomic`]), as the MP4 movies. The parts of a job array's chunks
//! (each started at its first frame's index, so its delays continue the running time) are joined
//! by [`merge_gif_parts`] byte for byte: the merged file equals one run's.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufReader, Seek};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, sync_channel};

use gif::{DisposalMethod, Encoder, Repeat};

use super::AtomicFile;
use super::video::{MovieSummary, VideoError, VideoQuality, check_fps, check_image_size};
use crate::render::RgbaImage;

/// The highest frame rate of a GIF movie, frames per second (a delay of 2/100 s).
pub const GIF_MAX_FPS: f64 = 50.0;

/// The largest side of a GIF, pixels (a 16-bit field).
pub const GIF_MAX_SIDE: u32 = u16::MAX as u32;

/// An animated GIF being written. Dropping it without [`GifMovie::finish`] deletes the temporary
/// file and leaves any existing target untouched.
pub struct GifMovie {
    path: PathBuf,
    size: [u16; 2],
    fps: f64,
    /// NeuQuant's sampling factor, 1 (best) to 30 (fastest).
    speed: i32,
    encoder: Encoder<AtomicFile>,
    /// Index of the first frame in the whole movie (a chunk's part starts later).
    first_frame: usize,
    frames: usize,
    /// Frames being quantised and compressed, in order, not yet written.
    pending: VecDeque<Receiver<gif::Frame<'static>>>,
}

/// The most frames in flight: two per rayon thread, at most 16 (a 1920x1080 frame holds 8 MB
/// until it is compressed).
fn max_pending() -> usize {
    (2 * rayon::current_num_threads()).clamp(2, 16)
}

impl GifMovie {
    /// Starts a GIF of `size` pixels at `fps` frames per second in `path`, whose first frame is
    /// frame `first_frame` of the whole movie (0 unless this is a chunk's part).
    pub fn create(
        path: &Path,
        size: [u32; 2],
        fps: f64,
        quality: VideoQuality,
        first_frame: usize,
    ) -> Result<GifMovie, VideoError> {
        let fps = check_gif_fps(path, fps)?;
        let [w, h] = check_gif_size(path, size)?;
        let file = AtomicFile::create(path)?;
        let mut encoder =
            Encoder::new(file, w, h, &[]).map_err(|e| encoding(path, "cannot start", e))?;
        encoder
            .set_repeat(Repeat::Infinite)
            .map_err(|e| encoding(path, "cannot start", e))?;
        Ok(GifMovie {
            path: path.to_path_buf(),
            size: [w, h],
            fps,
            speed: neuquant_speed(quality),
            encoder,
            first_frame,
            frames: 0,
            pending: VecDeque::new(),
        })
    }

    /// The output path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Adds `image` as the next frame (alpha 0: transparent, any other alpha: opaque).
    pub fn push(&mut self, image: &RgbaImage) -> Result<(), VideoError> {
        let [w, h] = self.size;
        check_image_size(&self.path, self.frames, image, [w, h].map(u32::from))?;
        let mut pixels = image.pixels.clone();
        let (speed, delay) = (
            self.speed,
            delay_cs(self.first_frame + self.frames, self.fps),
        );
        let (done, frame) = sync_channel(1);
        // The size was checked above and the speed is 1 to 30: no assertion of the crate fails.
        rayon::spawn(move || {
            let mut frame = gif::Frame::from_rgba_speed(w, h, &mut pixels, speed);
            frame.delay = delay;
            // Each frame covers the whole picture; clearing it first keeps a transparent
            // background from showing the frame before.
            frame.dispose = DisposalMethod::Background;
            frame.make_lzw_pre_encoded();
            // A movie dropped meanwhile no longer waits for it.
            let _ = done.send(frame);
        });
        self.pending.push_back(frame);
        self.frames += 1;
        while self.pending.len() > max_pending() {
            self.write_next()?;
        }
        Ok(())
    }

    /// Writes the oldest frame in flight, waiting for it.
    fn write_next(&mut self) -> Result<(), VideoError> {
        let Some(next) = self.pending.pop_front() else {
            return Ok(());
        };
        let frame = next.recv().map_err(|_| VideoError::Codec {
            path: self.path.clone(),
            what: "cannot write a frame",
            message: "the frame's encoder stopped".into(),
        })?;
        self.encoder
            .write_lzw_pre_encoded_frame(&frame)
            .map_err(|e| encoding(&self.path, "cannot write a frame", e))
    }

    /// Writes the trailer, syncs and renames the movie into place.
    pub fn finish(mut self) -> Result<MovieSummary, VideoError> {
        while !self.pending.is_empty() {
            self.write_next()?;
        }
        if self.frames == 0 {
            return Err(VideoError::Codec {
                path: self.path,
                what: "cannot write a movie",
                message: "no frames".into(),
            });
        }
        let path = self.path;
        let mut file = self
            .encoder
            .into_inner()
            .map_err(|e| encoding(&path, "cannot finish", e))?;
        let bytes = file
            .stream_position()
            .map_err(|e| super::ExportError::io(&path, e))?;
        file.commit()?;
        let first = self.first_frame;
        let centis = running_cs(first + self.frames, self.fps) - running_cs(first, self.fps);
        Ok(MovieSummary {
            frames: self.frames,
            seconds: centis as f64 / 100.0,
            bytes,
        })
    }
}

/// Refuses a frame rate a GIF cannot keep (see [`GIF_MAX_FPS`]) with one line naming the file.
pub fn check_gif_fps(path: &Path, fps: f64) -> Result<f64, VideoError> {
    let fps = check_fps(fps).map_err(|e| VideoError::Codec {
        path: path.to_path_buf(),
        what: "frame rate",
        message: e.to_string(),
    })?;
    if fps > GIF_MAX_FPS {
        return Err(VideoError::Codec {
            path: path.to_path_buf(),
            what: "frame rate",
            message: format!(
                "a GIF shows at most {GIF_MAX_FPS} frames/s (its delays are hundredths of a second), not {fps}; use --fps {GIF_MAX_FPS} or an .mp4 movie"
            ),
        });
    }
    Ok(fps)
}

/// The size as GIF fields, or one line naming the file when a side is 0 or too large.
pub fn check_gif_size(path: &Path, [w, h]: [u32; 2]) -> Result<[u16; 2], VideoError> {
    match (u16::try_from(w), u16::try_from(h)) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok([w, h]),
        _ => Err(VideoError::Codec {
            path: path.to_path_buf(),
            what: "picture size",
            message: format!("a GIF's sides are 1 to {GIF_MAX_SIDE} pixels, not {w}x{h}"),
        }),
    }
}

/// NeuQuant's sampling factor for a quality preset (1 samples every pixel).
fn neuquant_speed(quality: VideoQuality) -> i32 {
    match quality {
        VideoQuality::Low => 20,
        VideoQuality::Medium => 10,
        VideoQuality::High => 3,
    }
}

/// The running time in hundredths of a second at the start of frame `index`.
fn running_cs(index: usize, fps: f64) -> u64 {
    (index as f64 * 100.0 / fps).round() as u64
}

/// Frame `index`'s delay in hundredths of a second (see the module's comment).
fn delay_cs(index: usize, fps: f64) -> u16 {
    let d = running_cs(index + 1, fps) - running_cs(index, fps);
    d.clamp(1, u64::from(u16::MAX)) as u16
}

fn encoding(path: &Path, what: &'static str, e: gif::EncodingError) -> VideoError {
    match e {
        gif::EncodingError::Io(io) => super::ExportError::io(path, io).into(),
        e => VideoError::Codec {
            path: path.to_path_buf(),
            what,
            message: e.to_string(),
        },
    }
}

/// One part as read for a merge: its frames' compressed data is kept as it is.
fn open_gif_part(path: &Path) -> Result<gif::Decoder<BufReader<File>>, String> {
    let file = File::open(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let mut options = gif::DecodeOptions::new();
    options.skip_frame_decoding(true);
    options.check_frame_consistency(true);
    options
        .read_info(BufReader::new(file))
        .map_err(|e| format!("{}: not a GIF movie: {e}", path.display()))
}

/// A GIF part's size (pixels), frame count and running time (hundredths of a second).
struct PartTiming {
    size: [u16; 2],
    frames: u64,
    centis: u64,
}

impl PartTiming {
    /// Reads the part's header and every frame's delay (the pixels stay compressed).
    fn read(path: &Path) -> Result<Self, String> {
        let mut d = open_gif_part(path)?;
        let size = [d.width(), d.height()];
        let (mut frames, mut centis) = (0u64, 0u64);
        while let Some(frame) = d
            .read_next_frame()
            .map_err(|e| format!("{}: frame {frames}: {e}", path.display()))?
        {
            frames += 1;
            centis += u64::from(frame.delay);
        }
        Ok(PartTiming {
            size,
            frames,
            centis,
        })
    }

    /// Frames per second over the part (its delays are rounded on the running time, so the
    /// whole part keeps the rate to 1 / 100 s).
    fn fps(&self) -> f64 {
        self.frames as f64 * 100.0 / (self.centis.max(1) as f64)
    }

    /// Whether `self` and `other` can be one movie's parts at one frame rate: the mean
    /// delays agree within what rounding the running time to 1 / 100 s allows (under
    /// 1 / frames hundredths each).
    fn same_rate(&self, other: &PartTiming) -> bool {
        let mean = |p: &PartTiming| p.centis as f64 / p.frames.max(1) as f64;
        let allowed = 1.0 / self.frames.max(1) as f64 + 1.0 / other.frames.max(1) as f64;
        (mean(self) - mean(other)).abs() <= allowed + 1e-9
    }
}

/// Joins the GIF parts `paths` (in chunk order, checked by the caller to be complete) into
/// `movie`, atomically: every frame is copied as it is (palette, delay, compressed pixels).
/// Fails with one line naming the part when one is not a GIF, or has another size or frame
/// rate than the first.
pub fn merge_gif_parts(movie: &Path, paths: &[PathBuf]) -> Result<MovieSummary, String> {
    let Some(first) = paths.first() else {
        return Err(format!("{}: no parts to merge", movie.display()));
    };
    let first_part = PartTiming::read(first)?;
    let size = first_part.size;
    // Every part is checked before anything is written.
    for path in &paths[1..] {
        let part = PartTiming::read(path)?;
        if part.size != size {
            return Err(format!(
                "{}: {}x{} pixels, {} has {}x{}",
                path.display(),
                part.size[0],
                part.size[1],
                first.display(),
                size[0],
                size[1]
            ));
        }
        if !part.same_rate(&first_part) {
            return Err(format!(
                "{}: {:.2} frames/s, {} has {:.2} (--fps?)",
                path.display(),
                part.fps(),
                first.display(),
                first_part.fps()
            ));
        }
    }
    let file = AtomicFile::create(movie).map_err(|e| e.to_string())?;
    let fail = |e: gif::EncodingError| encoding(movie, "cannot write", e).to_string();
    let mut out = Encoder::new(file, size[0], size[1], &[]).map_err(fail)?;
    out.set_repeat(Repeat::Infinite).map_err(fail)?;
    let (mut frames, mut centis) = (0usize, 0u64);
    for path in paths {
        let mut part = open_gif_part(path)?;
        while let Some(frame) = part
            .read_next_frame()
            .map_err(|e| format!("{}: frame {frames}: {e}", path.display()))?
        {
            out.write_lzw_pre_encoded_frame(frame).map_err(fail)?;
            frames += 1;
            centis += u64::from(frame.delay);
        }
    }
    let mut file = out.into_inner().map_err(fail)?;
    let bytes = file
        .stream_position()
        .map_err(|e| super::ExportError::io(movie, e).to_string())?;
    file.commit().map_err(|e| e.to_string())?;
    Ok(MovieSummary {
        frames,
        seconds: centis as f64 / 100.0,
        bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_keep_the_running_time() {
        let delays: Vec<u16> = (0..6).map(|i| delay_cs(i, 30.0)).collect();
        assert_eq!(delays, [3, 4, 3, 3, 4, 3]);
        let total: u64 = (0..300).map(|i| u64::from(delay_cs(i, 30.0))).sum();
        assert_eq!(total, 1000);
        // A chunk's part continues the running time of the frames before it.
        let split: u64 = (100..300).map(|i| u64::from(delay_cs(i, 30.0))).sum();
        assert_eq!(split, running_cs(300, 30.0) - running_cs(100, 30.0));
    }

    /// The timing of the part holding frames `frames` of a movie at `fps`.
    fn part(frames: std::ops::Range<usize>, fps: f64) -> PartTiming {
        PartTiming {
            size: [8, 8],
            frames: frames.len() as u64,
            centis: frames.map(|i| u64::from(delay_cs(i, fps))).sum(),
        }
    }

    #[test]
    fn parts_of_one_rate_agree_and_other_rates_do_not() {
        // Every split of a 30 frames/s movie, however its delays round, is one rate.
        for fps in [30.0, 24.0, 29.97, 50.0, 7.0] {
            for cut in 1..40 {
                let (a, b) = (part(0..cut, fps), part(cut..40, fps));
                assert!(a.same_rate(&b) && b.same_rate(&a), "{fps} cut at {cut}");
            }
        }
        assert!(!part(0..10, 30.0).same_rate(&part(10..20, 25.0)));
        assert!(!part(0..3, 30.0).same_rate(&part(3..6, 10.0)));
        assert!((part(0..30, 30.0).fps() - 30.0).abs() < 1e-9);
    }

    #[test]
    fn fast_rates_and_huge_sizes_are_refused_in_one_line() {
        let p = Path::new("m.gif");
        assert_eq!(check_gif_fps(p, 50.0).ok(), Some(50.0));
        let e = check_gif_fps(p, 60.0).expect_err("too fast").to_string();
        assert!(
            e.starts_with("m.gif") && e.contains("60") && !e.contains('\n'),
            "{e}"
        );
        assert!(check_gif_fps(p, f64::NAN).is_err());
        assert_eq!(check_gif_size(p, [640, 480]).ok(), Some([640, 480]));
        let e = check_gif_size(p, [70_000, 10])
            .expect_err("too wide")
            .to_string();
        assert!(e.contains("70000x10") && !e.contains('\n'), "{e}");
    }
}
