//! Reading the part files of a chunked run (`FILE.part-IIII-of-NNNN.csv`) row by row: the
//! header line ([`PartHeader`]), the column line, then the data rows as CSV (so quoted names
//! round-trip), each with as many fields as the columns and a frame index first. Rows are
//! handed to the caller one at a time, so a merge of a large table holds one row, not the
//! table. Errors name the file and line.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use super::stats::csv_text;
use super::stats_merge::{MergeError, PART_MARK, PartHeader};

/// Longest header or column line read, in bytes (a part's are under a few hundred).
const HEAD_LINE_LIMIT: u64 = 64 * 1024;

/// One data row of a part file.
pub(crate) struct PartRow {
    /// Line in the file, from 1.
    pub line: usize,
    /// The first field, a frame index.
    pub frame: usize,
    /// The second field (the representation of a stats row; empty when there is none).
    pub second: String,
    /// The fields, quoted where needed, joined by commas.
    pub text: String,
}

/// A part that cannot be read (missing, not text) as a merge error naming it.
fn unreadable(path: &Path, e: std::io::Error) -> MergeError {
    MergeError::Invalid(format!("cannot read {}: {e}", path.display()))
}

/// "FILE:LINE: what" as a merge error.
fn bad(path: &Path, line: usize, what: String) -> MergeError {
    MergeError::Invalid(format!("{}:{line}: {what}", path.display()))
}

/// Opens a part file and reads its header and column lines (`what` names the kind of part in
/// messages); the reader is left at the first data row.
fn open_part(path: &Path, what: &str) -> Result<(PartHeader, String, BufReader<File>), MergeError> {
    let file = File::open(path).map_err(|e| unreadable(path, e))?;
    let mut reader = BufReader::new(file);
    let mut head = [String::new(), String::new()];
    for line in &mut head {
        (&mut reader)
            .take(HEAD_LINE_LIMIT)
            .read_line(line)
            .map_err(|e| unreadable(path, e))?;
        let end = line.trim_end_matches(['\n', '\r']).len();
        line.truncate(end);
    }
    let [header, columns] = head;
    let header = PartHeader::parse(&header).ok_or_else(|| {
        bad(
            path,
            1,
            format!("not a {what} (no '{PART_MARK} ...' first line)"),
        )
    })?;
    Ok((header, columns, reader))
}

/// Fails when a part's header names another chunk than its file name (`index` of `count`).
pub(crate) fn check_chunk_name(
    path: &Path,
    header: &PartHeader,
    index: usize,
    count: usize,
) -> Result<(), MergeError> {
    if (header.index, header.count) != (index, count) {
        let said = format!("{}/{}", header.index, header.count);
        return Err(bad(
            path,
            1,
            format!("the header says chunk {said}, the file name {index}/{count}"),
        ));
    }
    Ok(())
}

/// The header and the column line of a part file.
pub(crate) fn part_head(path: &Path, what: &str) -> Result<(PartHeader, String), MergeError> {
    open_part(path, what).map(|(header, columns, _)| (header, columns))
}

/// Hands every data row of a part file to `each`, in file order; stops at the first error,
/// `each`'s or the file's (a malformed row, a field count other than the columns', a first
/// field that is not a frame index).
pub(crate) fn for_each_part_row(
    path: &Path,
    what: &str,
    mut each: impl FnMut(PartRow) -> Result<(), MergeError>,
) -> Result<(), MergeError> {
    let (_, columns, reader) = open_part(path, what)?;
    let width = columns.split(',').count();
    let mut rows = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(reader);
    for record in rows.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line() as usize + 2);
            bad(path, line, format!("bad CSV row: {e}"))
        })?;
        let line = record.position().map_or(0, |p| p.line() as usize + 2);
        if record.len() != width {
            let found = record.len();
            return Err(bad(path, line, format!("{found} fields, expected {width}")));
        }
        let frame = record[0].parse().map_err(|_| {
            bad(
                path,
                line,
                format!("frame '{}' is not a frame index", &record[0]),
            )
        })?;
        let fields: Vec<String> = record.iter().map(csv_text).collect();
        each(PartRow {
            line,
            frame,
            second: record.get(1).unwrap_or("").to_string(),
            text: fields.join(","),
        })?;
    }
    Ok(())
}
