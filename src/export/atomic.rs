//! Atomic output for every file mdsurf writes (meshes, stats, pictures): data goes to a temporary
//! file in the target's directory and is renamed over the target only when writing succeeded, so
//! a failure never leaves a half-written or clobbered file. Symbolic links are written through
//! and special files (devices, pipes) written in place, never replaced by a regular file.

use std::fs;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use super::ExportError;

/// Where the bytes go: a temporary file renamed over the target at the end, or, for a target
/// that is not a regular file (a terminal, a pipe, `/dev/stdout`), that file itself.
pub enum Sink {
    /// A temporary file beside the (link-resolved) target.
    Temp(NamedTempFile),
    /// A special file written in place (it cannot be replaced, and must not be).
    Direct(fs::File),
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            Sink::Temp(t) => t.write(buf),
            Sink::Direct(f) => f.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self {
            Sink::Temp(t) => t.flush(),
            Sink::Direct(f) => f.flush(),
        }
    }
}

impl Seek for Sink {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        match self {
            Sink::Temp(t) => t.seek(pos),
            Sink::Direct(f) => f.seek(pos),
        }
    }
}

/// A file being written: a buffered temporary file next to its final path.
///
/// Dropping it without [`AtomicFile::commit`] deletes the temporary file and leaves the target
/// as it was. A symbolic link is written through (the file it points at is replaced, the link
/// stays); a special file (device, pipe, socket) is written in place.
pub struct AtomicFile {
    /// The path the user gave (for messages).
    target: PathBuf,
    /// The regular file replaced at the end (`target` with symbolic links resolved).
    real: PathBuf,
    writer: BufWriter<Sink>,
}

impl AtomicFile {
    /// Starts writing `target`: creates a temporary file in the same directory as the file
    /// `target` resolves to, or opens `target` itself when it is a special file.
    pub fn create(target: &Path) -> Result<AtomicFile, ExportError> {
        if target.is_dir() {
            return Err(ExportError::io(
                target,
                io::Error::new(io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
        // Opening follows links, so a special file (device, pipe) is written through the path
        // as given; a regular file is replaced where its links lead.
        let special = fs::metadata(target).is_ok_and(|meta| !meta.is_file());
        let real = if special {
            target.to_path_buf()
        } else {
            fs::canonicalize(target).unwrap_or_else(|_| resolve_links(target))
        };
        let sink = if special {
            Sink::Direct(
                fs::OpenOptions::new()
                    .write(true)
                    .open(target)
                    .map_err(|e| ExportError::io(target, e))?,
            )
        } else {
            let dir = match real.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            Sink::Temp(
                tempfile::Builder::new()
                    .prefix(".mdsurf-")
                    .suffix(".tmp")
                    .tempfile_in(dir)
                    .map_err(|e| ExportError::io(target, e))?,
            )
        };
        Ok(AtomicFile {
            target: target.to_path_buf(),
            real,
            writer: BufWriter::with_capacity(1 << 20, sink),
        })
    }

    /// The path the file will have once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The buffered writer.
    pub fn writer(&mut self) -> &mut BufWriter<Sink> {
        &mut self.writer
    }

    /// Flushes, syncs and renames the temporary file over the target (a special file is only
    /// flushed).
    pub fn commit(self) -> Result<(), ExportError> {
        let target = self.target;
        let sink = self
            .writer
            .into_inner()
            .map_err(|e| ExportError::io(&target, e.into_error()))?;
        let tmp = match sink {
            Sink::Direct(mut f) => return f.flush().map_err(|e| ExportError::io(&target, e)),
            Sink::Temp(tmp) => tmp,
        };
        tmp.as_file()
            .sync_all()
            .map_err(|e| ExportError::io(&target, e))?;
        set_permissions(&tmp, &self.real);
        tmp.persist(&self.real)
            .map_err(|e| ExportError::io(&target, e.error))?;
        Ok(())
    }
}

/// `path` with symbolic links followed (up to 40 of them): the file a write to `path` changes.
/// A dangling link resolves to the path it names.
pub fn resolve_links(path: &Path) -> PathBuf {
    let mut current = path.to_path_buf();
    for _ in 0..40 {
        match fs::read_link(&current) {
            Ok(next) => {
                current = match current.parent() {
                    Some(dir) if next.is_relative() => dir.join(next),
                    _ => next,
                };
            }
            Err(_) => break,
        }
    }
    current
}

/// Gives the new file the permissions of the file it replaces, or rw-r--r-- (temporary files
/// are created private). Best effort: a failure here does not fail the write.
fn set_permissions(tmp: &NamedTempFile, target: &Path) {
    let perms = match fs::metadata(target) {
        Ok(meta) => meta.permissions(),
        Err(_) => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                fs::Permissions::from_mode(0o644)
            }
            #[cfg(not(unix))]
            {
                return;
            }
        }
    };
    let _ = tmp.as_file().set_permissions(perms);
}

/// Writes `target` atomically with `write`: the target changes only if `write` and the final
/// rename both succeed.
pub fn write_atomic<F>(target: &Path, write: F) -> Result<(), ExportError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let mut file = AtomicFile::create(target)?;
    write(file.writer()).map_err(|e| ExportError::io(target, e))?;
    file.commit()
}
