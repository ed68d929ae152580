//! Atomic output for every file mdsurf writes (meshes, stats, pictures): data goes to a temporary
//! file in the target's directory and is renamed over the target only when writing succeeded, so
//! a failure never leaves a half-written or clobbered file.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use super::ExportError;

/// A file being written: a buffered temporary file next to its final path.
///
/// Dropping it without [`AtomicFile::commit`] deletes the temporary file and leaves the target
/// as it was.
pub struct AtomicFile {
    target: PathBuf,
    writer: BufWriter<NamedTempFile>,
}

impl AtomicFile {
    /// Starts writing `target`: creates a temporary file in the same directory.
    pub fn create(target: &Path) -> Result<AtomicFile, ExportError> {
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if target.is_dir() {
            return Err(ExportError::io(
                target,
                io::Error::new(io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
        let tmp = tempfile::Builder::new()
            .prefix(".mdsurf-")
            .suffix(".tmp")
            .tempfile_in(dir)
            .map_err(|e| ExportError::io(target, e))?;
        Ok(AtomicFile {
            target: target.to_path_buf(),
            writer: BufWriter::with_capacity(1 << 20, tmp),
        })
    }

    /// The path the file will have once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The buffered writer into the temporary file.
    pub fn writer(&mut self) -> &mut BufWriter<NamedTempFile> {
        &mut self.writer
    }

    /// Flushes, syncs and renames the temporary file over the target.
    pub fn commit(self) -> Result<(), ExportError> {
        let target = self.target;
        let tmp = self
            .writer
            .into_inner()
            .map_err(|e| ExportError::io(&target, e.into_error()))?;
        tmp.as_file()
            .sync_all()
            .map_err(|e| ExportError::io(&target, e))?;
        set_permissions(&tmp, &target);
        tmp.persist(&target)
            .map_err(|e| ExportError::io(&target, e.error))?;
        Ok(())
    }
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
