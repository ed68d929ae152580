//! Why an Amber NetCDF file, or one frame of it, cannot be read: a damaged or unsupported header
//! (`super::header`), a file that is NetCDF but not an Amber trajectory, a cut record, or a
//! failed read. Each prints as one line; callers wrap it in an [`crate::io::IoError`] naming the
//! file (and frame). Sizes and offsets are bytes.

use super::header::NcType;

/// A damaged, unsupported or unreadable Amber NetCDF file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum NetcdfError {
    /// The operating system could not read the file (its message).
    #[error("{0}")]
    Read(String),
    /// Fewer bytes than the 4-byte signature.
    #[error("too short for a NetCDF file")]
    TooShort,
    /// No `CDF` signature at the start.
    #[error("not a NetCDF file (no 'CDF' signature)")]
    NotNetcdf,
    /// A CDF-5 (64-bit data) file.
    #[error("a CDF-5 (64-bit data) NetCDF file: only CDF-1 and CDF-2 are read")]
    Cdf5,
    /// A NetCDF-4 file (HDF5 signature).
    #[error("a NetCDF-4 (HDF5) file: only classic NetCDF (CDF-1, CDF-2) is read")]
    Netcdf4,
    /// A type code that is none of the six classic types.
    #[error("unknown NetCDF type {0} (damaged header)")]
    UnknownType(u32),
    /// The header needs `bytes` bytes at byte `at`, past the end of a `file_len`-byte file.
    #[error(
        "the header needs {bytes} bytes at byte {at} of a {file_len}-byte file (damaged or truncated header)"
    )]
    Truncated {
        bytes: u64,
        at: usize,
        file_len: u64,
    },
    /// A count of `what` (e.g. "attributes") above `i32::MAX`.
    #[error("negative {what} count in the header (damaged header)")]
    NegativeCount { what: &'static str },
    /// `count` elements of `what` that the rest of a `file_len`-byte file cannot hold.
    #[error(
        "the header says {count} {what}, which a {file_len}-byte file cannot hold (damaged header)"
    )]
    CountTooLarge {
        what: &'static str,
        count: u32,
        file_len: u64,
    },
    /// A list (dimensions, attributes, variables) whose tag is not `expected`.
    #[error("expected the {what} list (tag {expected}), found tag {found} (damaged header)")]
    WrongTag {
        what: &'static str,
        expected: u32,
        found: u32,
    },
    /// A negative record count other than -1 (streaming).
    #[error("the header says {0} records (damaged header)")]
    NegativeRecords(i32),
    /// A dimension whose length is negative.
    #[error("dimension '{0}' has a negative length (damaged header)")]
    NegativeDimension(String),
    /// A variable over dimension `id` of the `count` the header defines.
    #[error("variable '{variable}' uses dimension {id}, of {count} (damaged header)")]
    UnknownDimension {
        variable: String,
        id: usize,
        count: usize,
    },
    /// The header did not parse within its first `limit` bytes.
    #[error("the header is larger than {limit} bytes (damaged header)")]
    HeaderTooLarge { limit: u64 },
    /// `Conventions` names AMBERRESTART: a restart file.
    #[error("an Amber NetCDF restart file, not a trajectory")]
    Restart,
    /// `Conventions` (this text) does not name AMBER.
    #[error("not an Amber NetCDF trajectory (Conventions attribute '{0}', AMBER expected)")]
    NotAmber(String),
    /// No `frame` dimension, or one that is not the record (unlimited) dimension.
    #[error("no 'frame' record dimension")]
    NoRecordDimension,
    /// No dimension of this name.
    #[error("no '{0}' dimension")]
    MissingDimension(&'static str),
    /// No `coordinates` variable, but `velocities` (sander's `mdvel`).
    #[error("no coordinates in this file (velocities only)")]
    VelocitiesOnly,
    /// No variable of this name (the file is unreadable without it).
    #[error("no coordinates in this file (no '{0}' variable)")]
    MissingVariable(&'static str),
    /// `coordinates` of another type, or over other dimensions (their names).
    #[error(
        "'coordinates' must be floating point over (frame, atom, spatial), found {kind:?} over {dimensions:?}"
    )]
    BadCoordinates {
        kind: NcType,
        dimensions: Vec<String>,
    },
    /// A dimension (`spatial`) that is `value` long instead of 3.
    #[error("the '{name}' dimension is {value}, not 3")]
    BadDimension { name: &'static str, value: u64 },
    /// A cell dimension (`cell_spatial`, `cell_angular`) that is not 3 long.
    #[error("the '{0}' dimension is not 3")]
    BadCellDimension(&'static str),
    /// A record variable of more bytes per frame than a `u64` holds, or than the
    /// `file_len`-byte file when its header promises no frames.
    #[error(
        "variable '{variable}' needs more bytes per frame than the {file_len}-byte file has (damaged header)"
    )]
    RecordTooLarge { variable: String, file_len: u64 },
    /// A record variable of `bytes` bytes per frame in a `file_len`-byte file whose header
    /// promises frames: the file ends inside frame 0.
    #[error(
        "the file ends inside this frame (truncated: variable '{variable}' needs {bytes} bytes per frame, the file has {file_len})"
    )]
    FirstFrameCut {
        variable: String,
        bytes: u64,
        file_len: u64,
    },
    /// A `units` attribute naming no known distance unit (this text, trimmed and lower-cased).
    #[error("unknown distance unit '{0}'")]
    UnknownUnit(String),
    /// A variable (this one) whose `scale_factor` attribute is not one floating-point number.
    #[error("'{0}' has a scale_factor that is not one number")]
    BadScaleFactor(String),
    /// A cell variable of another type, or over other dimensions than (frame, `dimension`).
    #[error("'{variable}' must be floating point over (frame, {dimension})")]
    BadCellVariable {
        variable: String,
        dimension: &'static str,
    },
    /// Only one of `cell_lengths` and `cell_angles`.
    #[error("one of 'cell_lengths' and 'cell_angles' without the other")]
    HalfCell,
    /// No whole frame.
    #[error("the file holds no frames")]
    NoFrames,
    /// The file ends inside a frame the header announces (it says `announced` frames).
    #[error("the file ends inside this frame (truncated: the header says {announced} frames)")]
    FewerFrames { announced: u64 },
    /// The file ends inside a frame of a streaming file (whose header gives no count).
    #[error("the file ends inside this frame (truncated)")]
    CutFrame,
    /// A frame's cell lengths and angles make no box (`unit_cell`'s reason).
    #[error(transparent)]
    Cell(#[from] crate::io::unit_cell::CellError),
}

impl From<std::io::Error> for NetcdfError {
    fn from(e: std::io::Error) -> Self {
        NetcdfError::Read(e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_read_as_before() {
        assert_eq!(
            NetcdfError::UnknownType(9).to_string(),
            "unknown NetCDF type 9 (damaged header)"
        );
        assert_eq!(
            NetcdfError::BadCoordinates {
                kind: NcType::Int,
                dimensions: vec!["frame".into(), "atom".into()],
            }
            .to_string(),
            "'coordinates' must be floating point over (frame, atom, spatial), found Int over [\"frame\", \"atom\"]"
        );
        assert_eq!(
            NetcdfError::FewerFrames { announced: 4 }.to_string(),
            "the file ends inside this frame (truncated: the header says 4 frames)"
        );
        assert_eq!(
            NetcdfError::Truncated {
                bytes: 8,
                at: 12,
                file_len: 16
            }
            .to_string(),
            "the header needs 8 bytes at byte 12 of a 16-byte file (damaged or truncated header)"
        );
    }
}
