//! Measurement tables of a job array: with `--chunk I/N`, `mdsurf surface --per-residue R.csv`
//! (and `--per-atom`, `--interface-csv`, `--interface-residues`) writes
//! `R.part-IIII-of-NNNN.csv`: the part header of [`super::stats_merge`], then the table's own
//! columns and its rows for the chunk's block of frames, in frame order. [`merge_csv_parts`]
//! (`mdsurf merge R.csv`) joins them: every chunk's part present, all from one run with the same
//! columns, each row's frame inside its chunk's block; the rows in chunk order are the table one
//! process would have written. Stats parts go to [`super::stats_merge::merge_parts`].

use std::collections::BTreeSet;
use std::io::Write;
use std::path::Path;

use super::part_rows::{check_chunk_name, for_each_part_row, part_head};
use super::stats::STATS_COLUMNS;
use super::stats_merge::{
    MergeError, MergeSummary, check_one_chunk_count, difference, find_parts, merge_parts,
    part_path, show_pattern,
};
use super::{AtomicFile, ExportError};

/// Joins the parts next to `merged` into `merged`, atomically: stats parts as
/// [`merge_parts`] does, any other table as described in the module's documentation. Fails
/// with one line naming the file (and line) on no parts, a missing chunk, parts of other runs
/// or with other columns, a malformed row, or a row outside its chunk's frames; the merged file
/// is then left as it was. The rows are copied one at a time, never held together.
pub fn merge_csv_parts(merged: &Path) -> Result<MergeSummary, MergeError> {
    let invalid = MergeError::Invalid;
    let parts = find_parts(merged)?;
    check_one_chunk_count(merged, &parts)?;
    let Some((_, count, first_path)) = parts.first() else {
        return Err(invalid(format!(
            "no part files {} next to {}",
            show_pattern(merged),
            merged.display()
        )));
    };
    let (first, columns) = part_head(first_path, "part")?;
    if columns == STATS_COLUMNS.join(",") {
        return merge_parts(merged);
    }
    let present: BTreeSet<usize> = parts.iter().map(|(i, _, _)| *i).collect();
    let absent: Vec<String> = (0..*count)
        .filter(|i| !present.contains(i))
        .take(8)
        .map(|i| part_path(merged, i, *count).display().to_string())
        .collect();
    if !absent.is_empty() {
        return Err(invalid(format!(
            "{}: missing part(s) {}",
            show_pattern(merged),
            absent.join(", ")
        )));
    }
    // Every part's first two lines before anything is written.
    let mut headers = Vec::with_capacity(parts.len());
    for (index, count, path) in &parts {
        let (header, its_columns) = part_head(path, "part")?;
        check_chunk_name(path, &header, *index, *count)?;
        if let Some(diff) = difference(&first, &header) {
            return Err(invalid(format!(
                "{}: written with {diff}, {} with {}; parts of runs with different parameters are not merged",
                path.display(),
                first_path.display(),
                difference(&header, &first).unwrap_or_default()
            )));
        }
        if its_columns != columns {
            return Err(invalid(format!(
                "{}:2: the columns differ from those of {}",
                path.display(),
                first_path.display()
            )));
        }
        if !columns.starts_with("frame,") {
            return Err(invalid(format!(
                "{}:2: no column line starting with 'frame'",
                path.display()
            )));
        }
        headers.push(header);
    }
    // Then the rows, part after part, each checked as it is copied.
    let mut file = AtomicFile::create(merged)?;
    let io = |e| MergeError::Io(ExportError::io(merged, e));
    writeln!(file.writer(), "{columns}").map_err(io)?;
    let (mut rows, mut frames, mut last) = (0usize, 0usize, None);
    for ((_, _, path), header) in parts.iter().zip(&headers) {
        let mut before = None;
        for_each_part_row(path, "part", |row| {
            let frame = row.frame;
            let bad = |what: String| invalid(format!("{}:{}: {what}", path.display(), row.line));
            if !header.holds(frame) {
                return Err(bad(format!(
                    "frame {frame} is not in chunk {}/{}'s frames",
                    header.index, header.count
                )));
            }
            if before.is_some_and(|b| b > frame) {
                return Err(bad(format!("frame {frame} comes after a later frame")));
            }
            before = Some(frame);
            if last != Some(frame) {
                frames += 1;
                last = Some(frame);
            }
            rows += 1;
            writeln!(file.writer(), "{}", row.text).map_err(io)
        })?;
    }
    file.commit()?;
    Ok(MergeSummary {
        parts: parts.into_iter().map(|(_, _, p)| p).collect(),
        rows,
        frames,
    })
}
