//! Job arrays (`--chunk I/N`, `--chunk slurm`, `mdsurf merge`): N chunks run as N local
//! processes of the real binary give, once merged, the same stats CSV byte for byte and the same
//! meshes and PNG images as one run; the merge refuses missing, duplicated and mismatched parts
//! with one line.

use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};

use crate::cli_common::{data, mdsurf, mdsurf_env};

/// adenylate kinase (3,341 atoms, 98 frames), coarse grid: a few ms per frame on the CPU.
fn inputs() -> [String; 2] {
    [data("adk_open.pdb"), data("adk_dims.dcd")]
}

/// Runs `mdsurf ARGS --chunk i/n` for every i at once (n local processes) in `dir`; each must
/// succeed.
pub(crate) fn run_chunks(dir: &Path, args: &[&str], n: usize) {
    let children: Vec<_> = (0..n)
        .map(|i| {
            Command::new(env!("CARGO_BIN_EXE_mdsurf"))
                .args(args)
                .args(["--chunk", &format!("{i}/{n}")])
                .current_dir(dir)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .expect("cannot start mdsurf")
        })
        .collect();
    for (i, child) in children.into_iter().enumerate() {
        let out = child.wait_with_output().expect("wait");
        assert!(
            out.status.success(),
            "chunk {i}/{n}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

fn surface_args<'a>(top: &'a str, traj: &'a str, stats: &'a str, mesh: &'a str) -> Vec<&'a str> {
    vec![
        "surface",
        top,
        traj,
        "--frames",
        "1:16:2",
        "--spacing",
        "1.5",
        "--backend",
        "cpu",
        "--no-timings",
        "-q",
        "--stats",
        stats,
        "-o",
        mesh,
    ]
}

#[test]
fn four_chunks_merged_equal_one_run_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::create_dir(d.join("one")).unwrap();
    fs::create_dir(d.join("arr")).unwrap();
    let [top, traj] = inputs();
    let single = mdsurf(
        d,
        &surface_args(&top, &traj, "one/stats.csv", "one/m_{frame:03}.ply"),
    );
    assert_eq!(single.code, 0, "{}", single.stderr);
    // 8 frames in 4 blocks of 2.
    run_chunks(
        d,
        &surface_args(&top, &traj, "arr/stats.csv", "arr/m_{frame:03}.ply"),
        4,
    );
    for i in 0..4 {
        let part = d.join(format!("arr/stats.part-{i:04}-of-0004.csv"));
        let text = fs::read_to_string(&part).unwrap();
        assert!(text.starts_with("# mdsurf-part chunk="), "{text}");
        assert_eq!(text.lines().count(), 4, "2 rows + 2 header lines: {text}");
    }
    let merge = mdsurf(d, &["merge", "arr/stats.csv"]);
    assert_eq!(merge.code, 0, "{}", merge.stderr);
    let one = fs::read(d.join("one/stats.csv")).unwrap();
    let merged = fs::read(d.join("arr/stats.csv")).unwrap();
    assert_eq!(
        String::from_utf8_lossy(&merged),
        String::from_utf8_lossy(&one)
    );
    assert_eq!(String::from_utf8_lossy(&one).lines().count(), 9);
    // Meshes are named by the global frame index and are the same files.
    for f in (1..16).step_by(2) {
        let name = format!("m_{f:03}.ply");
        let (a, b) = (
            fs::read(d.join("one").join(&name)).unwrap(),
            fs::read(d.join("arr").join(&name)).unwrap(),
        );
        assert!(a == b, "{name} differs");
    }
    assert_eq!(fs::read_dir(d.join("arr")).unwrap().count(), 8 + 4 + 1);
}

#[test]
fn merge_names_missing_duplicated_and_mismatched_parts_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [top, traj] = inputs();
    let args = surface_args(&top, &traj, "s.csv", "m_{frame}.stl");
    // 8 frames in 3 blocks: 3, 3, 2 (frames 1-5, 7-11, 13-15).
    run_chunks(d, &args, 3);
    let part = |i: usize| d.join(format!("s.part-{i:04}-of-0003.csv"));
    let one_line = |args: &[&str]| {
        let run = mdsurf(d, args);
        assert_eq!(run.code, 2, "{}", run.stderr);
        assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
        run.stderr
    };

    // A missing part: its frames and its file name.
    let saved = fs::read(part(1)).unwrap();
    fs::remove_file(part(1)).unwrap();
    let err = one_line(&["merge", "s.csv"]);
    assert!(
        err.contains("missing frames 7, 9, 11") && err.contains("s.part-0001-of-0003.csv"),
        "{err}"
    );
    assert!(!d.join("s.csv").exists());

    // A duplicated frame.
    let mut dup = saved.clone();
    let first_row = String::from_utf8_lossy(&saved)
        .lines()
        .nth(2)
        .unwrap()
        .to_string();
    dup.extend_from_slice(first_row.as_bytes());
    dup.push(b'\n');
    fs::write(part(1), &dup).unwrap();
    let err = one_line(&["merge", "s.csv"]);
    assert!(err.contains("duplicated frames 7"), "{err}");

    // A part of a run with another isovalue.
    let mut other = args.clone();
    other.extend(["--isovalue", "0.6", "--chunk", "1/3"]);
    let run = mdsurf(d, &other);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let err = one_line(&["merge", "s.csv"]);
    assert!(
        err.contains("isovalue=0.6") && err.contains("isovalue=0.5"),
        "{err}"
    );

    // Restored, the merge succeeds and can remove the parts.
    fs::write(part(1), &saved).unwrap();
    let ok = mdsurf(d, &["merge", "s.csv", "--remove-parts"]);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    assert!(!part(0).exists() && d.join("s.csv").exists());
}

#[test]
fn chunk_slurm_reads_the_array_variables_or_says_which_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [top, traj] = inputs();
    let args = surface_args(&top, &traj, "s.csv", "m_{frame}.stl");
    let mut slurm = args.clone();
    slurm.extend(["--chunk", "slurm"]);

    let run = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(&slurm)
        .current_dir(d)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_MIN")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("SLURM_ARRAY_TASK_ID is not set"), "{err}");

    // Task 12 of an array 10-13: chunk 2 of 4, frames 9 and 11.
    let run = mdsurf_env(
        d,
        &slurm,
        &[
            ("SLURM_ARRAY_TASK_ID", "12"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let text = fs::read_to_string(d.join("s.part-0002-of-0004.csv")).unwrap();
    let frames: Vec<&str> = text
        .lines()
        .skip(2)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(frames, ["9", "11"]);
    assert!(d.join("m_9.stl").exists() && d.join("m_11.stl").exists());
    assert!(!d.join("m_7.stl").exists());

    let bad = mdsurf(d, &[&args[..], &["--chunk", "4/4"]].concat());
    assert_eq!(bad.code, 2);
    assert!(bad.last_line().contains("bad chunk"), "{}", bad.stderr);
}

/// Size and RGBA8 pixels of a PNG.
fn pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    let image = mdsurf::render::RgbaImage::read_png(path).unwrap();
    (image.width, image.height, image.pixels)
}

#[test]
fn render_chunks_give_the_images_of_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::create_dir(d.join("one")).unwrap();
    fs::create_dir(d.join("arr")).unwrap();
    let [top, traj] = inputs();
    // The turntable angle and camera fit follow the whole run, not each chunk.
    let args = |out: &'static str| -> Vec<String> {
        [
            "render",
            &top,
            &traj,
            "--frames",
            "0:50:10",
            "--spacing",
            "2",
            "--backend",
            "cpu",
            "--size",
            "64x48",
            "--turntable",
            "20",
            "-o",
            out,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let single: Vec<String> = args("one/f_{frame:03}.png");
    let single: Vec<&str> = single.iter().map(String::as_str).collect();
    let run = mdsurf(d, &single);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let chunked = args("arr/f_{frame:03}.png");
    let chunked: Vec<&str> = chunked.iter().map(String::as_str).collect();
    run_chunks(d, &chunked, 4);
    let mut distinct = Vec::new();
    for f in (0..50).step_by(10) {
        let name = format!("f_{f:03}.png");
        let a = pixels(&d.join("one").join(&name));
        let b = pixels(&d.join("arr").join(&name));
        assert_eq!((a.0, a.1), (64, 48));
        assert!(
            a == b,
            "{name}: the chunked image differs from the single run's"
        );
        distinct.push(a.2);
    }
    // The images do change from frame to frame (so equal images mean something).
    assert!(distinct.windows(2).all(|w| w[0] != w[1]));
    assert_eq!(fs::read_dir(d.join("arr")).unwrap().count(), 5);
}
