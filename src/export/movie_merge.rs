//! `mdsurf merge MOVIE.mp4`: joins the MP4 parts that the chunks of a job array wrote
//! (`MOVIE.part-IIII-of-NNNN.mp4`, from `render --chunk`) into one movie without re-encoding.
//! (`MOVIE.gif` parts are joined frame by frame as they are: [`super::gif_movie`].)
//! Each part is an H.264 stream that starts with a key frame; the merged file holds every part's
//! samples in chunk order, byte for byte, with their durations, under one track whose SPS and
//! PPS all parts share. Written atomically: a failed merge leaves no movie.

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use mp4::{MediaType, Mp4Reader, Mp4Sample, TrackType};

use super::ExportError;
use super::gif_movie::merge_gif_parts;
use super::movie::MovieFormat;
use super::stats_merge::{MergeError, check_one_chunk_count, find_parts, part_path, show_pattern};
use super::video::{TIMESCALE, avc_track, mux, start_mp4};

/// What [`merge_movie_parts`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct MovieMergeSummary {
    /// The part files read, in chunk order.
    pub parts: Vec<PathBuf>,
    /// Frames in the merged movie.
    pub frames: usize,
    /// Its length in seconds.
    pub seconds: f64,
    /// Its size in bytes.
    pub bytes: u64,
}

/// One part's video track: what must agree across parts, and where its samples are.
struct Part {
    path: PathBuf,
    reader: Mp4Reader<BufReader<File>>,
    track: u32,
    samples: u32,
    size: [u32; 2],
    sps: Vec<u8>,
    pps: Vec<u8>,
    /// The first frame's duration in [`TIMESCALE`] ticks (the frame rate).
    first_duration: u32,
}

/// Joins the parts of `movie` (see [`part_path`]) into `movie`, atomically. Fails with one line
/// naming the file when there are no parts, parts of runs with different chunk counts, a missing
/// part, a part that is not an H.264 movie of this tool's making, or parts of different sizes,
/// encodings or frame rates.
pub fn merge_movie_parts(movie: &Path) -> Result<MovieMergeSummary, MergeError> {
    let invalid = MergeError::Invalid;
    let found = find_parts(movie)?;
    let Some(&(_, count, _)) = found.first() else {
        return Err(invalid(format!(
            "{}: no parts to merge (render --chunk writes them)",
            show_pattern(movie)
        )));
    };
    check_one_chunk_count(movie, &found)?;
    let present: BTreeSet<usize> = found.iter().map(|(i, _, _)| *i).collect();
    if let Some(missing) = (0..count).find(|i| !present.contains(i)) {
        return Err(invalid(format!(
            "{}: missing (chunk {missing} of {count}); render it before merging",
            part_path(movie, missing, count).display()
        )));
    }
    // Every part is checked before anything is written, one open file at a time (an array
    // of a thousand tasks would pass the usual limit of open files): each is opened again to
    // copy its frames.
    let paths: Vec<&PathBuf> = found.iter().map(|(_, _, p)| p).collect();
    if MovieFormat::of(movie) == Some(MovieFormat::Gif) {
        let parts: Vec<PathBuf> = paths.into_iter().cloned().collect();
        let s = merge_gif_parts(movie, &parts).map_err(invalid)?;
        return Ok(MovieMergeSummary {
            parts,
            frames: s.frames,
            seconds: s.seconds,
            bytes: s.bytes,
        });
    }
    let first = open_part(paths[0])?;
    for path in &paths[1..] {
        check_same(&first, &open_part(path)?)?;
    }
    let mut out = start_mp4(movie).map_err(|e| invalid(e.to_string()))?;
    let track = avc_track(first.size, first.sps.clone(), first.pps.clone());
    out.add_track(&track)
        .map_err(|e| invalid(mux(movie, e).to_string()))?;
    let (mut ticks, mut frames) = (0u64, 0usize);
    let mut opened_first = Some(first);
    for path in &paths {
        let mut part = match opened_first.take() {
            Some(first) => first,
            None => open_part(path)?,
        };
        for id in 1..=part.samples {
            let sample = read_sample(&mut part, id)?;
            let shifted = Mp4Sample {
                start_time: ticks,
                ..sample
            };
            ticks += u64::from(shifted.duration);
            out.write_sample(1, &shifted)
                .map_err(|e| invalid(mux(movie, e).to_string()))?;
            frames += 1;
        }
    }
    out.write_end()
        .map_err(|e| invalid(mux(movie, e).to_string()))?;
    let mut file = out.into_writer();
    let bytes = file
        .stream_position()
        .map_err(|e| ExportError::io(movie, e))?;
    file.commit()?;
    Ok(MovieMergeSummary {
        parts: paths.into_iter().cloned().collect(),
        frames,
        seconds: ticks as f64 / f64::from(TIMESCALE),
        bytes,
    })
}

/// Reads a part's header and its one H.264 track. The MP4 reader is a third-party parser: a
/// damaged part (a chunk killed while writing, say) that makes it panic is reported as
/// unreadable instead.
fn open_part(path: &Path) -> Result<Part, MergeError> {
    let bad = |why: String| MergeError::Invalid(format!("{}: {why}", path.display()));
    let file = File::open(path).map_err(|e| ExportError::io(path, e))?;
    let len = file.metadata().map_err(|e| ExportError::io(path, e))?.len();
    let mut file = BufReader::new(file);
    check_boxes(&mut file, 0, len, 0)
        .map_err(|e| bad(format!("not a readable MP4 movie ({e})")))?;
    file.rewind().map_err(|e| ExportError::io(path, e))?;
    let reader = match quietly(|| Mp4Reader::read_header(file, len)) {
        Some(Ok(r)) => r,
        Some(Err(e)) => return Err(bad(format!("not a readable MP4 movie ({e})"))),
        None => return Err(bad("not a readable MP4 movie (damaged)".into())),
    };
    let video: Vec<_> = reader
        .tracks()
        .values()
        .filter(|t| matches!(t.track_type(), Ok(TrackType::Video)))
        .collect();
    let [track] = video.as_slice() else {
        return Err(bad(format!(
            "{} video tracks, a part of render --chunk has one",
            video.len()
        )));
    };
    if !matches!(track.media_type(), Ok(MediaType::H264)) || track.timescale() != TIMESCALE {
        return Err(bad(
            "not an H.264 movie written by mdsurf render (another codec or clock)".into(),
        ));
    }
    let samples = track.sample_count();
    // Every sample takes at least one byte of the file: more is a damaged index.
    if samples == 0 || u64::from(samples) > len {
        return Err(bad(format!("{samples} frames in a file of {len} bytes")));
    }
    let (Ok(sps), Ok(pps)) = (
        track.sequence_parameter_set(),
        track.picture_parameter_set(),
    ) else {
        return Err(bad("its H.264 track has no SPS/PPS".into()));
    };
    let mut part = Part {
        path: path.to_path_buf(),
        size: [u32::from(track.width()), u32::from(track.height())],
        sps: sps.to_vec(),
        pps: pps.to_vec(),
        track: track.track_id(),
        samples,
        first_duration: 0,
        reader,
    };
    let first = read_sample(&mut part, 1)?;
    if !first.is_sync {
        return Err(bad("it does not start with a key frame".into()));
    }
    part.first_duration = first.duration;
    Ok(part)
}

/// Runs `f`, a call into the MP4 parser, and turns a panic of it into `None` without the panic
/// hook's report (the caller reports a damaged part in one line).
fn quietly<T>(f: impl FnOnce() -> T) -> Option<T> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = catch_unwind(AssertUnwindSafe(f)).ok();
    std::panic::set_hook(hook);
    result
}

/// The boxes that hold only boxes, down to the sample tables.
const CONTAINERS: [&[u8; 4]; 7] = [
    b"moov", b"trak", b"mdia", b"minf", b"stbl", b"dinf", b"edts",
];

/// Checks that the boxes from `start` to `end` (bytes) tile their parent exactly, each at least
/// a header long, and likewise inside the containers: the MP4 parser loops for ever on a box
/// of size 0 inside `moov` (found by corrupting parts), so a damaged index is refused first.
fn check_boxes(
    file: &mut BufReader<File>,
    start: u64,
    end: u64,
    depth: usize,
) -> Result<(), String> {
    let mut at = start;
    while at < end {
        file.seek(SeekFrom::Start(at)).map_err(|e| e.to_string())?;
        let mut header = [0u8; 8];
        file.read_exact(&mut header)
            .map_err(|_| format!("a box header cut at byte {at}"))?;
        let kind: [u8; 4] = header[4..8].try_into().expect("4 bytes");
        let (mut size, mut body) = (
            u64::from(u32::from_be_bytes(header[..4].try_into().expect("4 bytes"))),
            at + 8,
        );
        if size == 1 {
            let mut large = [0u8; 8];
            file.read_exact(&mut large)
                .map_err(|_| format!("a box header cut at byte {at}"))?;
            size = u64::from_be_bytes(large);
            body += 8;
        }
        let name: String = kind
            .iter()
            .map(|&b| {
                if b.is_ascii_graphic() || b == b' ' {
                    char::from(b)
                } else {
                    '?'
                }
            })
            .collect();
        if size < body - at || size > end - at {
            return Err(format!(
                "box '{name}' at byte {at} has size {size}, {} bytes are left",
                end - at
            ));
        }
        if depth < 8 && CONTAINERS.iter().any(|c| **c == kind) {
            check_boxes(file, body, at + size, depth + 1)?;
        }
        at += size;
    }
    Ok(())
}

/// Sample `id` (from 1) of a part.
fn read_sample(part: &mut Part, id: u32) -> Result<Mp4Sample, MergeError> {
    let (track, path) = (part.track, &part.path);
    match quietly(|| part.reader.read_sample(track, id)) {
        Some(Ok(Some(sample))) => Ok(sample),
        Some(Ok(None)) | None => Err(MergeError::Invalid(format!(
            "{}: frame {id} cannot be read (a damaged part?)",
            path.display()
        ))),
        Some(Err(e)) => Err(MergeError::Invalid(format!(
            "{}: frame {id} cannot be read ({e})",
            path.display()
        ))),
    }
}

/// Refuses a part that cannot follow the first one in one stream.
fn check_same(first: &Part, part: &Part) -> Result<(), MergeError> {
    let differs = if part.size != first.size {
        Some(format!(
            "{}x{} pixels, {} has {}x{}",
            part.size[0],
            part.size[1],
            first.path.display(),
            first.size[0],
            first.size[1]
        ))
    } else if part.first_duration.abs_diff(first.first_duration) > 1 {
        let fps = |d: u32| f64::from(TIMESCALE) / f64::from(d.max(1));
        Some(format!(
            "{:.3} frames/s, {} has {:.3}",
            fps(part.first_duration),
            first.path.display(),
            fps(first.first_duration)
        ))
    } else if (&part.sps, &part.pps) != (&first.sps, &first.pps) {
        Some(format!(
            "other encoder settings than {} (--video-quality?)",
            first.path.display()
        ))
    } else {
        None
    };
    match differs {
        Some(why) => Err(MergeError::Invalid(format!(
            "{}: {why}; parts of runs with different settings are not merged",
            part.path.display()
        ))),
        None => Ok(()),
    }
}
