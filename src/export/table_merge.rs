//! Measurement tables of a job array: with `--chunk I/N`, `mdsurf surface --per-residue R.csv`
//! (and `--per-atom`, `--interface-csv`, `--interface-residues`) writes
//! `R.part-IIII-of-NNNN.csv`: the part header of [`super::stats_merge`], then the table's own
//! columns and its rows for the chunk's block of frames, in frame order. [`merge_csv_parts`]
//! (`mdsurf merge R.csv`) joins them: every chunk's part present, all from one run with the same
//! columns, each row's frame inside its chunk's block; the rows in chunk order are the table one
//! process would have written. Stats parts go to [`super::stats_merge::merge_parts`].

use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::Path;

use super::stats::STATS_COLUMNS;
use super::stats_merge::{
    MergeError, MergeSummary, PartHeader, check_one_chunk_count, difference, find_parts,
    merge_parts, part_path, read_part_rows, show_pattern,
};
use super::{ExportError, write_atomic};

/// One part as read: its header, column line and rows (fields re-quoted, joined by commas).
struct TablePart {
    header: PartHeader,
    columns: String,
    rows: Vec<(usize, String)>,
}

/// Joins the parts next to `merged` into `merged`, atomically: stats parts as
/// [`merge_parts`] does, any other table as described in the module's documentation. Fails
/// with one line naming the file (and line) on no parts, a missing chunk, parts of other runs
/// or with other columns, a malformed row, or a row outside its chunk's frames.
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
    let first_text = fs::read_to_string(first_path).map_err(|e| ExportError::io(first_path, e))?;
    if first_text.lines().nth(1) == Some(STATS_COLUMNS.join(",").as_str()) {
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
    let mut read: Vec<TablePart> = Vec::with_capacity(parts.len());
    for (index, count, path) in &parts {
        let part = read_table_part(path)?;
        if (part.header.index, part.header.count) != (*index, *count) {
            return Err(invalid(format!(
                "{}:1: the header says chunk {}/{}, the file name {index}/{count}",
                path.display(),
                part.header.index,
                part.header.count
            )));
        }
        if let Some(first) = read.first() {
            if let Some(diff) = difference(&first.header, &part.header) {
                return Err(invalid(format!(
                    "{}: written with {diff}, {} with {}; parts of runs with different parameters are not merged",
                    path.display(),
                    first_path.display(),
                    difference(&part.header, &first.header).unwrap_or_default()
                )));
            }
            if first.columns != part.columns {
                return Err(invalid(format!(
                    "{}:2: the columns differ from those of {}",
                    path.display(),
                    first_path.display()
                )));
            }
        }
        read.push(part);
    }
    let columns = read[0].columns.clone();
    let rows: usize = read.iter().map(|p| p.rows.len()).sum();
    let frames: BTreeSet<usize> = read
        .iter()
        .flat_map(|p| p.rows.iter().map(|r| r.0))
        .collect();
    write_atomic(merged, |w: &mut dyn Write| {
        writeln!(w, "{columns}")?;
        for (_, line) in read.iter().flat_map(|p| &p.rows) {
            writeln!(w, "{line}")?;
        }
        Ok(())
    })?;
    Ok(MergeSummary {
        parts: parts.into_iter().map(|(_, _, p)| p).collect(),
        rows,
        frames: frames.len(),
    })
}

/// Reads one table part: the header, the column line (its first column `frame`) and the rows,
/// each with its frame inside the chunk's block and not before the row above it.
fn read_table_part(path: &Path) -> Result<TablePart, MergeError> {
    let part = read_part_rows(path, "part")?;
    let bad = |line: usize, what: String| {
        MergeError::Invalid(format!("{}:{line}: {what}", path.display()))
    };
    if !part.columns.starts_with("frame,") {
        return Err(bad(2, "no column line starting with 'frame'".into()));
    }
    let header = part.header;
    let mut rows: Vec<(usize, String)> = Vec::with_capacity(part.rows.len());
    for row in part.rows {
        let frame = row.frame;
        if !header.holds(frame) {
            return Err(bad(
                row.line,
                format!(
                    "frame {frame} is not in chunk {}/{}'s frames",
                    header.index, header.count
                ),
            ));
        }
        if rows.last().is_some_and(|(before, _)| *before > frame) {
            return Err(bad(
                row.line,
                format!("frame {frame} comes after a later frame"),
            ));
        }
        rows.push((frame, row.text));
    }
    Ok(TablePart {
        header,
        columns: part.columns,
        rows,
    })
}
