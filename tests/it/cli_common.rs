//! What the `tests/cli_*.rs` files share: running the real `mdsurf` binary, locating the demo and
//! `tests/data`, and small readers for the CSV and mesh files it writes.

#![allow(dead_code)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The result of one run of the binary.
pub struct Run {
    /// Exit status code (-1 when killed by a signal).
    pub code: i32,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Run {
    /// The last non-empty line of stderr.
    pub fn last_line(&self) -> &str {
        self.stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("")
    }
}

/// Runs `mdsurf ARGS` in `dir`.
pub fn mdsurf(dir: &Path, args: &[&str]) -> Run {
    mdsurf_env(dir, args, &[])
}

/// Runs `mdsurf ARGS` in `dir` with extra environment variables.
pub fn mdsurf_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .envs(env.iter().copied())
        .output()
        .expect("cannot start the mdsurf binary");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A file of `tests/data`, failing clearly when the data set is missing.
pub fn data(name: &str) -> String {
    let path = PathBuf::from(crate::data_support::DATA).join(name);
    assert!(
        path.is_file(),
        "test data {} is missing: see tests/data/README.md",
        path.display()
    );
    path.to_string_lossy().into_owned()
}

/// A file of the bundled demo in `assets/`.
pub fn asset(name: &str) -> String {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/")).join(name);
    assert!(path.is_file(), "demo file {} is missing", path.display());
    path.to_string_lossy().into_owned()
}

/// Runs `mdsurf bench ARGS --csv b.csv` in `dir`, asserts it succeeded and returns its CSV.
pub fn bench_csv(dir: &Path, args: &[&str]) -> Csv {
    let mut all = vec!["bench"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--csv", "b.csv"]);
    let run = mdsurf(dir, &all);
    assert_eq!(run.code, 0, "{}", run.stderr);
    Csv::read(&dir.join("b.csv"))
}

/// A stats CSV: the header and one map per row.
pub struct Csv {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, each as strings in column order.
    pub rows: Vec<Vec<String>>,
}

impl Csv {
    /// Reads `path`; every row must have as many fields as the header.
    pub fn read(path: &Path) -> Csv {
        let text = fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let columns: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        let rows: Vec<Vec<String>> = lines
            .map(|l| l.split(',').map(String::from).collect::<Vec<_>>())
            .collect();
        for r in &rows {
            assert_eq!(r.len(), columns.len(), "ragged CSV row {r:?}");
        }
        Csv { columns, rows }
    }

    /// Column `name` of every row as text.
    pub fn text_col(&self, name: &str) -> Vec<String> {
        let i = self
            .columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.columns));
        self.rows.iter().map(|r| r[i].clone()).collect()
    }

    /// Column `name` of every row as f64 (empty fields as NaN).
    pub fn col(&self, name: &str) -> Vec<f64> {
        let i = self
            .columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.columns));
        self.rows
            .iter()
            .map(|r| {
                if r[i].is_empty() {
                    f64::NAN
                } else {
                    r[i].parse().unwrap()
                }
            })
            .collect()
    }
}

/// A PLY file's header fields: `(vertices, faces, header bytes)`; checks the body size against
/// binary little-endian records of 27 and 13 bytes.
pub fn read_ply_counts(path: &Path) -> (usize, usize, usize) {
    let bytes = fs::read(path).unwrap();
    let end = b"end_header\n";
    let header_len = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("PLY without end_header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    let count = |element: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {element} ")))
            .unwrap_or_else(|| panic!("no element {element}"))
            .parse()
            .unwrap()
    };
    let (v, f) = (count("vertex"), count("face"));
    assert_eq!(
        bytes.len(),
        header_len + 27 * v + 13 * f,
        "{}",
        path.display()
    );
    (v, f, header_len)
}

/// The triangles of a binary STL file as `[[x, y, z]; 3]`, checking its size.
pub fn read_stl(path: &Path) -> Vec<[[f32; 3]; 3]> {
    let b = fs::read(path).unwrap();
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 84 + 50 * n);
    let f = |at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    (0..n)
        .map(|t| {
            let base = 84 + 50 * t + 12;
            [0, 1, 2].map(|k| [0, 1, 2].map(|c| f(base + 12 * k + 4 * c)))
        })
        .collect()
}

/// Enclosed volume (Å³) of triangles, `sum v0 . (v1 x v2) / 6`.
pub fn volume_of(tris: &[[[f32; 3]; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v.map(f64::from));
            let cross = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
        })
        .sum()
}

/// True when a wgpu adapter opens; without one, a note and false, unless `REQUIRE_GPU=1`, where
/// a missing adapter fails the test.
pub fn have_gpu() -> bool {
    match mdsurf::render::HeadlessGpu::new() {
        Ok(_) => true,
        Err(e) if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("REQUIRE_GPU=1 but {e}")
        }
        Err(e) => {
            eprintln!("note: skipping: {e}");
            false
        }
    }
}

/// Runs an ffmpeg tool (`ffprobe`, `ffmpeg`) and returns its stdout, failing (never skipping)
/// when it is not installed or fails.
pub fn ffmpeg_tool(tool: &str, args: &[&str]) -> Vec<u8> {
    let out = Command::new(tool).args(args).output().unwrap_or_else(|e| {
        panic!(
            "cannot run {tool} ({e}): install ffmpeg (`apt-get install ffmpeg`; scripts/test \
             installs it) to check the movies mdsurf writes"
        )
    });
    assert!(
        out.status.success(),
        "{tool} {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// The first video stream of `path` as ffprobe counts it: the `entries` of `stream=` (for
/// example `codec_name,nb_read_frames`), comma-separated, every frame decoded to count them.
pub fn probe_video(path: &Path, entries: &str) -> String {
    let path = path.to_str().expect("utf-8 path");
    let shown = format!("stream={entries}");
    let out = ffmpeg_tool(
        "ffprobe",
        &[
            "-v",
            "error",
            "-count_frames",
            "-select_streams",
            "v:0",
            "-show_entries",
            &shown,
            "-of",
            "csv=p=0",
            path,
        ],
    );
    String::from_utf8_lossy(&out).trim().to_string()
}

/// The length in seconds of the movie `path` as ffprobe reads it from the container.
pub fn probe_duration(path: &Path) -> f64 {
    let path = path.to_str().expect("utf-8 path");
    let out = ffmpeg_tool(
        "ffprobe",
        &[
            "-v",
            "error",
            "-show_entries",
            "format=duration",
            "-of",
            "csv=p=0",
            path,
        ],
    );
    String::from_utf8_lossy(&out)
        .trim()
        .parse()
        .expect("ffprobe duration")
}
