//! What our text trajectory readers ([`super::gro`], [`super::lammps`]) share: lines ended by
//! `\n`, `\r\n` or a lone `\r` (old Mac files), a UTF-8 byte-order mark skipped at the start of
//! a file, a scanner that walks a file line by line in 1 MiB chunks to index its frames (a
//! multi-GB trajectory is never held in memory whole), the bytes of one frame read back on
//! request ([`SpanFrames`], the open file both readers hand out), and chemfiles' rules for a
//! periodic box (a box they refuse is a [`BoxError`]).

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::IoError;
use super::native::{NativeFrames, NativeOpen};
use super::prepare::Prepared;
use crate::model::{Frame, Topology};

/// The UTF-8 byte-order mark some editors put at the start of a text file.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Bytes read at a time while indexing.
const CHUNK: usize = 1 << 20;

/// Where one frame sits in its file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FrameSpan {
    /// Byte offset of the frame's first line.
    pub start: u64,
    /// Byte offset just past the frame's last line (and its line end).
    pub end: u64,
    /// Line number (from 1) of the frame's first line, for messages.
    pub line: u64,
}

/// The first line of `bytes` (without its line end) and the bytes after it.
pub(crate) fn split_line(bytes: &[u8]) -> (&[u8], &[u8]) {
    match memchr::memchr2(b'\n', b'\r', bytes) {
        Some(i) => {
            let crlf = bytes[i] == b'\r' && bytes.get(i + 1) == Some(&b'\n');
            (&bytes[..i], &bytes[i + 1 + usize::from(crlf)..])
        }
        None => (bytes, &bytes[bytes.len()..]),
    }
}

/// The lines of `bytes` (see [`split_line`]); a last line without a line end counts, an empty
/// tail after the last line end does not.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = bytes;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let (line, next) = split_line(rest);
        rest = next;
        Some(line)
    })
}

/// Reads a file line by line, in chunks, keeping each line's byte offset and number.
pub(crate) struct LineScanner {
    file: File,
    buffer: Vec<u8>,
    /// The unread bytes are `buffer[start..end]`.
    start: usize,
    end: usize,
    /// File offset of `buffer[start]`.
    offset: u64,
    /// True once the file has no more bytes to read.
    eof: bool,
    /// Lines returned so far.
    line_number: u64,
}

impl LineScanner {
    /// Opens `path` (the file to scan: the user's, or its decompressed copy) for `shown` (the
    /// file named in messages); a byte-order mark at its start is skipped.
    pub(crate) fn open(path: &Path, shown: &Path) -> Result<Self, IoError> {
        let file = File::open(path).map_err(|e| IoError::NotFound {
            path: shown.to_path_buf(),
            reason: e.to_string(),
        })?;
        let mut scanner = LineScanner {
            file,
            buffer: vec![0; CHUNK],
            start: 0,
            end: 0,
            offset: 0,
            eof: false,
            line_number: 0,
        };
        while scanner.end < BOM.len() && !scanner.eof {
            scanner
                .fill()
                .map_err(|e| IoError::unreadable(shown, e.to_string()))?;
        }
        if scanner.buffer[..scanner.end].starts_with(BOM) {
            scanner.start = BOM.len();
            scanner.offset = BOM.len() as u64;
        }
        Ok(scanner)
    }

    /// Byte offset just past the last line returned (and its line end).
    pub(crate) fn position(&self) -> u64 {
        self.offset
    }

    /// The next line: its byte offset, its number (from 1) and its text (without its line
    /// end); `None` at the end of the file.
    pub(crate) fn next_line(&mut self) -> std::io::Result<Option<(u64, u64, &[u8])>> {
        let (at, from, len) = loop {
            let unread = &self.buffer[self.start..self.end];
            if let Some(i) = memchr::memchr2(b'\n', b'\r', unread) {
                if unread[i] == b'\r' && i + 1 == unread.len() && !self.eof {
                    // A `\r` at the end of the chunk: is a `\n` next?
                    self.fill()?;
                    continue;
                }
                let crlf = unread[i] == b'\r' && unread.get(i + 1) == Some(&b'\n');
                let used = i + 1 + usize::from(crlf);
                let found = (self.offset, self.start, i);
                self.start += used;
                self.offset += used as u64;
                break found;
            }
            if self.eof {
                if unread.is_empty() {
                    return Ok(None);
                }
                let found = (self.offset, self.start, unread.len());
                self.offset += unread.len() as u64;
                self.start = self.end;
                break found;
            }
            self.fill()?;
        };
        self.line_number += 1;
        Ok(Some((at, self.line_number, &self.buffer[from..from + len])))
    }

    /// Reads more of the file after the unread bytes (moved to the front of the buffer, which
    /// grows when one line fills it).
    fn fill(&mut self) -> std::io::Result<()> {
        if self.start > 0 {
            self.buffer.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        if self.end == self.buffer.len() {
            self.buffer.resize(self.buffer.len() * 2, 0);
        }
        loop {
            match self.file.read(&mut self.buffer[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(n) => {
                    self.end += n;
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            }
        }
    }
}

/// Parses the bytes of one frame whose first line is line `first_line` (from 1), for
/// [`SpanFrames`]; the error is one line without the file and frame.
pub(crate) type ParseSpan =
    fn(&[u8], u64) -> Result<Frame, Box<dyn std::error::Error + Send + Sync>>;

/// An open text trajectory whose frames were indexed into spans: each read parses one span,
/// and the frame read last is kept (frame 0 at first: the opening reads it for the topology).
pub(crate) struct SpanFrames {
    /// The format's name (`GRO`, `LAMMPS`).
    pub base: &'static str,
    /// The file as the user named it.
    pub path: PathBuf,
    /// The file read (the decompressed or cleaned copy, when there is one).
    pub file: File,
    /// The whole frames.
    pub spans: Vec<FrameSpan>,
    /// Why the file stops being readable after the spans, when it does.
    pub damage: Option<IoError>,
    /// The frame read last.
    pub cached: Option<Frame>,
    /// The format's parser.
    pub parse: ParseSpan,
    /// Keeps the decompressed or cleaned copy alive.
    pub _prepared: Prepared,
}

impl NativeFrames for SpanFrames {
    fn path(&self) -> &Path {
        &self.path
    }

    fn base(&self) -> &'static str {
        self.base
    }

    fn len(&self) -> usize {
        self.spans.len()
    }

    fn damage(&self) -> Option<&IoError> {
        self.damage.as_ref()
    }

    fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        if let Some(frame) = self.cached.as_ref().filter(|f| f.index == index) {
            return Ok(frame.clone());
        }
        let Some(&span) = self.spans.get(index) else {
            return Err(IoError::FrameOutOfRange {
                path: self.path.clone(),
                frame: index,
                len: self.spans.len(),
            });
        };
        let bytes = read_span(&mut self.file, &self.path, index, span)?;
        let frame = (self.parse)(&bytes, span.line)
            .map_err(|m| IoError::bad_frame(&self.path, index, m))?;
        let frame = Frame { index, ..frame };
        self.cached = Some(frame.clone());
        Ok(frame)
    }
}

/// Opens the text trajectory `path` (its bytes in `prepared`) in the format `base`: indexes its
/// frames with `next_frame` (as [`index_spans`]), reads frame 0 with `first` (the frame and the
/// topology it holds, if any; its error is one line) and hands out the rest through `parse`.
/// A file with neither a whole frame nor a damaged one is empty.
pub(crate) fn open_spans<E: std::fmt::Display, F: std::fmt::Display>(
    path: &Path,
    prepared: Prepared,
    base: &'static str,
    next_frame: impl FnMut(&mut LineScanner) -> std::io::Result<Result<Option<FrameSpan>, E>>,
    first: impl FnOnce(&[u8], u64) -> Result<(Frame, Option<Topology>), F>,
    parse: ParseSpan,
) -> Result<NativeOpen, IoError> {
    let (mut spans, mut damage) = index_spans(path, &prepared.open_path, next_frame)?;
    mark_cut_stream(path, &prepared, &mut spans, &mut damage);
    let mut file = File::open(&prepared.open_path).map_err(|e| IoError::NotFound {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let (topology, cached) = match spans.first() {
        Some(&span) => {
            let bytes = read_span(&mut file, path, 0, span)?;
            let (frame, topology) =
                first(&bytes, span.line).map_err(|m| IoError::bad_frame(path, 0, m))?;
            (topology, Some(Frame { index: 0, ..frame }))
        }
        None => (None, None),
    };
    if let (None, None) = (&topology, &damage) {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
            what: "no frames",
        });
    }
    Ok(NativeOpen {
        topology,
        frames: Box::new(SpanFrames {
            base,
            path: path.to_path_buf(),
            file,
            spans,
            damage,
            cached,
            parse,
            _prepared: prepared,
        }),
    })
}

/// Finds every frame of `file` (`path` in messages) with `next_frame`, which walks over one
/// frame: its span, `None` at the end of the file, or why the frame is cut or damaged. Returns
/// the spans and the error of the first bad frame (the frames before it are whole).
pub(crate) fn index_spans<E: std::fmt::Display>(
    path: &Path,
    file: &Path,
    mut next_frame: impl FnMut(&mut LineScanner) -> std::io::Result<Result<Option<FrameSpan>, E>>,
) -> Result<(Vec<FrameSpan>, Option<IoError>), IoError> {
    let mut scan = LineScanner::open(file, path)?;
    let mut spans = Vec::new();
    loop {
        match next_frame(&mut scan).map_err(|e| IoError::unreadable(path, e.to_string()))? {
            Ok(Some(span)) => spans.push(span),
            Ok(None) => return Ok((spans, None)),
            Err(message) => {
                let damage = IoError::bad_frame(path, spans.len(), message);
                return Ok((spans, Some(damage)));
            }
        }
    }
}

/// The bytes of `span` in `file` (`path` names the file in messages, `frame` the frame).
pub(crate) fn read_span(
    file: &mut File,
    path: &Path,
    frame: usize,
    span: FrameSpan,
) -> Result<Vec<u8>, IoError> {
    let failed = |e: std::io::Error| IoError::bad_frame(path, frame, e.to_string());
    let len = usize::try_from(span.end - span.start)
        .map_err(|_| IoError::bad_frame(path, frame, "the frame is too large for this machine"))?;
    let mut bytes = vec![0u8; len];
    file.seek(SeekFrom::Start(span.start)).map_err(failed)?;
    file.read_exact(&mut bytes).map_err(failed)?;
    Ok(bytes)
}

/// Limits `spans` and sets `damage` when `prepared` says the compressed stream of `path` was
/// cut: the frame it cut (the first one left out of the copy, else the copy's last) is the
/// damage, even when its text happens to parse.
pub(crate) fn mark_cut_stream(
    path: &Path,
    prepared: &Prepared,
    spans: &mut Vec<FrameSpan>,
    damage: &mut Option<IoError>,
) {
    let Some(reason) = &prepared.truncated else {
        return;
    };
    let frame = if prepared.cut_removed || damage.is_some() {
        spans.len()
    } else {
        spans.len().saturating_sub(1)
    };
    spans.truncate(frame);
    *damage = Some(IoError::bad_frame(path, frame, reason));
}

/// Why [`cell_rows`] refuses a box.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum BoxError {
    /// A right-angled box with a negative length among these (a, b, c in Å, or the file's
    /// length unit).
    #[error("the box has a negative length ({} {} {})", .0[0], .0[1], .0[2])]
    NegativeLength([f64; 3]),
    /// Box vectors of negative determinant.
    #[error("the box vectors are left-handed (negative volume)")]
    LeftHanded,
}

/// A periodic box by chemfiles' rules, from its rows a, b, c (Å): `None` for an absent box
/// (every diagonal element within 1e-5 of 0 and no tilt), an error for a negative length or a
/// left-handed (negative determinant) box.
pub(crate) fn cell_rows(rows: [[f64; 3]; 3]) -> Result<Option<[Vec3; 3]>, BoxError> {
    let [a, b, c] = rows;
    let tiny = |v: f64| v.abs() < 1e-5;
    let diagonal = [a[1], a[2], b[0], b[2], c[0], c[1]].into_iter().all(tiny);
    if diagonal && [a[0], b[1], c[2]].into_iter().any(|v| v < 0.0) {
        return Err(BoxError::NegativeLength([a[0], b[1], c[2]]));
    }
    let determinant = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]);
    if determinant < 0.0 {
        return Err(BoxError::LeftHanded);
    }
    if diagonal && [a[0], b[1], c[2]].into_iter().all(tiny) {
        return Ok(None);
    }
    let row = |r: [f64; 3]| Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32);
    Ok(Some([row(a), row(b), row(c)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_end_splits_lines() {
        let got: Vec<&[u8]> = lines(b"a\r\nb\rc\n\nd").collect();
        assert_eq!(got, vec![&b"a"[..], b"b", b"c", b"", b"d"]);
        let got: Vec<&[u8]> = lines(b"a\r\r\n").collect();
        assert_eq!(got, vec![&b"a"[..], b""]);
    }

    #[test]
    fn the_scanner_gives_lines_offsets_and_skips_a_bom() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.txt");
        // Lines longer than a chunk, and a CR-LF cut by a chunk boundary.
        let long = "x".repeat(CHUNK - 1);
        let text = format!("\u{feff}ab\r\n{long}\r\ncd\re");
        std::fs::write(&path, &text).unwrap();
        let mut scanner = LineScanner::open(&path, &path).unwrap();
        let mut got = Vec::new();
        while let Some((at, number, line)) = scanner.next_line().unwrap() {
            got.push((at, line.len(), number));
        }
        let long_at = 3 + 4;
        let cd_at = long_at + long.len() as u64 + 2;
        assert_eq!(
            got,
            vec![
                (3, 2, 1),
                (long_at, long.len(), 2),
                (cd_at, 2, 3),
                (cd_at + 3, 1, 4)
            ]
        );
        assert_eq!(scanner.position(), text.len() as u64);
    }

    #[test]
    fn boxes_follow_chemfiles_rules() {
        let zero = [[0.0; 3]; 3];
        assert_eq!(cell_rows(zero), Ok(None));
        let cube = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]];
        assert_eq!(
            cell_rows(cube).unwrap().unwrap()[1],
            Vec3::new(0.0, 20.0, 0.0)
        );
        let tilted = [[10.0, 0.0, 0.0], [2.0, 20.0, 0.0], [1.0, 3.0, 30.0]];
        assert_eq!(
            cell_rows(tilted).unwrap().unwrap()[2],
            Vec3::new(1.0, 3.0, 30.0)
        );
        let negative = [[-10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]];
        let error = cell_rows(negative).unwrap_err();
        assert_eq!(error, BoxError::NegativeLength([-10.0, 20.0, 30.0]));
        assert_eq!(
            error.to_string(),
            "the box has a negative length (-10 20 30)"
        );
        let left = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 5.0, -30.0]];
        assert_eq!(cell_rows(left), Err(BoxError::LeftHanded));
    }
}
