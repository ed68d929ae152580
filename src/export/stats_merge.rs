//! Stats of a job array: each chunk (`mdsurf surface --chunk I/N --stats STATS.csv`) writes
//! `STATS.part-IIII-of-NNNN.csv`, whose first line (a `#` comment, which pandas skips with
//! `comment="#"`) records the chunk, the whole run's frame selection and the parameters that
//! affect the numbers. [`merge_parts`] (`mdsurf merge STATS.csv`) checks that the parts come from
//! one run and together hold every selected frame exactly once, and writes `STATS.csv` sorted by
//! frame, as one run without chunks would have written it.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::part_rows::{check_chunk_name, for_each_part_row, part_head};
use super::stats::STATS_COLUMNS;
use super::{ExportError, write_atomic};

/// How a part file's first line starts.
pub const PART_MARK: &str = "# mdsurf-part";

/// What a part file records about the run it belongs to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartHeader {
    /// This chunk, `0..count`.
    pub index: usize,
    /// Number of chunks.
    pub count: usize,
    /// The whole run's frames: start, stop (exclusive, already clipped to the trajectory) and
    /// step, so the merge knows every frame that should be there.
    pub selection: [usize; 3],
    /// Parameters that affect the numbers, as `key=value` without spaces, in a fixed order.
    pub params: Vec<(String, String)>,
}

impl PartHeader {
    /// The header line (no newline).
    pub fn line(&self) -> String {
        let [a, b, s] = self.selection;
        let mut line = format!(
            "{PART_MARK} chunk={}/{} frames={a}:{b}:{s}",
            self.index, self.count
        );
        for (k, v) in &self.params {
            let _ = write!(line, " {}={}", clean(k), clean(v));
        }
        line
    }

    /// Parses a header line; `None` when it is not one.
    pub fn parse(line: &str) -> Option<PartHeader> {
        let rest = line.trim_end().strip_prefix(PART_MARK)?;
        let mut words = rest.split_whitespace().map(|w| w.split_once('='));
        let (index, count) = match words.next()?? {
            ("chunk", v) => {
                let (i, n) = v.split_once('/')?;
                (i.parse().ok()?, n.parse().ok()?)
            }
            _ => return None,
        };
        let selection = match words.next()?? {
            ("frames", v) => {
                let mut it = v.split(':').map(|p| p.parse::<usize>().ok());
                [it.next()??, it.next()??, it.next()??]
            }
            _ => return None,
        };
        let params = words
            .map(|kv| kv.map(|(k, v)| (k.to_string(), v.to_string())))
            .collect::<Option<Vec<_>>>()?;
        if count == 0 || index >= count || selection[2] == 0 {
            return None;
        }
        // Checked before anything is allocated from them: a run has at most MAX_RUN_FRAMES
        // frames and no more chunks than frames (a hostile or damaged header is not a header).
        let [a, b, step] = selection;
        let frames = b.saturating_sub(a).div_ceil(step);
        if frames > MAX_RUN_FRAMES || count > frames.max(1) {
            return None;
        }
        Some(PartHeader {
            index,
            count,
            selection,
            params,
        })
    }

    /// True when `frame` is one of this chunk's frames: its block of the run's selection
    /// ([`chunk_block`]).
    pub fn holds(&self, frame: usize) -> bool {
        let [a, b, step] = self.selection;
        let len = b.saturating_sub(a).div_ceil(step);
        let block = chunk_block(self.index, self.count, len);
        frame >= a && (frame - a).is_multiple_of(step) && block.contains(&((frame - a) / step))
    }

    /// Every frame index of the whole run (at most [`MAX_RUN_FRAMES`]).
    pub fn frames(&self) -> Vec<usize> {
        let [a, b, s] = self.selection;
        (a..b).step_by(s).collect()
    }
}

/// The positions in a selection of `len` frames that chunk `index` of `count` does:
/// contiguous blocks whose sizes differ by at most one, the larger ones first (empty when
/// `len < count` and this is one of the last blocks).
pub fn chunk_block(index: usize, count: usize, len: usize) -> std::ops::Range<usize> {
    let (base, extra) = (len / count.max(1), len % count.max(1));
    let start = index * base + index.min(extra);
    let size = base + usize::from(index < extra);
    start..start + size
}

/// Most frames a run's header may name (a billion-frame selection is damage, not a run).
pub const MAX_RUN_FRAMES: usize = 100_000_000;

/// A value with its whitespace replaced, so the header stays `key=value` words.
fn clean(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect()
}

/// The part file of chunk `index` of `count` for the stats path `stats`:
/// `DIR/STEM.part-IIII-of-NNNN.EXT` (at least 4 digits, I from 0).
pub fn part_path(stats: &Path, index: usize, count: usize) -> PathBuf {
    let width = count.to_string().len().max(4);
    let (stem, ext) = stem_ext(stats);
    let name = format!("{stem}.part-{index:0width$}-of-{count:0width$}{ext}");
    stats.with_file_name(name)
}

/// `STEM` and `.EXT` (empty when there is none) of a stats path's file name.
fn stem_ext(stats: &Path) -> (String, String) {
    let stem = stats
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = stats
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (stem, ext)
}

/// Why parts could not be merged; each message is one line naming the file(s).
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A part could not be read, or the merged file not written.
    #[error(transparent)]
    Io(#[from] ExportError),
    /// Anything else: no parts, parts of different runs, missing or duplicated frames, a
    /// malformed part.
    #[error("{0}")]
    Invalid(String),
}

/// What [`merge_parts`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MergeSummary {
    /// The part files read, in chunk order.
    pub parts: Vec<PathBuf>,
    /// Rows written (one per frame and surface representation).
    pub rows: usize,
    /// Distinct frames.
    pub frames: usize,
}

/// One data row of a part.
struct Row {
    frame: usize,
    rep: String,
    line: String,
    /// Where it came from, for messages: `file:line`.
    at: String,
}

/// Joins the parts of `stats` (see [`part_path`]) into `stats`, atomically. Fails with one line
/// when there are no parts, parts with different chunk counts or parameters, a frame (and
/// representation) in two parts, or frames of the selection that no part holds.
pub fn merge_parts(stats: &Path) -> Result<MergeSummary, MergeError> {
    let invalid = |m: String| MergeError::Invalid(m);
    let parts = find_parts(stats)?;
    check_one_chunk_count(stats, &parts)?;
    let mut first: Option<(PathBuf, PartHeader)> = None;
    let mut rows: Vec<Row> = Vec::new();
    let mut present = BTreeSet::new();
    for (index, count, path) in &parts {
        let (header, part_rows) = read_part(path)?;
        check_chunk_name(path, &header, *index, *count)?;
        match &first {
            None => first = Some((path.clone(), header)),
            Some((first_path, first_header)) => {
                if let Some(diff) = difference(first_header, &header) {
                    return Err(invalid(format!(
                        "{}: written with {diff}, {} with {}; parts of runs with different parameters are not merged",
                        path.display(),
                        first_path.display(),
                        difference(&header, first_header).unwrap_or_default()
                    )));
                }
            }
        }
        present.insert(*index);
        rows.extend(part_rows);
    }
    let Some((_, header)) = first else {
        return Err(invalid(format!(
            "no part files {} next to {}",
            show_pattern(stats),
            stats.display()
        )));
    };

    // Every frame of the selection exactly once per representation; nothing else.
    let expected: BTreeSet<usize> = header.frames().into_iter().collect();
    let mut seen: BTreeMap<(usize, &str), &str> = BTreeMap::new();
    let mut duplicated = BTreeSet::new();
    let mut dup_at = None;
    for row in &rows {
        if !expected.contains(&row.frame) {
            return Err(invalid(format!(
                "{}: frame {} is not in the run's selection {}",
                row.at,
                row.frame,
                frames_text(&header)
            )));
        }
        if let Some(prev) = seen.insert((row.frame, row.rep.as_str()), row.at.as_str()) {
            duplicated.insert(row.frame);
            dup_at.get_or_insert_with(|| format!("{prev} and {}", row.at));
        }
    }
    if !duplicated.is_empty() {
        return Err(invalid(format!(
            "{}: duplicated frames {} (first at {})",
            show_pattern(stats),
            ranges(&duplicated),
            dup_at.unwrap_or_default()
        )));
    }
    let have: BTreeSet<usize> = rows.iter().map(|r| r.frame).collect();
    let missing: BTreeSet<usize> = expected.difference(&have).copied().collect();
    if !missing.is_empty() {
        let absent: Vec<String> = (0..header.count)
            .filter(|i| !present.contains(i))
            .take(8)
            .map(|i| {
                part_path(stats, i, header.count)
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            })
            .collect();
        let why = if absent.is_empty() {
            String::new()
        } else {
            format!(" (no file {})", absent.join(", "))
        };
        return Err(invalid(format!(
            "{}: missing frames {}{why}",
            show_pattern(stats),
            ranges(&missing)
        )));
    }

    rows.sort_by_key(|r| r.frame);
    write_atomic(stats, |w: &mut dyn Write| {
        writeln!(w, "{}", STATS_COLUMNS.join(","))?;
        for row in &rows {
            writeln!(w, "{}", row.line)?;
        }
        Ok(())
    })?;
    Ok(MergeSummary {
        parts: parts.into_iter().map(|(_, _, p)| p).collect(),
        rows: rows.len(),
        frames: have.len(),
    })
}

/// Refuses parts (as [`find_parts`] lists them) of runs with different chunk counts.
pub(crate) fn check_one_chunk_count(
    merged: &Path,
    parts: &[(usize, usize, PathBuf)],
) -> Result<(), MergeError> {
    let counts: BTreeSet<usize> = parts.iter().map(|(_, n, _)| *n).collect();
    if counts.len() > 1 {
        let list: Vec<String> = counts.iter().map(|n| format!("of-{n:04}")).collect();
        return Err(MergeError::Invalid(format!(
            "{}: parts of runs with different chunk counts ({}); remove the stale ones",
            show_pattern(merged),
            list.join(", ")
        )));
    }
    Ok(())
}

/// `DIR/STEM.part-*-of-*.EXT`, for messages.
pub(crate) fn show_pattern(stats: &Path) -> String {
    let (stem, ext) = stem_ext(stats);
    stats
        .with_file_name(format!("{stem}.part-*-of-*{ext}"))
        .display()
        .to_string()
}

/// The part files next to `stats`: (chunk index, chunk count, path), sorted.
pub(crate) fn find_parts(stats: &Path) -> Result<Vec<(usize, usize, PathBuf)>, MergeError> {
    let dir = match stats.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let (stem, ext) = stem_ext(stats);
    let prefix = format!("{stem}.part-");
    let entries = fs::read_dir(dir).map_err(|e| {
        MergeError::Invalid(format!(
            "{}: cannot read the folder of its parts ({e})",
            show_pattern(stats)
        ))
    })?;
    let mut parts = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| ExportError::io(dir, e))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(middle) = name
            .strip_prefix(&prefix)
            .and_then(|m| m.strip_suffix(ext.as_str()))
        else {
            continue;
        };
        let Some((i, n)) = middle.split_once("-of-") else {
            continue;
        };
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        if !digits(i) || !digits(n) {
            continue;
        }
        if let (Ok(i), Ok(n)) = (i.parse(), n.parse()) {
            parts.push((i, n, stats.with_file_name(name)));
        }
    }
    parts.sort();
    Ok(parts)
}

/// Reads one stats part: its header and rows.
fn read_part(path: &Path) -> Result<(PartHeader, Vec<Row>), MergeError> {
    let (header, columns) = part_head(path, "stats part")?;
    if columns != STATS_COLUMNS.join(",") {
        return Err(MergeError::Invalid(format!(
            "{}:2: the columns differ from this mdsurf's stats columns",
            path.display()
        )));
    }
    let mut rows = Vec::new();
    for_each_part_row(path, "stats part", |row| {
        rows.push(Row {
            frame: row.frame,
            rep: row.second,
            line: row.text,
            at: format!("{}:{}", path.display(), row.line),
        });
        Ok(())
    })?;
    Ok((header, rows))
}

/// The first setting of `a` that `b` does not share, as `key=value` (or the frame selection).
pub(crate) fn difference(a: &PartHeader, b: &PartHeader) -> Option<String> {
    if a.selection != b.selection {
        return Some(format!("--frames {}", frames_text(a)));
    }
    for (k, v) in &a.params {
        if b.params.iter().find(|(bk, _)| bk == k).map(|(_, bv)| bv) != Some(v) {
            return Some(format!("{k}={v}"));
        }
    }
    b.params
        .iter()
        .find(|(k, _)| !a.params.iter().any(|(ak, _)| ak == k))
        .map(|(k, _)| format!("no {k}"))
}

/// A header's selection as `START:STOP:STEP`.
fn frames_text(h: &PartHeader) -> String {
    let [a, b, s] = h.selection;
    format!("{a}:{b}:{s}")
}

/// Frame numbers as runs, e.g. `3-5, 9` (the first 8 runs, then how many more frames).
fn ranges(frames: &BTreeSet<usize>) -> String {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for &f in frames {
        match runs.last_mut() {
            Some((_, end)) if *end + 1 == f => *end = f,
            _ => runs.push((f, f)),
        }
    }
    let shown: Vec<String> = runs
        .iter()
        .take(8)
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect();
    let rest: usize = runs.iter().skip(8).map(|(a, b)| b - a + 1).sum();
    if rest > 0 {
        format!("{} and {rest} more", shown.join(", "))
    } else {
        shown.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(index: usize, iso: &str) -> PartHeader {
        PartHeader {
            index,
            count: 2,
            selection: [0, 4, 1],
            params: vec![
                ("isovalue".into(), iso.into()),
                ("engine".into(), "cpu".into()),
            ],
        }
    }

    fn write_part(dir: &Path, h: &PartHeader, frames: &[usize]) {
        let mut text = format!("{}\n{}\n", h.line(), STATS_COLUMNS.join(","));
        for f in frames {
            text += &format!("{f},\"a,b\",,1,2,2,2,3,4,5.0000,6.0000,,,,,,\n");
        }
        fs::write(part_path(&dir.join("s.csv"), h.index, h.count), text).unwrap();
    }

    #[test]
    fn a_part_holds_the_frames_of_its_block_only() {
        // Frames 3, 5, ..., 21 (10 frames) in 3 chunks: 4, 3 and 3 frames.
        let part = |index| PartHeader {
            index,
            count: 3,
            selection: [3, 22, 2],
            params: Vec::new(),
        };
        let held = |index| {
            (0..30)
                .filter(|&f| part(index).holds(f))
                .collect::<Vec<_>>()
        };
        assert_eq!(held(0), [3, 5, 7, 9]);
        assert_eq!(held(1), [11, 13, 15]);
        assert_eq!(held(2), [17, 19, 21]);
    }

    #[test]
    fn header_round_trips_and_paths_are_padded() {
        let h = header(1, "0.5");
        assert_eq!(PartHeader::parse(&h.line()), Some(h.clone()));
        assert_eq!(h.frames(), [0, 1, 2, 3]);
        assert_eq!(PartHeader::parse("frame,rep"), None);
        assert_eq!(
            part_path(Path::new("out/s.csv"), 3, 12),
            Path::new("out/s.part-0003-of-0012.csv")
        );
        assert_eq!(
            part_path(Path::new("s"), 3, 12345),
            Path::new("s.part-00003-of-12345")
        );
        assert_eq!(ranges(&[1, 2, 3, 7, 9, 10].into()), "1-3, 7, 9-10");
    }

    #[test]
    fn hostile_headers_are_refused_before_anything_is_allocated() {
        let good = header(1, "0.5").line();
        // A selection of 2^64 frames, more chunks than frames, a zero step.
        for (from, to) in [
            ("frames=0:4:1", "frames=0:18446744073709551615:1"),
            ("chunk=1/2", "chunk=1/4294967296"),
            ("frames=0:4:1", "frames=0:4:0"),
        ] {
            assert!(good.contains(from), "{good}");
            let bad = good.replace(from, to);
            assert_eq!(PartHeader::parse(&bad), None, "{bad}");
        }
    }

    #[test]
    fn merge_sorts_and_refuses_gaps_duplicates_and_other_parameters() {
        let dir = tempfile::tempdir().unwrap();
        let stats = dir.path().join("s.csv");
        let err = merge_parts(&stats).unwrap_err().to_string();
        assert!(err.starts_with("no part files"), "{err}");

        write_part(dir.path(), &header(1, "0.5"), &[2, 3]);
        let err = merge_parts(&stats).unwrap_err().to_string();
        assert!(
            err.contains("missing frames 0-1 (no file s.part-0000-of-0002.csv)"),
            "{err}"
        );
        assert!(!stats.exists());

        write_part(dir.path(), &header(0, "0.5"), &[0, 1]);
        let sum = merge_parts(&stats).unwrap();
        assert_eq!((sum.rows, sum.frames, sum.parts.len()), (4, 4, 2));
        let text = fs::read_to_string(&stats).unwrap();
        let frames: Vec<&str> = text.lines().skip(1).map(|l| &l[..1]).collect();
        assert_eq!(frames, ["0", "1", "2", "3"]);
        assert!(text.contains("\"a,b\""), "{text}");

        write_part(dir.path(), &header(0, "0.5"), &[0, 1, 2]);
        let err = merge_parts(&stats).unwrap_err().to_string();
        assert!(err.contains("duplicated frames 2"), "{err}");

        write_part(dir.path(), &header(0, "0.6"), &[0, 1]);
        let err = merge_parts(&stats).unwrap_err().to_string();
        assert!(
            err.contains("isovalue=0.5") && err.contains("isovalue=0.6"),
            "{err}"
        );
        assert!(!err.contains('\n'));
    }
}
