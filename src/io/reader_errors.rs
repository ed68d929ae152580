//! Why a file of one of our own trajectory readers cannot be read, one enum per format family:
//! [`DcdError`] (the DCD reader `super::dcd_frames` and the header check `super::dcd`),
//! [`GroError`] (`super::gro`) and [`LammpsError`] (`super::lammps`, `super::lammps_header`).
//! Variants carry the values (sizes, counts, line numbers from 1, the text found); each prints
//! as the one line the user reads, and callers wrap it in an [`super::IoError`] naming the file
//! (and frame). Sizes and offsets are bytes.

use super::text_scan::BoxError;

/// A damaged, unsupported or unreadable DCD file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum DcdError {
    /// The operating system could not read the file (its message).
    #[error("{0}")]
    Read(String),
    /// Fewer bytes than the 92-byte header record.
    #[error("too short for a DCD header")]
    TooShort,
    /// No `CORD` header record.
    #[error("not a DCD file (no 'CORD' header record)")]
    NotDcd,
    /// Record markers of 8 bytes.
    #[error("DCD files with 64-bit record markers are not supported")]
    Markers64,
    /// A header record of `len` bytes at byte `offset` that a `total`-byte file does not hold.
    #[error(
        "the file ends inside its header ({len} bytes at byte {offset} of {total}; truncated or damaged header)"
    )]
    HeaderCut { len: u64, offset: u64, total: u64 },
    /// The file ends inside its header (found by the header check).
    #[error("the file ends inside its header (truncated)")]
    #[cfg(feature = "chemfiles")] // found by the header check run before chemfiles
    HeaderTruncated,
    /// The header record's closing marker is not 84.
    #[error("the header record's closing marker is not 84 (damaged header)")]
    HeaderMarker,
    /// A title record of `title` bytes (negative, or more than the `total`-byte file).
    #[error("the title record says {title} bytes, in a file of {total} bytes (damaged header)")]
    TitleSize { title: i64, total: u64 },
    /// The same, as the header check words it.
    #[error(
        "the header's title record says {title} bytes, in a file of {total} bytes (damaged header)"
    )]
    #[cfg(feature = "chemfiles")] // found by the header check run before chemfiles
    HeaderTitleSize { title: i64, total: u64 },
    /// The title record's closing marker differs from its opening one.
    #[error("the title record's closing marker does not match (damaged header)")]
    TitleMarker,
    /// The atom-count record's markers are not 4.
    #[error("the atom-count record's markers are not 4 (damaged header)")]
    AtomCountMarkers,
    /// An atom count that is not positive.
    #[error("the header says {0} atoms (damaged header)")]
    BadAtomCount(i64),
    /// An atom count whose first frame (12 bytes per atom at least) a `total`-byte file cannot
    /// hold.
    #[error(
        "the header says {atoms} atoms, which a file of {total} bytes cannot hold (damaged header)"
    )]
    #[cfg(feature = "chemfiles")] // found by the header check run before chemfiles
    AtomsDontFit { atoms: i64, total: u64 },
    /// A fixed-atom count that is negative or above the atom count.
    #[error("the header says {fixed} fixed atoms out of {atoms} (damaged header)")]
    BadFixed { fixed: i64, atoms: i64 },
    /// The free-atom record's markers do not match its size.
    #[error("the free-atom record's markers do not match (damaged header)")]
    FreeAtomMarkers,
    /// Free atom `k` (from 0) is atom `index`, outside `1..=atoms`.
    #[error("free atom {k} is atom {index}, outside 1..={atoms} (damaged header)")]
    FreeAtomIndex { k: usize, index: i64, atoms: i64 },
    /// The free-atom list is damaged (found by the header check).
    #[error("the free-atom list in the header is damaged")]
    #[cfg(feature = "chemfiles")] // found by the header check run before chemfiles
    FreeAtomList,
    /// The file ends `have` bytes into a frame of `expected` bytes holding `atoms` atoms.
    #[error(
        "the file ends inside this frame (truncated: {have} of {expected} bytes for {atoms} atoms)"
    )]
    FrameCut {
        have: u64,
        expected: u64,
        atoms: usize,
    },
    /// A frame's `record` record ("unit cell", "x", ...) has a marker of `found` bytes where
    /// its payload is `expected` bytes.
    #[error(
        "the {record} record's marker says {found} bytes where {expected} belong (damaged frame)"
    )]
    RecordMarker {
        record: &'static str,
        found: i64,
        expected: u64,
    },
    /// No whole frame.
    #[error("the file holds no frames")]
    NoFrames,
    /// A frame's cell record makes no box (`unit_cell`'s reason).
    #[error(transparent)]
    Cell(#[from] crate::io::unit_cell::CellError),
}

impl From<std::io::Error> for DcdError {
    fn from(e: std::io::Error) -> Self {
        DcdError::Read(e.to_string())
    }
}

/// A damaged or cut GRO frame. Line numbers count from 1 in the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum GroError {
    /// The file ends after a frame's title (the count was due on `line`).
    #[error("line {line}: the file ends before the atom count")]
    EndsBeforeCount { line: u64 },
    /// The atom count (this text) is not a number.
    #[error("line {line}: the atom count '{shown}' is not a number")]
    BadCount { line: u64, shown: String },
    /// The atom count is not a number (as the frame reader words it).
    #[error("line {line}: the atom count is not a number")]
    CountNotNumber { line: u64 },
    /// The file ends before atom `missing` (from 1) of the `atoms` the frame announces.
    #[error("the file ends inside this frame (atom {missing} of {atoms} is missing)")]
    AtomMissing { missing: u64, atoms: u64 },
    /// An atom line of `length` bytes, shorter than the `needed` its coordinates take.
    #[error("line {line}: an atom line of {length} characters (at least {needed} expected)")]
    ShortAtomLine {
        line: u64,
        length: usize,
        needed: usize,
    },
    /// The file ends before a frame's box line.
    #[error("the file ends before this frame's box line")]
    EndsBeforeBox,
    /// The frame's bytes end before its atom count.
    #[error("the frame ends before the atom count")]
    FrameEndsBeforeCount,
    /// The frame's bytes end before atom `atom` (from 1).
    #[error("line {line}: the frame ends before atom {atom}")]
    FrameEndsBeforeAtom { line: u64, atom: usize },
    /// Coordinate `axis` ("x", "y" or "z") of atom `atom` (from 1) is not a number.
    #[error("line {line}: atom {atom}: {axis} '{shown}' is not a number")]
    BadCoordinate {
        line: u64,
        atom: usize,
        axis: &'static str,
        shown: String,
    },
    /// The frame's bytes end before its box line.
    #[error("line {line}: the frame ends before its box line")]
    FrameEndsBeforeBox { line: u64 },
    /// A box value (this text) is not a number.
    #[error("line {line}: the box value '{shown}' is not a number")]
    BadBoxValue { line: u64, shown: String },
    /// A box line of `count` numbers (counting stops at 10: more than 9).
    #[error("line {line}: the box line holds {} numbers (3 or 9 expected)", box_count(*count))]
    BoxCount { line: u64, count: usize },
    /// The box line's numbers make no box.
    #[error("line {line}: {error}")]
    Cell { line: u64, error: BoxError },
}

/// `count` as a box line's number count reads: "more than 9" above 9.
fn box_count(count: usize) -> String {
    if count > 9 {
        "more than 9".to_string()
    } else {
        count.to_string()
    }
}

/// A damaged or cut LAMMPS dump frame. Line numbers count from 1 in the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum LammpsError {
    /// The file ends inside a frame's header, before `what` ("the box", "ITEM: ATOMS", ...).
    #[error("the file ends inside this frame (before {what})")]
    EndsBefore { what: &'static str },
    /// A header line (this text, trimmed) that is no `ITEM:` line.
    #[error("line {line}: '{shown}' where an ITEM: line should be")]
    NotAnItem { line: u64, shown: String },
    /// An item name (this text) the reader does not know.
    #[error("line {line}: unknown item 'ITEM: {shown}'")]
    UnknownItem { line: u64, shown: String },
    /// The `TIMESTEP` value is not a number.
    #[error("line {line}: the time step is not a number")]
    BadTimestep { line: u64 },
    /// The `NUMBER OF ATOMS` value is not a number.
    #[error("line {line}: the atom count is not a number")]
    BadAtomCount { line: u64 },
    /// `BOX BOUNDS abc origin` (a general triclinic box).
    #[error("line {line}: general triclinic boxes (BOX BOUNDS abc origin) are not read")]
    GeneralTriclinic { line: u64 },
    /// A `BOX BOUNDS` line of `found` values where `wanted` belong.
    #[error("line {line}: {found} box values ({wanted} expected)")]
    BoxValueCount {
        line: u64,
        found: usize,
        wanted: usize,
    },
    /// A box value (this text) is not a number.
    #[error("line {line}: the box value '{shown}' is not a number")]
    BadBoxValue { line: u64, shown: String },
    /// `ITEM: ATOMS` before the item `missing` ("TIMESTEP", "NUMBER OF ATOMS", "BOX BOUNDS").
    #[error("line {line}: ITEM: ATOMS before ITEM: {missing}")]
    AtomsBefore { line: u64, missing: &'static str },
    /// The `ITEM: ATOMS` columns name no positions.
    #[error(
        "line {line}: the ATOMS columns hold no positions (x y z, xs ys zs, xu yu zu or xsu ysu zsu)"
    )]
    NoPositions { line: u64 },
    /// The `BOX BOUNDS` (first line `line`) make no box.
    #[error("line {line}: {error}")]
    Cell { line: u64, error: BoxError },
    /// The file ends before atom `missing` (from 1) of the `atoms` the frame announces.
    #[error("the file ends inside this frame (atom {missing} of {atoms} is missing)")]
    AtomMissing { missing: usize, atoms: usize },
    /// The frame's bytes end before atom `atom` (from 1).
    #[error("line {line}: the frame ends before atom {atom}")]
    FrameEndsBeforeAtom { line: u64, atom: usize },
    /// An atom line of `found` values for the `columns` the `ITEM: ATOMS` line names.
    #[error("line {line}: {found} values for the {columns} columns of ITEM: ATOMS")]
    ValueCount {
        line: u64,
        found: usize,
        columns: usize,
    },
    /// The `what` ("position", "mass", "charge") of an atom (this text) is not a number.
    #[error("line {line}: the {what} '{shown}' is not a number")]
    NotANumber {
        line: u64,
        what: &'static str,
        shown: String,
    },
    /// An atom id (this text) that is not a whole number.
    #[error("line {line}: the atom id '{shown}' is not a whole number")]
    BadId { line: u64, shown: String },
    /// An image flag (this text) that is not a whole number.
    #[error("line {line}: the image flag '{shown}' is not a whole number")]
    BadImage { line: u64, shown: String },
    /// Two atoms of the frame (whose atom lines start at `first_line`) share `id`.
    #[error("atom id {id} appears twice (lines from {first_line})")]
    DuplicateId { id: u64, first_line: u64 },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_read_as_before() {
        assert_eq!(
            DcdError::HeaderCut {
                len: 4,
                offset: 92,
                total: 94
            }
            .to_string(),
            "the file ends inside its header (4 bytes at byte 92 of 94; truncated or damaged header)"
        );
        assert_eq!(
            GroError::BoxCount { line: 5, count: 10 }.to_string(),
            "line 5: the box line holds more than 9 numbers (3 or 9 expected)"
        );
        assert_eq!(
            GroError::BoxCount { line: 5, count: 2 }.to_string(),
            "line 5: the box line holds 2 numbers (3 or 9 expected)"
        );
        assert_eq!(
            GroError::Cell {
                line: 7,
                error: BoxError::LeftHanded
            }
            .to_string(),
            "line 7: the box vectors are left-handed (negative volume)"
        );
        assert_eq!(
            LammpsError::AtomsBefore {
                line: 3,
                missing: "BOX BOUNDS"
            }
            .to_string(),
            "line 3: ITEM: ATOMS before ITEM: BOX BOUNDS"
        );
    }
}
