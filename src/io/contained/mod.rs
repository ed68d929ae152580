//! The contained reader: every file chemfiles (C++) reads is read in a child process, so that no
//! C or C++ parser sees a user's bytes in the process that holds the user's work. A damaged TNG,
//! NetCDF, LAMMPS or DCD file that crashes chemfiles (SIGSEGV, SIGABRT) ends the child, not the
//! viewer or the `surface` run: the parent turns the crash into a one-line [`IoError`] naming the
//! file and the frame, keeps the frames it already has, and starts a new child for the next
//! request.
//!
//! The child is the same executable started in a hidden mode (`mdsurf __read-frames ...`, see
//! [`child`]); it sends the frame count when it has opened the file, then a topology or a frame
//! for each request, over its stdin and stdout ([`protocol`]). Its stderr is captured and
//! dropped: chemfiles' and the TNG library's text never reaches the user's terminal (chemfiles'
//! warnings come back as messages, into [`crate::io::take_warnings`]). The Rust checks and
//! preparation of a file ([`check_and_prepare`]: decompression, cleaned text, salvaged TNG) run
//! in the parent, which owns the temporary copies, so they are removed however the child ends.
//!
//! Which executable is the reader:
//! 1. the one `MDSURF_READER_EXE` names, when set;
//! 2. this executable, when its `main` called [`reader_main`] (the `mdsurf` binary does);
//! 3. an `mdsurf` binary next to this executable or one folder up (a test or benchmark binary
//!    of this package lives in `target/<profile>/deps`, the `mdsurf` binary in
//!    `target/<profile>`);
//! 4. none: the file is read in this process (a program embedding the library without the
//!    binary). Setting `MDSURF_IN_PROCESS_READ` chooses this too (for timing the two paths).

mod child;
mod protocol;

use std::ffi::OsString;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

use glam::Vec3;

use super::chem::{ChemReader, check_and_prepare};
use super::format::FileFormat;
use super::frame_checks::check_positions;
use super::prepare::read_all;
use super::{IoError, pdb_models, warnings};
use crate::model::{Frame, Topology};
use protocol::{Garbage, Reader, TAG_ERROR, TAG_FRAME, TAG_OPEN, TAG_TOPOLOGY, TAG_WARNING};

pub use child::READER_ARG;

/// At most this much of a child's stderr is kept (the rest is read and dropped).
const MAX_STDERR: usize = 64 * 1024;

/// Set when this executable's `main` serves the reader mode (see [`reader_main`]).
static SERVES: AtomicBool = AtomicBool::new(false);

/// For `main`: runs the reader mode when the first argument is [`READER_ARG`] and returns its
/// exit code; otherwise records that this executable can be its own reader and returns `None`.
pub fn reader_main() -> Option<i32> {
    let mut args = std::env::args_os().skip(1);
    if args.next().is_some_and(|a| a == READER_ARG) {
        let rest: Vec<OsString> = args.collect();
        return Some(child::serve(&rest));
    }
    SERVES.store(true, Ordering::Relaxed);
    None
}

/// The reader executable, or `None` to read in this process (see the module documentation).
fn reader_exe() -> Option<PathBuf> {
    if std::env::var_os("MDSURF_IN_PROCESS_READ").is_some() {
        return None;
    }
    if let Some(exe) = std::env::var_os("MDSURF_READER_EXE").filter(|e| !e.is_empty()) {
        return Some(PathBuf::from(exe));
    }
    let me = std::env::current_exe().ok()?;
    if SERVES.load(Ordering::Relaxed) {
        return Some(me);
    }
    let name = format!("mdsurf{}", std::env::consts::EXE_SUFFIX);
    let dir = me.parent()?;
    [Some(dir), dir.parent()]
        .into_iter()
        .flatten()
        .map(|d| d.join(&name))
        .find(|candidate| candidate.is_file())
}

/// One file read through chemfiles: in a reader process, or in this one (see the module
/// documentation). The same calls as [`ChemReader`].
pub(crate) struct ContainedReader {
    path: PathBuf,
    format: FileFormat,
    base: &'static str,
    len: usize,
    truncated: Option<(String, bool)>,
    backend: Backend,
}

enum Backend {
    InProcess(ChemReader),
    Child {
        launch: Launch,
        /// The running child; `None` after it died (the next request starts another).
        process: Option<Process>,
    },
}

/// How to start a reader process for the file.
struct Launch {
    exe: PathBuf,
    args: Vec<OsString>,
    /// The temporary copy the child reads, when the file needed one: removed when the reader is
    /// dropped, whatever became of the child.
    _temp: Option<tempfile::TempDir>,
}

/// A running reader process.
struct Process {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    /// Drains the child's stderr (so it never blocks on a full pipe); gives what it kept.
    stderr: Option<JoinHandle<Vec<u8>>>,
}

/// What a reply holds.
enum Reply {
    Open(usize),
    Frame(Frame),
    Topology(Box<Topology>),
}

impl ContainedReader {
    /// Opens `path` in `format`; in a reader process unless `contain` is false or no reader
    /// executable is found. Fails like [`ChemReader::open`], or with a one-line error when the
    /// reader process crashes while opening the file.
    pub(crate) fn open(path: &Path, format: &FileFormat, contain: bool) -> Result<Self, IoError> {
        let exe = if contain { reader_exe() } else { None };
        let Some(exe) = exe else {
            let reader = ChemReader::open(path, format)?;
            return Ok(ContainedReader {
                path: path.to_path_buf(),
                format: format.clone(),
                base: format.base,
                len: reader.len(),
                truncated: reader.truncated().map(|(t, r)| (t.to_string(), r)),
                backend: Backend::InProcess(reader),
            });
        };
        let prepared = check_and_prepare(path, format)?;
        let mut args: Vec<OsString> = vec![
            READER_ARG.into(),
            format.base.into(),
            prepared.chemfiles.clone().into(),
            path.as_os_str().to_owned(),
        ];
        if prepared.open_path != path {
            args.push(prepared.open_path.as_os_str().to_owned());
        }
        let launch = Launch {
            exe,
            args,
            _temp: prepared.temp,
        };
        let mut reader = ContainedReader {
            path: path.to_path_buf(),
            format: format.clone(),
            base: format.base,
            len: 0,
            truncated: prepared.truncated.map(|t| (t, prepared.cut_removed)),
            backend: Backend::Child {
                launch,
                process: None,
            },
        };
        reader.len = reader.start(None)?;
        Ok(reader)
    }

    /// The file this reader reads.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// The format without compression (`DCD`, `GRO`).
    pub(crate) fn base(&self) -> &'static str {
        self.base
    }

    /// Number of frames.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// See [`ChemReader::truncated`].
    pub(crate) fn truncated(&self) -> Option<(&str, bool)> {
        self.truncated
            .as_ref()
            .map(|(t, removed)| (t.as_str(), *removed))
    }

    /// Reads frame `index`; positions are checked to be finite.
    pub(crate) fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        let frame = self.read_unchecked(index)?;
        check_positions(&self.path, index, &frame.positions)?;
        Ok(frame)
    }

    /// Reads frame `index` and returns its raw positions in Å (not checked to be finite).
    pub(crate) fn read_positions(&mut self, index: usize) -> Result<Vec<Vec3>, IoError> {
        Ok(self.read_unchecked(index)?.positions)
    }

    /// Reads frame `index` and returns the topology it carries; see
    /// [`ChemReader::read_topology`].
    pub(crate) fn read_topology(&mut self, index: usize) -> Result<Topology, IoError> {
        self.topology(index).map_err(|e| self.placed(e))
    }

    /// A PDB reader's error with the line number of the record it quotes (see
    /// [`pdb_models::name_line`]); other errors as they are.
    fn placed(&self, error: IoError) -> IoError {
        if self.base != "PDB" {
            return error;
        }
        let locate = |message: &str| {
            let (bytes, _) = read_all(&self.path, &self.format).ok()?;
            pdb_models::name_line(&bytes, message)
        };
        match error {
            IoError::BadFrame {
                path,
                frame,
                message,
            } => IoError::BadFrame {
                path,
                frame,
                message: locate(&message).unwrap_or(message),
            },
            IoError::Unreadable { path, message } => IoError::Unreadable {
                path,
                message: locate(&message).unwrap_or(message),
            },
            other => other,
        }
    }

    fn topology(&mut self, index: usize) -> Result<Topology, IoError> {
        if let Backend::InProcess(reader) = &mut self.backend {
            return reader.read_topology(index);
        }
        match self.request(protocol::OP_TOPOLOGY, index)? {
            Reply::Topology(t) => Ok(*t),
            _ => Err(self.died(index, Died::Garbage)),
        }
    }

    fn read_unchecked(&mut self, index: usize) -> Result<Frame, IoError> {
        self.frame(index).map_err(|e| self.placed(e))
    }

    fn frame(&mut self, index: usize) -> Result<Frame, IoError> {
        if let Backend::InProcess(reader) = &mut self.backend {
            return reader.read_unchecked(index);
        }
        if index >= self.len {
            return Err(IoError::FrameOutOfRange {
                path: self.path.clone(),
                frame: index,
                len: self.len,
            });
        }
        match self.request(protocol::OP_FRAME, index)? {
            Reply::Frame(f) => Ok(f),
            _ => Err(self.died(index, Died::Garbage)),
        }
    }

    /// Sends request `op` for frame `index` (starting a reader process when none runs) and
    /// reads its reply; a crash or garbage becomes an error naming the frame.
    fn request(&mut self, op: u8, index: usize) -> Result<Reply, IoError> {
        if matches!(&self.backend, Backend::Child { process: None, .. }) {
            let len = self.start(Some(index))?;
            if len != self.len {
                let message = format!(
                    "the restarted reader counts {len} frames, not {} (did the file change?)",
                    self.len
                );
                self.stop(false);
                return Err(IoError::bad_frame(&self.path, index, message));
            }
        }
        let Backend::Child {
            process: Some(process),
            ..
        } = &mut self.backend
        else {
            return Err(self.died(index, Died::Garbage));
        };
        let mut request = protocol::Writer::tag(op);
        request.u64(index as u64);
        if protocol::send(&mut process.stdin, &request.0).is_err() {
            return Err(self.died(index, Died::Gone));
        }
        self.reply(Some(index))
    }

    /// Starts a reader process and reads its first reply: the frame count. `index` is the frame
    /// wanted, for the error when the child crashes (`None` while opening the file).
    fn start(&mut self, index: Option<usize>) -> Result<usize, IoError> {
        let Backend::Child { launch, process } = &mut self.backend else {
            return Ok(self.len);
        };
        let spawned = Command::new(&launch.exe)
            .args(&launch.args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = spawned.map_err(|e| {
            IoError::unreadable(
                &self.path,
                format!(
                    "cannot start the reader process {}: {e}",
                    launch.exe.display()
                ),
            )
        })?;
        let (Some(stdin), Some(stdout), Some(mut stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(IoError::unreadable(
                &self.path,
                "cannot start the reader process",
            ));
        };
        let drain = std::thread::spawn(move || {
            let mut kept = Vec::new();
            let mut buffer = [0u8; 8192];
            while let Ok(n) = stderr.read(&mut buffer) {
                if n == 0 {
                    break;
                }
                let room = MAX_STDERR.saturating_sub(kept.len());
                kept.extend_from_slice(&buffer[..n.min(room)]);
            }
            kept
        });
        *process = Some(Process {
            child,
            stdin,
            stdout: BufReader::with_capacity(1 << 20, stdout),
            stderr: Some(drain),
        });
        match self.reply(index)? {
            Reply::Open(len) => Ok(len),
            _ => Err(self.died_at(index, Died::Garbage)),
        }
    }

    /// Reads the reply to the last request (warnings go to [`warnings`]); `index` as in
    /// [`ContainedReader::start`].
    fn reply(&mut self, index: Option<usize>) -> Result<Reply, IoError> {
        loop {
            let Backend::Child {
                process: Some(process),
                ..
            } = &mut self.backend
            else {
                return Err(self.died_at(index, Died::Garbage));
            };
            let body = match protocol::receive(&mut process.stdout) {
                Ok(Some(body)) => body,
                Ok(None) | Err(_) => return Err(self.died_at(index, Died::Gone)),
            };
            match self.parse(&body, index) {
                Ok(Some(reply)) => return Ok(reply),
                Ok(None) => continue,
                Err(Some(error)) => return Err(error),
                Err(None) => return Err(self.died_at(index, Died::Garbage)),
            }
        }
    }

    /// One message: a reply, `Ok(None)` for a warning, `Err(Some)` for the reader's error,
    /// `Err(None)` for garbage.
    fn parse(&self, body: &[u8], index: Option<usize>) -> Result<Option<Reply>, Option<IoError>> {
        let garbage = |_: Garbage| None;
        let Some((&tag, rest)) = body.split_first() else {
            return Err(None);
        };
        let mut r = Reader(rest);
        match tag {
            TAG_WARNING => {
                warnings::push(&r.str().map_err(garbage)?);
                Ok(None)
            }
            TAG_ERROR => Err(Some(
                protocol::decode_error(&mut r, &self.path).map_err(garbage)?,
            )),
            TAG_OPEN => {
                let version = r.u64().map_err(garbage)?;
                let len = r.u64().map_err(garbage)?;
                r.end().map_err(garbage)?;
                if version != child::PROTOCOL {
                    return Err(Some(IoError::unreadable(
                        &self.path,
                        "the reader process speaks another protocol version",
                    )));
                }
                Ok(Some(Reply::Open(usize::try_from(len).map_err(|_| None)?)))
            }
            TAG_FRAME => {
                let frame = protocol::decode_frame(&mut r, index.unwrap_or(0));
                Ok(Some(Reply::Frame(frame.map_err(garbage)?)))
            }
            TAG_TOPOLOGY => Ok(Some(Reply::Topology(Box::new(
                protocol::decode_topology(&mut r).map_err(garbage)?,
            )))),
            _ => Err(None),
        }
    }

    /// The error for frame `index` when the reader process died or misbehaved; it is stopped
    /// (the next request starts another).
    fn died(&mut self, index: usize, how: Died) -> IoError {
        self.died_at(Some(index), how)
    }

    fn died_at(&mut self, index: Option<usize>, how: Died) -> IoError {
        let status = self.stop(matches!(how, Died::Gone));
        let what = match (how, status) {
            (_, Some(Ended::Signal(signal))) => {
                format!("the reader process crashed ({})", signal_name(signal))
            }
            (Died::Garbage, _) => "the reader process sent an invalid reply".to_string(),
            (Died::Gone, Some(Ended::Code(code))) => {
                format!("the reader process ended unexpectedly (exit status {code})")
            }
            (Died::Gone, None) => "the reader process ended unexpectedly".to_string(),
        };
        match index {
            Some(index) => IoError::bad_frame(&self.path, index, what),
            None => IoError::unreadable(&self.path, format!("{what} while opening the file")),
        }
    }

    /// Ends the reader process, if one runs, and says how it ended. A child whose stdout
    /// closed (`patient`) is given up to two seconds to finish dying (a core dump takes a
    /// moment) before it is killed; otherwise it is killed at once.
    fn stop(&mut self, patient: bool) -> Option<Ended> {
        use std::os::unix::process::ExitStatusExt;
        let Backend::Child { process, .. } = &mut self.backend else {
            return None;
        };
        let mut process = process.take()?;
        drop(process.stdin);
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(2);
        let status = loop {
            match process.child.try_wait() {
                Ok(Some(status)) => break Some(status),
                Ok(None) if patient && std::time::Instant::now() < deadline => {
                    std::thread::sleep(std::time::Duration::from_millis(5));
                }
                _ => {
                    let _ = process.child.kill();
                    let _ = process.child.wait();
                    break None;
                }
            }
        };
        // Its stderr is dropped unread: library text is never shown.
        if let Some(drain) = process.stderr.take() {
            let _ = drain.join();
        }
        status.map(|s| match s.signal() {
            Some(signal) => Ended::Signal(signal),
            None => Ended::Code(s.code().unwrap_or(-1)),
        })
    }
}

impl Drop for ContainedReader {
    fn drop(&mut self) {
        self.stop(false);
    }
}

/// How the conversation with a reader process broke.
#[derive(Clone, Copy)]
enum Died {
    /// Its stdout closed (it exited or crashed).
    Gone,
    /// It sent something that is not a reply.
    Garbage,
}

/// How a reader process ended.
enum Ended {
    Signal(i32),
    Code(i32),
}

/// `SIGSEGV` for 11, and so on; `signal N` for the others.
fn signal_name(signal: i32) -> String {
    let name = match signal {
        libc::SIGSEGV => "SIGSEGV",
        libc::SIGABRT => "SIGABRT",
        libc::SIGBUS => "SIGBUS",
        libc::SIGFPE => "SIGFPE",
        libc::SIGILL => "SIGILL",
        libc::SIGKILL => "SIGKILL",
        libc::SIGTERM => "SIGTERM",
        _ => return format!("signal {signal}"),
    };
    name.to_string()
}
