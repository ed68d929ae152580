//! How many bytes a temporary copy of a user's file (a decompressed `.gz`, `.bz2` or `.xz`) may
//! take in its folder (TMPDIR): what the folder's file system has free for unprivileged users,
//! less a reserve; and where that file system is memory (tmpfs or ramfs: `/tmp` on many
//! cluster nodes, `/dev/shm`), also at most half of the memory budget
//! ([`crate::surface::memory`]), since a copy there is memory charged to the job (its cgroup:
//! Slurm's `--mem`) and the other half is left to the computation. A copy that reaches its room
//! stops there, as a cut stream does: the frames before are read, and the frame it cut is
//! reported with the reason.

use std::ffi::CString;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;

/// Bytes of free space a copy leaves on a disk: 64 MiB or 1 % of the file system, the larger.
const DISK_RESERVE_MIN: u64 = 64 << 20;

/// The room of a temporary copy, and where it is (for messages).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CopyRoom {
    /// Bytes the copy may take.
    pub bytes: u64,
    /// The folder and what bounds it, e.g. `/tmp (tmpfs, half the memory budget)`.
    pub place: String,
}

impl CopyRoom {
    /// Why a copy stopped after `written` bytes, for the cut frame's message.
    pub fn reason(&self, written: u64) -> String {
        format!(
            "the decompressed copy stopped at {} MB, the room its folder allows: {}; set TMPDIR to \
             a folder with more space, or decompress the file first",
            written >> 20,
            self.place
        )
    }
}

/// The room for a copy in `folder` (see the module documentation); unbounded where the file
/// system cannot be asked. The `test-hooks` build takes it from `MDSURF_TEST_COPY_ROOM` (bytes)
/// when that is set.
pub(crate) fn copy_room(folder: &Path) -> CopyRoom {
    #[cfg(feature = "test-hooks")]
    if let Some(bytes) = std::env::var("MDSURF_TEST_COPY_ROOM")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        return CopyRoom {
            bytes,
            place: format!("{} (MDSURF_TEST_COPY_ROOM)", folder.display()),
        };
    }
    let Some(space) = file_system(folder) else {
        return CopyRoom {
            bytes: u64::MAX,
            place: folder.display().to_string(),
        };
    };
    room_of(
        folder,
        space,
        crate::surface::memory::available_memory_bytes(),
    )
}

/// What [`copy_room`] needs of a file system, in bytes.
#[derive(Debug, Clone, Copy)]
struct FileSystem {
    /// Free for unprivileged users (`f_bavail`).
    free: u64,
    /// Its size (`f_blocks`).
    size: u64,
    /// True for tmpfs and ramfs (memory).
    in_memory: bool,
}

/// The room in `folder` on `space`, with `memory` the memory budget in bytes.
fn room_of(folder: &Path, space: FileSystem, memory: u64) -> CopyRoom {
    let reserve = DISK_RESERVE_MIN.max(space.size / 100);
    let disk = space.free.saturating_sub(reserve);
    if space.in_memory {
        let half_memory = memory / 2;
        let (bytes, bound) = if half_memory < disk {
            (half_memory, "half the memory budget")
        } else {
            (disk, "its free space")
        };
        CopyRoom {
            bytes,
            place: format!("{} (memory, tmpfs: {bound})", folder.display()),
        }
    } else {
        CopyRoom {
            bytes: disk,
            place: format!("{} (its free space)", folder.display()),
        }
    }
}

/// `statfs(2)` of the file system holding `folder`.
fn file_system(folder: &Path) -> Option<FileSystem> {
    /// `f_type` of tmpfs and ramfs (linux/magic.h).
    const TMPFS_MAGIC: i64 = 0x0102_1994;
    const RAMFS_MAGIC: i64 = 0x8584_58f6;
    let path = CString::new(folder.as_os_str().as_bytes()).ok()?;
    // SAFETY: `path` is a NUL-terminated string and `stat` a zeroed struct statfs that the
    // call fills; nothing is kept past the call.
    let mut stat: libc::statfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statfs(path.as_ptr(), &mut stat) } != 0 {
        return None;
    }
    let block = stat.f_bsize as u64;
    #[allow(clippy::unnecessary_cast)] // f_type's width differs between C libraries
    let kind = stat.f_type as i64;
    Some(FileSystem {
        free: (stat.f_bavail as u64).saturating_mul(block),
        size: (stat.f_blocks as u64).saturating_mul(block),
        in_memory: kind == TMPFS_MAGIC || kind == RAMFS_MAGIC,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GIB: u64 = 1 << 30;

    #[test]
    fn a_disk_keeps_its_reserve_and_memory_keeps_half_the_budget() {
        let folder = Path::new("/scratch");
        let disk = FileSystem {
            free: 50 * GIB,
            size: 1000 * GIB,
            in_memory: false,
        };
        // 1 % of 1000 GiB stays free; memory does not bound a disk.
        assert_eq!(room_of(folder, disk, GIB).bytes, 40 * GIB);
        let small_disk = FileSystem {
            free: GIB,
            size: 2 * GIB,
            in_memory: false,
        };
        assert_eq!(room_of(folder, small_disk, GIB).bytes, GIB - (64 << 20));
        let tmpfs = FileSystem {
            free: 60 * GIB,
            size: 64 * GIB,
            in_memory: true,
        };
        // Slurm's --mem=8G leaves the copy 4 GiB.
        let room = room_of(Path::new("/tmp"), tmpfs, 8 * GIB);
        assert_eq!(room.bytes, 4 * GIB);
        assert!(
            room.place.contains("half the memory budget"),
            "{}",
            room.place
        );
        let full = FileSystem {
            free: 10 << 20,
            size: 64 << 20,
            in_memory: true,
        };
        assert_eq!(room_of(Path::new("/dev/shm"), full, 8 * GIB).bytes, 0);
    }

    #[test]
    fn the_temporary_folder_has_a_room() {
        let room = copy_room(&std::env::temp_dir());
        assert!(room.bytes > 0, "{room:?}");
        let reason = room.reason(3 << 20);
        assert!(
            reason.contains("3 MB") && reason.contains("TMPDIR"),
            "{reason}"
        );
    }
}
