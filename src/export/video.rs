//! Movies: rendered RGBA images in, one H.264 video in an MP4 file out. The images are converted
//! to YUV 4:2:0 (BT.601, limited range, as the stream's VUI says), encoded by OpenH264 (built from
//! its bundled source) and muxed by the `mp4` crate into a temporary file beside the target,
//! which is renamed over it only by [`Mp4Movie::finish`] (see [`super::atomic`]): a failed or
//! abandoned movie leaves no file.

use std::fmt;
use std::io::{self, Seek, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;

use mp4::{AvcConfig, MediaConfig, Mp4Config, Mp4Sample, Mp4Writer, TrackConfig, TrackType};
use openh264::OpenH264API;
use openh264::encoder::{
    BitRate, Complexity, Encoder, EncoderConfig, FrameRate, IntraFramePeriod, QpRange,
    RateControlMode, UsageType, VuiConfig,
};
use openh264::formats::YUVBuffer;

use super::{AtomicFile, ExportError};
use crate::render::RgbaImage;

/// The MP4 track's clock: 90 kHz, the usual video clock (integer frame durations for 24, 25,
/// 30, 50, 60 and 29.97 frames/s).
pub(crate) const TIMESCALE: u32 = 90_000;

/// The lowest and highest frame rates accepted, frames per second.
pub const FPS_RANGE: (f64, f64) = (0.1, 240.0);

/// Why a movie could not be written.
#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    /// H.264 with 4:2:0 chroma needs even sides.
    #[error(
        "{}: an H.264 movie needs an even width and height, not {w}x{h} (try --size {}x{})",
        path.display(), (w & !1).max(2), (h & !1).max(2)
    )]
    OddSize {
        /// The output path.
        path: PathBuf,
        /// Width in pixels.
        w: u32,
        /// Height in pixels.
        h: u32,
    },
    /// An image of another size than the movie's.
    #[error("{}: image {index} is {got_w}x{got_h}, the movie is {w}x{h}", path.display())]
    SizeChanged {
        /// The output path.
        path: PathBuf,
        /// Image number (from 0).
        index: usize,
        /// The image's width.
        got_w: u32,
        /// The image's height.
        got_h: u32,
        /// The movie's width.
        w: u32,
        /// The movie's height.
        h: u32,
    },
    /// The encoder or the muxer failed.
    #[error("{}: {what}: {message}", path.display())]
    Codec {
        /// The output path.
        path: PathBuf,
        /// Which step (encoding, muxing).
        what: &'static str,
        /// What went wrong.
        message: String,
    },
    /// Creating, writing or renaming the file failed.
    #[error(transparent)]
    Export(#[from] ExportError),
}

/// Quality presets: each caps the quantiser (lower is better) and sets a target bit rate in
/// bits per pixel per frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VideoQuality {
    /// Small files: QP up to 34, about 0.05 bit per pixel.
    Low,
    /// The default: QP up to 26, about 0.15 bit per pixel.
    #[default]
    Medium,
    /// Near transparent: QP up to 20, about 0.4 bit per pixel.
    High,
}

impl VideoQuality {
    /// All presets, worst first.
    pub const ALL: [VideoQuality; 3] =
        [VideoQuality::Low, VideoQuality::Medium, VideoQuality::High];

    /// The preset's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            VideoQuality::Low => "low",
            VideoQuality::Medium => "medium",
            VideoQuality::High => "high",
        }
    }

    /// (lowest QP, highest QP, target bits per pixel per frame).
    fn tuning(self) -> (u8, u8, f64) {
        match self {
            VideoQuality::Low => (16, 34, 0.05),
            VideoQuality::Medium => (12, 26, 0.15),
            VideoQuality::High => (8, 20, 0.4),
        }
    }
}

impl fmt::Display for VideoQuality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A video option that cannot be used; prints as one line naming the value as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VideoOptionError {
    /// A quality name that is not known.
    #[error("bad video quality '{0}': expected low, medium or high")]
    Quality(String),
    /// A frame rate outside [`FPS_RANGE`] or not finite.
    #[error(
        "bad frame rate {0}: expected {lo} to {hi} frames per second",
        lo = FPS_RANGE.0,
        hi = FPS_RANGE.1
    )]
    Fps(f64),
}

impl FromStr for VideoQuality {
    type Err = VideoOptionError;

    fn from_str(s: &str) -> Result<Self, VideoOptionError> {
        VideoQuality::ALL
            .into_iter()
            .find(|q| q.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| VideoOptionError::Quality(s.to_string()))
    }
}

/// Checks a frame rate: finite and within [`FPS_RANGE`].
pub fn check_fps(fps: f64) -> Result<f64, VideoOptionError> {
    if fps.is_finite() && (FPS_RANGE.0..=FPS_RANGE.1).contains(&fps) {
        Ok(fps)
    } else {
        Err(VideoOptionError::Fps(fps))
    }
}

/// Whether `path` names an MP4 movie (`.mp4`, any case).
pub fn is_mp4(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mp4"))
}

/// Refuses odd sides (H.264 4:2:0 needs even ones), with the nearest even size as a hint.
pub fn check_even_size(path: &Path, [w, h]: [u32; 2]) -> Result<(), VideoError> {
    if w % 2 == 1 || h % 2 == 1 || w == 0 || h == 0 {
        return Err(VideoError::OddSize {
            path: path.to_path_buf(),
            w,
            h,
        });
    }
    Ok(())
}

/// Refuses image `index` of the movie `path` when it is not of the movie's `size`.
pub(crate) fn check_image_size(
    path: &Path,
    index: usize,
    image: &RgbaImage,
    [w, h]: [u32; 2],
) -> Result<(), VideoError> {
    if [image.width, image.height] == [w, h] {
        return Ok(());
    }
    Err(VideoError::SizeChanged {
        path: path.to_path_buf(),
        index,
        got_w: image.width,
        got_h: image.height,
        w,
        h,
    })
}

/// What a finished movie holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MovieSummary {
    /// Frames written.
    pub frames: usize,
    /// Duration in seconds.
    pub seconds: f64,
    /// File size in bytes.
    pub bytes: u64,
}

/// An MP4 movie being written. Dropping it without [`Mp4Movie::finish`] deletes the temporary
/// file and leaves any existing target untouched.
pub struct Mp4Movie {
    path: PathBuf,
    size: [u32; 2],
    fps: f64,
    encoder: Encoder,
    mp4: Mp4Writer<AtomicFile>,
    /// Whether the track (which needs the first frame's SPS and PPS) has been added.
    track: bool,
    frames: usize,
    /// Start of the next frame in [`TIMESCALE`] ticks.
    ticks: u64,
}

impl Mp4Movie {
    /// Starts a movie of `size` pixels at `fps` frames per second in `path` (written to a
    /// temporary file until [`Mp4Movie::finish`]).
    pub fn create(
        path: &Path,
        size: [u32; 2],
        fps: f64,
        quality: VideoQuality,
    ) -> Result<Mp4Movie, VideoError> {
        check_even_size(path, size)?;
        let fps = check_fps(fps).map_err(|e| codec(path, "frame rate", e.to_string()))?;
        let (qp_min, qp_max, bpp) = quality.tuning();
        let pixels = f64::from(size[0]) * f64::from(size[1]);
        let bps = (bpp * pixels * fps).clamp(64_000.0, 400e6) as u32;
        let config = EncoderConfig::new()
            .usage_type(UsageType::CameraVideoRealTime)
            .rate_control_mode(RateControlMode::Quality)
            .bitrate(BitRate::from_bps(bps))
            .qp(QpRange::new(qp_min, qp_max))
            .max_frame_rate(FrameRate::from_hz(fps as f32))
            .skip_frames(false)
            .complexity(Complexity::High)
            // A key frame about every 2 s, so players can seek.
            .intra_frame_period(IntraFramePeriod::from_num_frames(
                (2.0 * fps).round().clamp(1.0, 600.0) as u32,
            ))
            .vui(VuiConfig::bt601());
        let mut encoder = Encoder::with_api_config(OpenH264API::from_source(), config)
            .map_err(|e| codec(path, "cannot start the H.264 encoder", e.to_string()))?;
        // OpenH264 logs to stderr from its first encode (a warning for every quality-mode
        // stream, three lines on failures, which our one-line error already reports): quiet.
        let mut level = openh264_sys2::WELS_LOG_QUIET as std::os::raw::c_int;
        // SAFETY: the trace level may be set before initialisation; the option is read as a
        // c_int through a pointer that outlives the call.
        unsafe {
            encoder.raw_api().set_option(
                openh264_sys2::ENCODER_OPTION_TRACE_LEVEL,
                (&raw mut level).cast(),
            );
        }
        let mp4 = start_mp4(path)?;
        Ok(Mp4Movie {
            path: path.to_path_buf(),
            size,
            fps,
            encoder,
            mp4,
            track: false,
            frames: 0,
            ticks: 0,
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

    /// Encodes `image` as the next frame (alpha is ignored).
    pub fn push(&mut self, image: &RgbaImage) -> Result<(), VideoError> {
        let [w, h] = self.size;
        check_image_size(&self.path, self.frames, image, self.size)?;
        let mut planes = Vec::new();
        rgba_to_i420(&image.pixels, w as usize, h as usize, &mut planes);
        let yuv = YUVBuffer::from_vec(planes, w as usize, h as usize);
        let millis = (self.frames as f64 * 1000.0 / self.fps).round() as u64;
        let stream = self
            .encoder
            .encode_at(&yuv, openh264::Timestamp::from_millis(millis))
            .map_err(|e| codec(&self.path, "H.264 encoding failed", e.to_string()))?;
        let mut sps = None;
        let mut pps = None;
        let mut sample = Vec::new();
        let mut idr = false;
        for l in 0..stream.num_layers() {
            let Some(layer) = stream.layer(l) else {
                continue;
            };
            for n in 0..layer.nal_count() {
                let Some(nal) = layer.nal_unit(n).map(strip_start_code) else {
                    continue;
                };
                match nal.first().map(|b| b & 0x1f) {
                    Some(7) => sps = Some(nal.to_vec()),
                    Some(8) => pps = Some(nal.to_vec()),
                    Some(t) => {
                        idr |= t == 5;
                        sample.extend_from_slice(&(nal.len() as u32).to_be_bytes());
                        sample.extend_from_slice(nal);
                    }
                    None => {}
                }
            }
        }
        if !self.track {
            let (Some(seq_param_set), Some(pic_param_set)) = (sps, pps) else {
                return Err(codec(
                    &self.path,
                    "H.264 encoding failed",
                    "the first frame has no SPS/PPS".into(),
                ));
            };
            let track = avc_track(self.size, seq_param_set, pic_param_set);
            self.mp4.add_track(&track).map_err(|e| mux(&self.path, e))?;
            self.track = true;
        }
        if sample.is_empty() {
            return Err(codec(
                &self.path,
                "H.264 encoding failed",
                format!("the encoder returned no picture for frame {}", self.frames),
            ));
        }
        let next = ((self.frames + 1) as f64 * f64::from(TIMESCALE) / self.fps).round() as u64;
        let duration = (next - self.ticks).max(1) as u32;
        let sample = Mp4Sample {
            start_time: self.ticks,
            duration,
            rendering_offset: 0,
            is_sync: idr,
            bytes: sample.into(),
        };
        self.mp4
            .write_sample(1, &sample)
            .map_err(|e| mux(&self.path, e))?;
        self.ticks += u64::from(duration);
        self.frames += 1;
        Ok(())
    }

    /// Writes the index, syncs and renames the movie into place.
    pub fn finish(mut self) -> Result<MovieSummary, VideoError> {
        if self.frames == 0 {
            return Err(codec(
                &self.path,
                "cannot write a movie",
                "no frames".into(),
            ));
        }
        self.mp4.write_end().map_err(|e| mux(&self.path, e))?;
        let mut file = self.mp4.into_writer();
        let bytes = file
            .stream_position()
            .map_err(|e| ExportError::io(&self.path, e))?;
        file.commit()?;
        Ok(MovieSummary {
            frames: self.frames,
            seconds: self.ticks as f64 / f64::from(TIMESCALE),
            bytes,
        })
    }
}

/// Starts an MP4 file (ISO brands, millisecond movie clock) in a temporary file beside `path`.
pub(crate) fn start_mp4(path: &Path) -> Result<Mp4Writer<AtomicFile>, VideoError> {
    let file = AtomicFile::create(path)?;
    let brands = ["isom", "iso2", "avc1", "mp41"];
    let config = Mp4Config {
        major_brand: brands[0].parse().expect("four letters"),
        minor_version: 512,
        compatible_brands: brands
            .iter()
            .map(|b| b.parse().expect("four letters"))
            .collect(),
        timescale: 1000,
    };
    Mp4Writer::write_start(file, &config).map_err(|e| mux(path, e))
}

/// The H.264 video track of `size` pixels with its SPS and PPS, on the [`TIMESCALE`] clock.
pub(crate) fn avc_track([w, h]: [u32; 2], sps: Vec<u8>, pps: Vec<u8>) -> TrackConfig {
    TrackConfig {
        track_type: TrackType::Video,
        timescale: TIMESCALE,
        language: "und".into(),
        media_conf: MediaConfig::AvcConfig(AvcConfig {
            width: w as u16,
            height: h as u16,
            seq_param_set: sps,
            pic_param_set: pps,
        }),
    }
}

fn codec(path: &Path, what: &'static str, message: String) -> VideoError {
    VideoError::Codec {
        path: path.to_path_buf(),
        what,
        message,
    }
}

pub(crate) fn mux(path: &Path, e: mp4::Error) -> VideoError {
    match e {
        mp4::Error::IoError(io) => ExportError::io(path, io).into(),
        e => codec(path, "MP4 muxing failed", e.to_string()),
    }
}

/// A NAL unit without its Annex B start code (00 00 01 or 00 00 00 01).
fn strip_start_code(nal: &[u8]) -> &[u8] {
    if let Some(rest) = nal.strip_prefix(&[0, 0, 0, 1]) {
        rest
    } else if let Some(rest) = nal.strip_prefix(&[0, 0, 1]) {
        rest
    } else {
        nal
    }
}

/// Converts 8-bit RGBA (`w * h * 4` bytes, `w` and `h` even) to planar I420 in `out`: BT.601
/// limited range (Y 16..235, Cb/Cr 16..240), each chroma sample the mean of a 2x2 block,
/// rounded to nearest.
pub fn rgba_to_i420(rgba: &[u8], w: usize, h: usize, out: &mut Vec<u8>) {
    out.clear();
    out.resize(w * h * 3 / 2, 0);
    let (y_plane, chroma) = out.split_at_mut(w * h);
    let (u_plane, v_plane) = chroma.split_at_mut(w * h / 4);
    for (i, px) in rgba.chunks_exact(4).take(w * h).enumerate() {
        let (r, g, b) = (i32::from(px[0]), i32::from(px[1]), i32::from(px[2]));
        y_plane[i] = (((66 * r + 129 * g + 25 * b + 128) >> 8) + 16) as u8;
    }
    for cy in 0..h / 2 {
        for cx in 0..w / 2 {
            let (mut r, mut g, mut b) = (0, 0, 0);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = ((2 * cy + dy) * w + 2 * cx + dx) * 4;
                r += i32::from(rgba[p]);
                g += i32::from(rgba[p + 1]);
                b += i32::from(rgba[p + 2]);
            }
            // Sums of four: the 2x2 mean is folded into the shift (>> 10 instead of >> 8).
            let u = ((-38 * r - 74 * g + 112 * b + 512) >> 10) + 128;
            let v = ((112 * r - 94 * g - 18 * b + 512) >> 10) + 128;
            u_plane[cy * (w / 2) + cx] = u.clamp(0, 255) as u8;
            v_plane[cy * (w / 2) + cx] = v.clamp(0, 255) as u8;
        }
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer().write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer().flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
        self.writer().seek(pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_white_black_convert_to_limited_range() {
        let mut out = Vec::new();
        let px = |v: u8| [v, v, v, 255];
        let rgba: Vec<u8> = [px(0), px(255), px(0), px(255)].concat();
        rgba_to_i420(&rgba, 2, 2, &mut out);
        assert_eq!(&out[..4], &[16, 235, 16, 235]);
        assert_eq!(&out[4..], &[128, 128]);
    }

    #[test]
    fn odd_sizes_and_bad_rates_are_refused_in_one_line() {
        let e = check_even_size(Path::new("m.mp4"), [161, 120]).expect_err("odd");
        let text = e.to_string();
        assert!(
            text.contains("161x120") && text.contains("160x120"),
            "{text}"
        );
        assert!(!text.contains('\n'));
        assert!(check_even_size(Path::new("m.mp4"), [160, 120]).is_ok());
        assert!(check_fps(0.0).is_err() && check_fps(f64::NAN).is_err());
        assert_eq!(check_fps(24.0), Ok(24.0));
        assert_eq!("HIGH".parse(), Ok(VideoQuality::High));
        assert!("best".parse::<VideoQuality>().is_err());
    }
}
