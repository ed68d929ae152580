//! The reader process: `mdsurf __read-frames BASE FORMAT PATH [COPY]` opens `COPY` (the file
//! its parent prepared; `PATH` itself when absent) with chemfiles in format `FORMAT`, names
//! `PATH` in its errors, answers `O` (the frame count) or `E`, then serves requests from stdin
//! until stdin closes (see [`super::protocol`]). It writes nothing else to stdout: file
//! descriptor 1 is pointed at stderr (which the parent captures) before chemfiles is touched, so
//! a C library printing to stdout cannot corrupt the replies.
//!
//! Test hooks (only with the `test-hooks` feature, never in the shipped binary): with
//! `MDSURF_READER_CRASH_AT=K` in its environment the process aborts (SIGABRT)
//! when asked for frame `K`, as chemfiles does on some damaged files; with
//! `MDSURF_READER_GARBAGE_AT=K` it answers that request with bytes that are no reply.

use std::ffi::OsString;
use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::os::fd::FromRawFd;
use std::path::PathBuf;

use super::protocol::{
    self, OP_FRAME, OP_TOPOLOGY, Reader, TAG_OPEN, TAG_WARNING, Writer, encode_error, encode_frame,
    encode_topology,
};
use crate::io::chem::ChemReader;
use crate::io::{IoError, format, warnings};

/// The first argument that starts the reader mode.
pub const READER_ARG: &str = "__read-frames";

/// Version of the messages; the `O` reply carries it and the parent checks it.
pub(super) const PROTOCOL: u64 = 1;

/// Runs the reader mode with `args` (after [`READER_ARG`]); returns the exit code.
pub(super) fn serve(args: &[OsString]) -> i32 {
    let (Some(base), Some(chemfiles), Some(path)) = (args.first(), args.get(1), args.get(2)) else {
        eprintln!("usage: mdsurf {READER_ARG} BASE FORMAT PATH [COPY]");
        return 2;
    };
    let Some(base) = base.to_str().and_then(format::base_named) else {
        eprintln!("unknown format {base:?}");
        return 2;
    };
    let Some(chemfiles) = chemfiles.to_str() else {
        return 2;
    };
    let path = PathBuf::from(path);
    let copy = args.get(3).map(PathBuf::from);
    let Some(mut out) = protocol_output() else {
        return 2;
    };
    #[cfg(feature = "test-hooks")]
    let faults = Faults::from_env();
    let reader = ChemReader::open_prepared(&path, base, copy, chemfiles, None);
    let mut reader = match reader {
        Ok(reader) => reader,
        Err(e) => {
            let _ = reply(&mut out, &encode_error(&e));
            return 0;
        }
    };
    let mut open = Writer::tag(TAG_OPEN);
    open.u64(PROTOCOL).u64(reader.len() as u64);
    if reply(&mut out, &open.0).is_err() {
        return 0;
    }
    let mut input = BufReader::new(std::io::stdin().lock());
    while let Ok(Some(request)) = protocol::receive(&mut input) {
        let mut r = Reader(&request);
        let (Ok(op), Ok(index)) = (r.u8(), r.u64()) else {
            return 2;
        };
        #[cfg(feature = "test-hooks")]
        if faults.inject(index, &mut out) {
            continue;
        }
        let body = match usize::try_from(index) {
            Err(_) => encode_error(&IoError::bad_frame(&path, usize::MAX, "no such frame")),
            Ok(index) => match op {
                OP_FRAME => reader
                    .read_unchecked(index)
                    .map_or_else(|e| encode_error(&e), |f| encode_frame(&f)),
                OP_TOPOLOGY => reader
                    .read_topology(index)
                    .map_or_else(|e| encode_error(&e), |t| encode_topology(&t)),
                _ => return 2,
            },
        };
        if reply(&mut out, &body).is_err() {
            return 0;
        }
    }
    0
}

/// Faults the tests inject (feature `test-hooks`): the frame index whose request aborts the
/// process (`MDSURF_READER_CRASH_AT`) and the one answered with bytes that are no reply
/// (`MDSURF_READER_GARBAGE_AT`).
#[cfg(feature = "test-hooks")]
struct Faults {
    crash_at: Option<u64>,
    garbage_at: Option<u64>,
}

#[cfg(feature = "test-hooks")]
impl Faults {
    fn from_env() -> Faults {
        let hook = |name: &str| -> Option<u64> { std::env::var(name).ok()?.trim().parse().ok() };
        Faults {
            crash_at: hook("MDSURF_READER_CRASH_AT"),
            garbage_at: hook("MDSURF_READER_GARBAGE_AT"),
        }
    }

    /// Acts on a request for frame `index`: aborts at `crash_at`; at `garbage_at` sends garbage
    /// and returns true (the request is answered).
    fn inject(&self, index: u64, out: &mut impl Write) -> bool {
        if self.crash_at == Some(index) {
            std::process::abort();
        }
        if self.garbage_at == Some(index) {
            let _ = protocol::send(out, b"?garbage");
            return true;
        }
        false
    }
}

/// Sends the warnings chemfiles gave since the last reply, then `body`.
fn reply(out: &mut impl Write, body: &[u8]) -> std::io::Result<()> {
    let (kept, _dropped) = warnings::take_warnings();
    for warning in kept {
        let mut w = Writer::tag(TAG_WARNING);
        w.str(&warning);
        protocol::send(out, &w.0)?;
    }
    protocol::send(out, body)
}

/// The replies' channel: the original stdout, moved to a new descriptor; descriptor 1 then
/// points at stderr.
fn protocol_output() -> Option<BufWriter<File>> {
    let _ = std::io::stdout().flush();
    // SAFETY: plain descriptor calls on descriptors this process owns; `dup` gives a new
    // descriptor that nothing else refers to, so the `File` made from it owns it alone.
    unsafe {
        let fd = libc::dup(1);
        if fd < 0 || libc::dup2(2, 1) < 0 {
            return None;
        }
        Some(BufWriter::with_capacity(1 << 20, File::from_raw_fd(fd)))
    }
}
