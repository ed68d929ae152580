//! How much memory a computation may take, in bytes: the least of what the machine has free
//! (`MemAvailable`), what the process's own limits leave (`RLIMIT_AS` above the address space
//! in use, `RLIMIT_DATA` above the data in use: `ulimit -v`, `prlimit`, some batch systems) and
//! what its memory cgroup leaves (v2 `memory.max` minus `memory.current`, v1
//! `memory.limit_in_bytes` minus `memory.usage_in_bytes`: Slurm's `--mem`, containers). Large
//! allocations (grids) are checked against it first, so a run over budget stops with one line
//! instead of being killed by the kernel and losing the frames it had computed.
//!
//! Everything is read from `/proc` and `/sys` as text; on other systems (or when nothing can be
//! read) there is no known limit.

use std::path::{Path, PathBuf};

/// Allocations up to this size (bytes) go without reading the system's memory: reading it takes
/// several `/proc` and `/sys` files, which a small surface would pay every frame (2.5 % of a run
/// of adenylate kinase's interface), while a process that cannot find this much more fails on
/// far smaller allocations elsewhere.
pub const UNCHECKED_BYTES: u64 = 64 << 20;

/// The memory (bytes) to hold an allocation of `needed` bytes against: `limit` when set,
/// otherwise [`available_memory_bytes`], read only when `needed` is over [`UNCHECKED_BYTES`]
/// (`u64::MAX` below it).
pub fn memory_for(needed: u64, limit: Option<u64>) -> u64 {
    match limit {
        Some(limit) => limit,
        None if needed <= UNCHECKED_BYTES => u64::MAX,
        None => available_memory_bytes(),
    }
}

/// Memory the engine may use in bytes (see the module documentation); `u64::MAX` when no limit
/// is known.
pub fn available_memory_bytes() -> u64 {
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let limits = [
        read(Path::new("/proc/meminfo")).and_then(|t| meminfo_available(&t)),
        rlimit_headroom(
            read(Path::new("/proc/self/limits")).as_deref(),
            read(Path::new("/proc/self/status")).as_deref(),
        ),
        read(Path::new("/proc/self/cgroup")).and_then(|t| cgroup_headroom(&t, &read)),
    ];
    limits.into_iter().flatten().min().unwrap_or(u64::MAX)
}

/// `MemAvailable` of `/proc/meminfo` text, in bytes.
pub fn meminfo_available(meminfo: &str) -> Option<u64> {
    kib_field(meminfo, "MemAvailable:")
}

/// A `NAME:   123 kB` field of `/proc` text, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// The soft limit of `/proc/self/limits` row `name` (`Max address space`), in bytes; `None`
/// when unlimited or unreadable.
fn soft_limit(limits: &str, name: &str) -> Option<u64> {
    let rest = limits.lines().find_map(|l| l.strip_prefix(name))?;
    rest.split_whitespace().next()?.parse().ok()
}

/// Bytes left under the process's address-space and data limits (`/proc/self/limits`), given
/// what it uses (`/proc/self/status`: `VmSize`, `VmData`); `None` without a limit.
pub fn rlimit_headroom(limits: Option<&str>, status: Option<&str>) -> Option<u64> {
    let limits = limits?;
    let used = |field: &str| status.and_then(|s| kib_field(s, field)).unwrap_or(0);
    [
        soft_limit(limits, "Max address space").map(|l| l.saturating_sub(used("VmSize:"))),
        soft_limit(limits, "Max data size").map(|l| l.saturating_sub(used("VmData:"))),
    ]
    .into_iter()
    .flatten()
    .min()
}

/// Bytes left in the process's memory cgroup: the `/proc/self/cgroup` text names the group;
/// `read` reads a file of `/sys/fs/cgroup` (v2 first, then v1's memory controller; at the
/// group's path, else at the root, which is what a container sees). `None` without a limit.
pub fn cgroup_headroom(cgroup: &str, read: &dyn Fn(&Path) -> Option<String>) -> Option<u64> {
    let number = |p: PathBuf| -> Option<u64> { read(&p)?.trim().parse().ok() };
    let root = Path::new("/sys/fs/cgroup");
    let mut found = Vec::new();
    for line in cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next(), parts.next()?, parts.next()?);
        let path = path.trim_start_matches('/');
        let (dir, limit, usage) = match controllers {
            // v2: one unified hierarchy.
            "" => (root.to_path_buf(), "memory.max", "memory.current"),
            c if c.split(',').any(|c| c == "memory") => (
                root.join("memory"),
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            ),
            _ => continue,
        };
        for base in [dir.join(path), dir.clone()] {
            // `max` (v2) or a huge number (v1) means no limit.
            if let Some(max) = number(base.join(limit)).filter(|&m| m < 1 << 60) {
                let used = number(base.join(usage)).unwrap_or(0);
                found.push(max.saturating_sub(used));
                break;
            }
        }
    }
    found.into_iter().min()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An engine's own limit always holds; without one, small allocations are not checked and
    /// large ones are held to what the system has.
    #[test]
    fn small_allocations_skip_the_system_read() {
        assert_eq!(memory_for(1, Some(5)), 5);
        assert_eq!(memory_for(UNCHECKED_BYTES + 1, Some(5)), 5);
        assert_eq!(memory_for(UNCHECKED_BYTES, None), u64::MAX);
        #[cfg(target_os = "linux")]
        assert!(
            memory_for(UNCHECKED_BYTES + 1, None) < u64::MAX,
            "MemAvailable is read"
        );
    }

    #[test]
    fn meminfo_and_rlimits_are_read_from_proc_text() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:    2000000 kB\n";
        assert_eq!(meminfo_available(meminfo), Some(2_048_000_000));
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max data size             unlimited            unlimited            bytes\n\
                      Max address space         3000000000           unlimited            bytes\n";
        let status = "VmSize:\t  1000000 kB\nVmData:\t   100000 kB\n";
        assert_eq!(
            rlimit_headroom(Some(limits), Some(status)),
            Some(3_000_000_000 - 1_024_000_000)
        );
        let unlimited = limits.replace("3000000000", "unlimited");
        assert_eq!(rlimit_headroom(Some(&unlimited), Some(status)), None);
    }

    #[test]
    fn cgroup_limits_v1_and_v2_leave_their_headroom() {
        let v2 = |p: &Path| -> Option<String> {
            match p.to_str()? {
                "/sys/fs/cgroup/job_7/memory.max" => Some("2147483648\n".into()),
                "/sys/fs/cgroup/job_7/memory.current" => Some("147483648\n".into()),
                _ => None,
            }
        };
        assert_eq!(cgroup_headroom("0::/job_7\n", &v2), Some(2_000_000_000));
        // A container sees its own group at the root.
        let v1 = |p: &Path| -> Option<String> {
            match p.to_str()? {
                "/sys/fs/cgroup/memory/memory.limit_in_bytes" => Some("1000000000".into()),
                "/sys/fs/cgroup/memory/memory.usage_in_bytes" => Some("400000000".into()),
                _ => None,
            }
        };
        let text = "4:memory:/slurm/uid_1/job_7\n3:cpuset:/\n";
        assert_eq!(cgroup_headroom(text, &v1), Some(600_000_000));
        // `max` and v1's "unlimited" number are no limit.
        let none = |p: &Path| -> Option<String> {
            p.to_str()?
                .ends_with("limit_in_bytes")
                .then(|| "9223372036854771712".into())
        };
        assert_eq!(cgroup_headroom(text, &none), None);
    }
}
