//! The mutation test of issue 10: seeded mutants (bit flips, truncations, chunks duplicated or
//! deleted) of every format in the project's data (PDB, GRO, gzipped GRO, XTC, DCD, TNG, LAMMPS
//! dump, bzip2-compressed LAMMPS dump, mmCIF, gzipped mmCIF), 100 per format, each run through
//! the real binary (`mdsurf surface`) with a time limit. Every run must end with exit 0 or 2
//! (never a signal, never a panic's 101, never a hang), print no panic and no third-party
//! library noise, give exactly one line of error on exit 2 (at most one note on exit 0), and
//! stay under 1 GB of resident memory.
//!
//! Run many more locally: `MDSURF_MUTANTS=2000 MDSURF_MUTANT_SEED=7 cargo test --release
//! io_mutants -- --nocapture` (or `scripts/mutants 2000 7`). A failing mutant is kept next to the
//! report (its path is printed) so it can be replayed by hand.

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use crate::data_support::data;

/// Mutants per format in CI.
const DEFAULT_PER_FORMAT: usize = 100;
/// The committed seed.
const DEFAULT_SEED: u64 = 0x5eed_1010;
/// A run past this is a hang.
pub(crate) const TIME_LIMIT: Duration = Duration::from_secs(30);
/// Peak resident memory allowed per run (KiB).
const MAX_RSS_KIB: i64 = 1024 * 1024;
/// Parallel runs.
pub(crate) const WORKERS: usize = 2;

/// One format under test: the file mutated, the topology it needs (unmutated), and the
/// extension the mutant is written with.
struct Case {
    name: &'static str,
    bytes: Vec<u8>,
    topology: Option<PathBuf>,
    extension: &'static str,
}

fn cases() -> Vec<Case> {
    let read = |name: &str| std::fs::read(data(name)).expect("test data");
    let gzip = |bytes: &[u8]| {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut e, bytes).expect("gzip");
        e.finish().expect("gzip")
    };
    // The plain LAMMPS dump: the first four frames of the bzip2 file, decompressed.
    let mut dump = Vec::new();
    bzip2::read::BzDecoder::new(&read("spce_all_coords.lammpstrj.bz2")[..])
        .read_to_end(&mut dump)
        .expect("bunzip2");
    let frame_starts: Vec<usize> = dump
        .windows(14)
        .enumerate()
        .filter(|(_, w)| *w == b"ITEM: TIMESTEP")
        .map(|(k, _)| k)
        .collect();
    dump.truncate(frame_starts.get(4).copied().unwrap_or(dump.len()));
    vec![
        Case {
            name: "PDB",
            bytes: read("1hpv.pdb"),
            topology: None,
            extension: "pdb",
        },
        Case {
            name: "GRO",
            bytes: read("md_1u19.gro"),
            topology: None,
            extension: "gro",
        },
        Case {
            // A smaller gzipped GRO than YiiP_lipids.gro.gz (same format, quicker runs).
            name: "GRO.GZ",
            bytes: gzip(&read("md_1u19.gro")),
            topology: None,
            extension: "gro.gz",
        },
        Case {
            name: "XTC",
            bytes: read("md_1u19.xtc"),
            topology: Some(data("md_1u19.gro")),
            extension: "xtc",
        },
        Case {
            name: "DCD",
            bytes: read("adk_dims.dcd"),
            topology: Some(data("adk_open.pdb")),
            extension: "dcd",
        },
        Case {
            name: "TNG",
            bytes: read("argon_npt_compressed.tng"),
            topology: None,
            extension: "tng",
        },
        Case {
            name: "LAMMPS",
            bytes: dump,
            topology: None,
            extension: "lammpstrj",
        },
        Case {
            name: "LAMMPS.BZ2",
            bytes: read("spce_all_coords.lammpstrj.bz2"),
            topology: None,
            extension: "lammpstrj.bz2",
        },
        Case {
            name: "mmCIF",
            bytes: crate::data_support::gunzipped("1gbt.cif.gz").into_bytes(),
            topology: None,
            extension: "cif",
        },
        Case {
            name: "mmCIF.GZ",
            bytes: read("1a7g.cif.gz"),
            topology: None,
            extension: "cif.gz",
        },
    ]
}

/// A small deterministic generator (xorshift64), so the mutants are the same on every run.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One seeded mutant of `bytes`: 1 to 8 bit flips, a truncation, or a chunk of up to 4 KiB
/// duplicated elsewhere or deleted (as an interrupted copy or a bad concatenation leaves).
fn mutate(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let n = out.len();
    match rng.below(4) {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let at = rng.below(n);
                out[at] ^= 1 << rng.below(8);
            }
        }
        1 => out.truncate(1 + rng.below(n - 1)),
        2 => {
            let (a, len, at) = (rng.below(n), 1 + rng.below(4096), rng.below(n));
            let chunk = out[a..(a + len).min(n)].to_vec();
            out.splice(at..at, chunk);
        }
        _ => {
            let (a, len) = (rng.below(n), 1 + rng.below(4096));
            out.drain(a..(a + len).min(n));
        }
    }
    out
}

/// How one run ended.
pub(crate) struct Outcome {
    /// Exit code; `None` when a signal ended it.
    pub(crate) code: Option<i32>,
    pub(crate) signal: Option<i32>,
    pub(crate) stderr: String,
    pub(crate) timed_out: bool,
    /// Peak resident memory (KiB).
    pub(crate) max_rss_kib: i64,
}

/// Runs `mdsurf ARGS`, killing it after [`TIME_LIMIT`], and collects its peak memory: the
/// high-water mark of its own address space (`VmHWM` in `/proc/PID/status`), read every 5 ms
/// while it runs. Not `wait4`'s `ru_maxrss`: Linux carries the spawning process's peak into a
/// child's (the child starts as a copy of, or on, the parent's memory until it execs), so a
/// test process that once held 1 GiB (GPU tests beside this one on an NVIDIA machine) made
/// every mutant look like 1 GiB.
#[allow(clippy::zombie_processes)] // reaped by `waitpid` below, not by `Child::wait`
pub(crate) fn run(args: &[String]) -> Outcome {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("cannot start mdsurf");
    let mut stderr = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut text = Vec::new();
        stderr.read_to_end(&mut text).ok();
        String::from_utf8_lossy(&text).into_owned()
    });
    let pid = child.id() as libc::pid_t;
    let start = Instant::now();
    let mut timed_out = false;
    let mut peak_kib = 0;
    let status = loop {
        if let Some(kib) = own_peak_kib(pid) {
            peak_kib = peak_kib.max(kib);
        }
        let mut status = 0;
        // SAFETY: plain FFI call with valid pointers to locals; `pid` is our own child, reaped
        // only here (std's `Child` is never waited on).
        let done = unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) };
        if done == pid {
            break status;
        }
        if !timed_out && start.elapsed() > TIME_LIMIT {
            timed_out = true;
            // SAFETY: signalling our own child, not yet reaped.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let exited = libc::WIFEXITED(status);
    Outcome {
        code: exited.then(|| libc::WEXITSTATUS(status)),
        signal: libc::WIFSIGNALED(status).then(|| libc::WTERMSIG(status)),
        stderr: reader.join().unwrap_or_default(),
        timed_out,
        max_rss_kib: peak_kib,
    }
}

/// The peak resident memory (KiB) of `pid` once it runs mdsurf (before its exec the child
/// still shows the test process's memory), or None when it cannot be read.
fn own_peak_kib(pid: libc::pid_t) -> Option<i64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .map(str::trim)
    };
    if field("Name:")? != "mdsurf" {
        return None;
    }
    field("VmHWM:")?.trim_end_matches("kB").trim().parse().ok()
}

/// Why an outcome breaks the rules, if it does.
pub(crate) fn violation(o: &Outcome) -> Option<String> {
    let lines: Vec<&str> = o.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    let noise = ["panicked", "TNG library", "RUST_BACKTRACE", ".cpp:", ".c:"];
    if o.timed_out {
        Some(format!("no exit within {TIME_LIMIT:?}"))
    } else if let Some(signal) = o.signal {
        Some(format!("killed by signal {signal}"))
    } else if !matches!(o.code, Some(0) | Some(2)) {
        Some(format!("exit code {:?}", o.code))
    } else if let Some(n) = noise.iter().find(|n| o.stderr.contains(*n)) {
        Some(format!("stderr contains {n:?}"))
    } else if o.code == Some(2) && lines.len() != 1 {
        Some(format!("{} lines of error", lines.len()))
    } else if o.code == Some(0) && lines.len() > 1 {
        Some(format!("{} lines on success", lines.len()))
    } else if o.max_rss_kib > MAX_RSS_KIB {
        Some(format!("peak memory {} MiB", o.max_rss_kib / 1024))
    } else {
        None
    }
}

pub(crate) fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
fn mutants_of_every_format_end_cleanly() {
    let per_format: usize = env_or("MDSURF_MUTANTS", DEFAULT_PER_FORMAT);
    let seed: u64 = env_or("MDSURF_MUTANT_SEED", DEFAULT_SEED);
    let dir = tempfile::tempdir().unwrap();
    // Each mutant: (case index, mutant number, path).
    let mut jobs = Vec::new();
    let cases = cases();
    for (c, case) in cases.iter().enumerate() {
        // One generator per format, so adding a format does not change the others' mutants.
        let mut rng = Rng(seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(c as u64 + 1)));
        for k in 0..per_format {
            let path = dir.path().join(format!("m{c}_{k}.{}", case.extension));
            std::fs::write(&path, mutate(&case.bytes, &mut rng)).expect("write mutant");
            jobs.push((c, k, path));
        }
    }
    let (counts, failures) = run_pool(&jobs, cases.len(), |(c, k, path)| {
        let case = &cases[*c];
        let mut args = vec!["surface".to_string()];
        args.extend(case.topology.iter().map(|t| t.display().to_string()));
        args.push(path.display().to_string());
        // Two frames keep it quick; a damaged middle or end is still probed when the file
        // opens.
        args.extend(
            [
                "--backend",
                "cpu",
                "--spacing",
                "2",
                "-q",
                "--frames",
                "0:2",
            ]
            .map(String::from),
        );
        let o = run(&args);
        let failure = violation(&o).map(|why| {
            let kept = std::env::temp_dir()
                .join(format!("mdsurf_mutant_{seed:x}_{c}_{k}.{}", case.extension));
            std::fs::copy(path, &kept).ok();
            format!(
                "{} mutant {k} (seed {seed:#x}, kept as {}): {why}: {}",
                case.name,
                kept.display(),
                o.stderr.trim()
            )
        });
        (*c, o, failure)
    });
    report(
        cases.iter().map(|c| c.name),
        counts,
        failures,
        jobs.len(),
        "mutants",
    );
}

/// Runs `check` on every one of `jobs` on [`WORKERS`] threads. `check` runs one mutant and gives
/// its format's index (below `formats`), the run's outcome and, when it broke the rules, the
/// failure line. Returns the [read, refused in one line] counts per format and the failure
/// lines.
pub(crate) fn run_pool<J: Sync>(
    jobs: &[J],
    formats: usize,
    check: impl Fn(&J) -> (usize, Outcome, Option<String>) + Sync,
) -> (Vec<[usize; 2]>, Vec<String>) {
    let next = Mutex::new(0usize);
    let failures = Mutex::new(Vec::new());
    let counts = Mutex::new(vec![[0usize; 2]; formats]);
    std::thread::scope(|scope| {
        for _ in 0..WORKERS {
            scope.spawn(|| {
                loop {
                    let job = {
                        let mut n = next.lock().unwrap();
                        *n += 1;
                        jobs.get(*n - 1)
                    };
                    let Some(job) = job else { break };
                    let (format, o, failure) = check(job);
                    counts.lock().unwrap()[format][usize::from(o.code == Some(2))] += 1;
                    failures.lock().unwrap().extend(failure);
                }
            });
        }
    });
    (counts.into_inner().unwrap(), failures.into_inner().unwrap())
}

/// Prints how many mutants of each format (`names`, with `counts` of [read, refused]) were read
/// or refused, and fails listing every one of the `failures` among `total` runs of `what`.
pub(crate) fn report<'a>(
    names: impl Iterator<Item = &'a str>,
    counts: Vec<[usize; 2]>,
    failures: Vec<String>,
    total: usize,
    what: &str,
) {
    for (name, [ok, refused]) in names.zip(counts) {
        eprintln!("{name}: {ok} read, {refused} refused in one line");
    }
    assert!(
        failures.is_empty(),
        "{} of {total} {what} broke the rules:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
