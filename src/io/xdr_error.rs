//! Why an XTC or TRR frame cannot be read: a damaged or truncated frame header found by the
//! header walk ([`super::xdr`]), or frame data the readers ([`super::xdr_reader`]) cannot
//! decode. Each prints as one line; callers wrap it in an [`super::IoError`] naming the file and
//! frame. Offsets are bytes from the start of the file.

use std::sync::Arc;

/// A damaged or unreadable XTC/TRR frame.
#[derive(Debug, Clone, thiserror::Error)]
pub(crate) enum XdrError {
    /// The operating system could not open, seek or read the file.
    #[error(transparent)]
    Os(Arc<std::io::Error>),
    /// The file ends inside a frame header.
    #[error("the file ends inside the frame header at byte {offset} (truncated)")]
    TruncatedHeader { offset: u64 },
    /// The file ends inside a frame's data.
    #[error("the file ends inside this frame (truncated: {have} of {need} bytes)")]
    Truncated { have: u64, need: u64 },
    /// No frame header (magic number) where one should start.
    #[error("no {format} frame header at byte {offset}")]
    NoHeader { format: &'static str, offset: u64 },
    /// The two atom counts of an XTC header differ.
    #[error("inconsistent atom counts in the frame header at byte {offset}")]
    AtomCounts { offset: u64 },
    /// A frame's atom count differs from the first frame's.
    #[error(
        "the frame header at byte {offset} says {natoms} atoms, the first frame {first} (damaged file)"
    )]
    AtomCountChanged {
        offset: u64,
        natoms: usize,
        first: usize,
    },
    /// A box length beyond any real box.
    #[error("absurd box in the frame header at byte {offset}")]
    AbsurdBox { offset: u64 },
    /// An XTC precision that is not a positive number.
    #[error("invalid precision in the frame header at byte {offset}")]
    Precision { offset: u64 },
    /// An XTC coordinate range with a minimum above its maximum.
    #[error("invalid coordinate range in the frame header at byte {offset}")]
    CoordinateRange { offset: u64 },
    /// An XTC compression index out of range.
    #[error("invalid compression index in the frame header at byte {offset}")]
    CompressionIndex { offset: u64 },
    /// An XTC byte count that cannot hold the atoms.
    #[error("the frame header at byte {offset} gives {count} bytes of data for {natoms} atoms")]
    DataSize {
        offset: u64,
        count: i32,
        natoms: u64,
    },
    /// A TRR version string of absurd length.
    #[error("invalid version string in the frame header at byte {offset}")]
    VersionString { offset: u64 },
    /// A negative TRR block size or atom count.
    #[error("negative size in the frame header at byte {offset}")]
    NegativeSize { offset: u64 },
    /// TRR reals that are neither 4 nor 8 bytes.
    #[error("invalid real size in the frame header at byte {offset}")]
    RealSize { offset: u64 },
    /// TRR block sizes that do not fit the atom count.
    #[error("the frame header at byte {offset} gives sizes that do not fit {natoms} atoms")]
    SizesDoNotFit { offset: u64, natoms: u64 },
    /// The file holds no frame at all.
    #[error("no frame")]
    NoFrame,
    /// A damaged header after a frame: that frame's data may hold the damage too.
    #[error("the data after this frame's header is damaged ({0})")]
    DamagedAfter(Box<XdrError>),
    /// The XTC decoder panicked on the frame's compressed data.
    #[error("the compressed coordinates are damaged")]
    CompressedDamaged,
    /// The XTC decoder refused the frame's compressed data.
    #[error("cannot decode the compressed coordinates ({0})")]
    Decode(Arc<std::io::Error>),
    /// The XTC decoder gave another number of atoms than the header.
    #[error("decoded {decoded} atoms, the header says {expected}")]
    DecodedAtoms { decoded: usize, expected: usize },
    /// A TRR frame with velocities or forces only.
    #[error("this frame has no positions (only velocities or forces)")]
    NoPositions,
    /// The TRR frame's reals could not be read.
    #[error("cannot read the frame data ({0})")]
    FrameData(Arc<std::io::Error>),
}

impl XdrError {
    /// An operating-system error.
    pub(crate) fn os(e: std::io::Error) -> Self {
        XdrError::Os(Arc::new(e))
    }

    /// The one-line reason when this is a remote source's network failure ([`RemoteFailure`]),
    /// not damage in the file.
    pub(crate) fn remote(&self) -> Option<String> {
        match self {
            XdrError::Os(e) => remote_failure(e),
            _ => None,
        }
    }

    /// True when the file ends inside a frame or its header.
    pub(crate) fn is_truncation(&self) -> bool {
        matches!(
            self,
            XdrError::Truncated { .. } | XdrError::TruncatedHeader { .. }
        )
    }
}

/// A remote byte source's failure (a server gone, a dropped connection, a short reply), carried
/// inside a `std::io::Error` by the HTTP source (`super::http`): not damage in the file, so the
/// header walk stops with it instead of ending the readable frames there. Prints as one line
/// naming the byte range.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct RemoteFailure(pub String);

/// The reason `e` gives when it carries a [`RemoteFailure`].
pub(crate) fn remote_failure(e: &std::io::Error) -> Option<String> {
    e.get_ref()
        .and_then(|inner| inner.downcast_ref::<RemoteFailure>())
        .map(|failure| failure.0.clone())
}
