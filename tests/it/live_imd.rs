//! Frames from a running simulation over IMD, against a real engine: GROMACS (`gmx` from the
//! Debian package; scripts/test installs it) runs a small water box built in the test, with
//! `-imdwait` so that it waits for us. The frames received must equal the positions GROMACS
//! writes to its own trajectory for the same steps; a killed engine keeps the frames received.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use mdsurf::io::{self, IoError, LiveOptions};

use crate::cli_common::{Csv, mdsurf};

/// Time step of the test runs (ps).
const DT_PS: f64 = 0.002;

/// Runs `gmx ARGS` in `dir`, failing (never skipping) when GROMACS is missing or fails.
fn gmx(dir: &Path, args: &[&str]) {
    let out = Command::new("gmx")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "cannot run gmx ({e}): install GROMACS (`apt-get install gromacs`; scripts/test \
                 installs it) to test live frames over IMD"
            )
        });
    assert!(
        out.status.success(),
        "gmx {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A box of 176 SPC/E waters (1.8 nm) and a run input of `steps` MD steps writing positions to
/// `md.trr` every 5 steps; returns the structure file.
pub(crate) fn water_box(dir: &Path, steps: i64) -> PathBuf {
    gmx(
        dir,
        &[
            "solvate",
            "-cs",
            "spc216.gro",
            "-box",
            "1.8",
            "1.8",
            "1.8",
            "-o",
            "water.gro",
        ],
    );
    let waters = std::fs::read_to_string(dir.join("water.gro"))
        .unwrap()
        .lines()
        .nth(1)
        .unwrap()
        .trim()
        .parse::<usize>()
        .unwrap()
        / 3;
    std::fs::write(
        dir.join("topol.top"),
        format!(
            "#include \"oplsaa.ff/forcefield.itp\"\n#include \"oplsaa.ff/spce.itp\"\n\
             [ system ]\nwater\n[ molecules ]\nSOL {waters}\n"
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("md.mdp"),
        format!(
            "integrator = md\ndt = {DT_PS}\nnsteps = {steps}\nnstxout = 5\nnstcalcenergy = 5\n\
             nstenergy = 5\ncutoff-scheme = Verlet\nrcoulomb = 0.8\nrvdw = 0.8\n\
             coulombtype = PME\ntcoupl = v-rescale\ntc-grps = System\ntau-t = 0.1\n\
             ref-t = 300\nIMD-group = System\n"
        ),
    )
    .unwrap();
    gmx(
        dir,
        &[
            "grompp",
            "-f",
            "md.mdp",
            "-c",
            "water.gro",
            "-p",
            "topol.top",
            "-o",
            "md.tpr",
        ],
    );
    dir.join("water.gro")
}

/// A port nothing listens on (free a moment ago).
pub(crate) fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// `gmx mdrun` on `md.tpr` in `dir`, waiting for an IMD client on `port`; killed when dropped.
pub(crate) struct Mdrun(pub(crate) Child);

impl Mdrun {
    pub(crate) fn start(dir: &Path, port: u16) -> Mdrun {
        // Its messages (unbuffered, unlike md.log) go to mdrun.err, for assert_running.
        let messages = std::fs::File::create(dir.join("mdrun.err")).unwrap();
        let child = Command::new("gmx")
            .args([
                "mdrun", "-s", "md.tpr", "-deffnm", "md", "-nt", "1", "-imdwait",
            ])
            .args(["-imdport", &port.to_string()])
            .current_dir(dir)
            .stdout(Stdio::null())
            .stderr(messages)
            .spawn()
            .expect("cannot start gmx mdrun");
        Mdrun(child)
    }

    /// Panics with the exit status and the end of its messages (`mdrun.err` in `dir`, the
    /// run's folder) when the run has stopped: `what` says why it should not have.
    pub(crate) fn assert_running(&mut self, dir: &Path, what: &str) {
        if let Some(status) = self.0.try_wait().unwrap() {
            let log = std::fs::read_to_string(dir.join("mdrun.err")).unwrap_or_default();
            let tail: Vec<&str> = log.lines().rev().take(12).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            panic!(
                "{what}: gmx mdrun ended ({status}); its last messages:\n{}",
                tail.join("\n")
            );
        }
    }

    /// Waits for the run to end by itself.
    fn wait(mut self) {
        let status = self.0.wait().unwrap();
        assert!(status.success(), "gmx mdrun failed: {status}");
    }
}

impl Drop for Mdrun {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

pub(crate) fn options(port: u16) -> LiveOptions {
    let mut options = LiveOptions::new(&format!("127.0.0.1:{port}"));
    options.connect_timeout = Duration::from_secs(60);
    options.frame_timeout = Duration::from_secs(60);
    options.timestep_ps = Some(DT_PS);
    options
}

#[test]
fn imd_frames_equal_the_positions_gromacs_writes() {
    let dir = tempfile::tempdir().unwrap();
    let top = water_box(dir.path(), 50);
    let port = free_port();
    let engine = Mdrun::start(dir.path(), port);
    let live = io::open_live(&top, &options(port)).unwrap();
    assert!(live.is_live());
    let mut received = Vec::new();
    let end = loop {
        match live.read_frame(received.len()) {
            Ok(frame) => received.push(frame),
            Err(end) => break end,
        }
    };
    engine.wait();
    assert_eq!(received.len(), 51, "steps 0 to 50, one frame each");
    assert!(
        matches!(end, IoError::LiveEnded { frames: 51, .. }),
        "{end}"
    );
    // The frames received stay readable after the end.
    assert_eq!(live.read_frame(3).unwrap().positions, received[3].positions);

    let written = io::open(&top, Some(&dir.path().join("md.trr"))).unwrap();
    assert_eq!(written.len(), 11, "md.trr holds steps 0, 5, ..., 50");
    for k in 0..written.len() {
        let expected = written.read_frame(k).unwrap();
        let got = &received[5 * k];
        // GROMACS sends molecules whole, so an atom may be a box vector away from where the
        // trajectory file has it: compare positions modulo the (rectangular) box.
        let cell = expected.cell.expect("md.trr has a box");
        let live_cell = got.cell.expect("live frames carry the structure's box");
        for (a, b) in live_cell.iter().zip(&cell) {
            assert!(
                (*a - *b).abs().max_element() < 1e-4,
                "{live_cell:?} != {cell:?}"
            );
        }
        let edges = glam::Vec3::new(cell[0].x, cell[1].y, cell[2].z);
        let worst = expected
            .positions
            .iter()
            .zip(&got.positions)
            .map(|(a, b)| {
                let d = *a - *b;
                (d - (d / edges).round() * edges).abs().max_element()
            })
            .fold(0.0f32, f32::max);
        assert!(
            worst < 1e-4,
            "step {}: IMD and md.trr differ by {worst} Å",
            5 * k
        );
        let time = expected.time_ps.unwrap();
        let live_time = got
            .time_ps
            .expect("a time from the step and --imd-timestep");
        assert!(
            (live_time - time).abs() < 1e-6,
            "step {}: IMD time {live_time} ps, md.trr {time} ps",
            5 * k
        );
    }
}

#[test]
fn surface_measures_a_running_simulation_until_it_ends() {
    let dir = tempfile::tempdir().unwrap();
    let top = water_box(dir.path(), 20);
    let port = free_port();
    let engine = Mdrun::start(dir.path(), port);
    let address = format!("127.0.0.1:{port}");
    let top = top.to_str().unwrap();
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            top,
            "--imd",
            &address,
            "--imd-timestep",
            "0.002",
            "--backend",
            "cpu",
            "--periodic",
            "--stats",
            "live.csv",
        ],
    );
    engine.wait();
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains(&format!(
            "imd://{address}: the simulation stream ended after 21 frames"
        )),
        "{}",
        run.stderr
    );
    let live = Csv::read(&dir.path().join("live.csv"));
    assert_eq!(live.col("area_A2").len(), 21);

    // The same steps from the trajectory GROMACS wrote give the same areas (periodic surfaces
    // do not depend on which image of an atom a file holds).
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            top,
            "md.trr",
            "--backend",
            "cpu",
            "--periodic",
            "--stats",
            "file.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let file = Csv::read(&dir.path().join("file.csv"));
    let (live_area, file_area) = (live.col("area_A2"), file.col("area_A2"));
    assert_eq!(file_area.len(), 5);
    for (k, area) in file_area.iter().enumerate() {
        let got = live_area[5 * k];
        assert!(
            ((got - area) / area).abs() < 1e-4,
            "step {}: {got} Å² live, {area} Å² from md.trr",
            5 * k
        );
    }
    // Step 10 is frame 10 of the stream and frame 2 of md.trr (which stores times as floats).
    assert!((live.col("time_ps")[10] - file.col("time_ps")[2]).abs() < 1e-6);
}

#[test]
fn a_killed_engine_keeps_the_frames_received() {
    let dir = tempfile::tempdir().unwrap();
    let top = water_box(dir.path(), 1_000_000);
    let port = free_port();
    let mut engine = Mdrun::start(dir.path(), port);
    let live = io::open_live(&top, &options(port)).unwrap();
    for index in 0..10 {
        live.read_frame(index).unwrap();
    }
    engine.0.kill().unwrap();
    engine.0.wait().unwrap();
    let mut index = 10;
    let end = loop {
        match live.read_frame(index) {
            Ok(_) => index += 1,
            Err(end) => break end,
        }
    };
    match &end {
        IoError::LiveEnded { frames, .. } => assert_eq!(*frames, index),
        other => panic!("expected the end of the stream, got: {other}"),
    }
    assert_eq!(end.to_string().lines().count(), 1);
    // The first frames are still held (the ring keeps the last 256).
    if index <= 256 {
        live.read_frame(0).unwrap();
    } else {
        let gone = live.read_frame(0).unwrap_err().to_string();
        assert!(gone.contains("no longer held"), "{gone}");
    }
}

#[test]
fn no_engine_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let top = crate::cli_common::data("adk_open.pdb");
    let port = free_port();
    let address = format!("127.0.0.1:{port}");
    let run = mdsurf(
        dir.path(),
        &["surface", &top, "--imd", &address, "--imd-wait", "1"],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(
        run.stderr.trim(),
        format!(
            "error: imd://{address}: cannot read: cannot connect: nothing listens at {address} (waited 1 s)"
        )
    );
    let run = mdsurf(dir.path(), &["surface", &top, &top, "--imd", &address]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(
        run.last_line().contains("give no trajectory file"),
        "{}",
        run.stderr
    );
}

#[test]
fn the_viewer_follows_the_newest_frame_and_keeps_them_when_the_engine_dies() {
    let LiveViewer {
        dir: _dir,
        mut engine,
        port,
        source,
        mut core,
    } = LiveViewer::start();
    assert!(source.is_live());
    // The timeline grows as frames arrive and the window shows the newest one.
    let start = std::time::Instant::now();
    assert_eq!(
        core.timeline.current + 1,
        core.timeline.len,
        "opens on the newest frame"
    );
    let opened_with = core.timeline.len;
    while core.timeline.len < opened_with + 20 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no frames arrive"
        );
        core.follow_live();
        core.poll();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(core.timeline.current, core.timeline.len - 1);
    assert!(core.wait_idle(Duration::from_secs(120)));
    let shown = core
        .shown
        .as_ref()
        .expect("a frame on screen")
        .computed
        .frame;
    assert!(
        shown + 1 >= opened_with + 20,
        "showing frame {shown}, not the newest"
    );
    // Scrubbing back stops following: new frames extend the timeline, the view stays.
    core.timeline.current = 5;
    core.request_current();
    let len = core.timeline.len;
    while core.timeline.len < len + 5 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no more frames arrive"
        );
        core.follow_live();
        core.poll();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(core.timeline.current, 5);
    // A killed engine: the frames received stay, readable, and the window keeps its state.
    engine.0.kill().unwrap();
    engine.0.wait().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    core.follow_live();
    core.follow_live();
    let received = core.timeline.len;
    assert_eq!(
        core.status,
        format!(
            "imd://127.0.0.1:{port}: the simulation stream ended after {received} frames (the simulation closed the connection)"
        )
    );
    assert!(core.wait_idle(Duration::from_secs(120)));
    assert!(core.error.is_none(), "{:?}", core.error);
    let last = source.read_frame(received - 1).unwrap();
    assert_eq!(last.positions.len(), source.topology().len());
    assert!(core.shown.is_some());
}

#[test]
fn render_makes_a_movie_of_a_run_until_it_ends() {
    let dir = tempfile::tempdir().unwrap();
    let top = water_box(dir.path(), 12);
    let port = free_port();
    let engine = Mdrun::start(dir.path(), port);
    let address = format!("127.0.0.1:{port}");
    let top = top.to_str().unwrap();
    let run = mdsurf(
        dir.path(),
        &[
            "render", top, "--imd", &address, "--size", "160x120", "-o", "live.mp4",
        ],
    );
    engine.wait();
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("the simulation stream ended after 13 frames"),
        "{}",
        run.stderr
    );
    let frames = crate::cli_common::probe_video(&dir.path().join("live.mp4"), "nb_read_frames");
    assert_eq!(frames, "13");
    // One picture of a stream is refused before connecting.
    let run = mdsurf(
        dir.path(),
        &["render", top, "--imd", &address, "-o", "one.png"],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(run.last_line().contains("--frames :N"), "{}", run.stderr);
}

/// The viewer's core on a running GROMACS simulation (a water box of a million steps, a 2 Å
/// grid), as the window opens it with `--imd`.
pub(crate) struct LiveViewer {
    /// The run's files; removed when dropped.
    pub(crate) dir: tempfile::TempDir,
    /// The engine; killed when dropped.
    pub(crate) engine: Mdrun,
    /// The IMD port the engine listens on.
    pub(crate) port: u16,
    /// The frames received.
    pub(crate) source: std::sync::Arc<dyn mdsurf::app::source::FrameSource>,
    /// The app core showing them.
    pub(crate) core: mdsurf::app::AppCore,
}

impl LiveViewer {
    pub(crate) fn start() -> LiveViewer {
        use mdsurf::app::source::open_live_with;
        use mdsurf::app::worker::Worker;
        use mdsurf::surface::CpuEngine;

        let dir = tempfile::tempdir().unwrap();
        let top = water_box(dir.path(), 1_000_000);
        let port = free_port();
        let engine = Mdrun::start(dir.path(), port);
        let live = io::LiveSource::Imd(options(port));
        let source = open_live_with(&top, &live, &Default::default()).unwrap();
        let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
        let mut core = mdsurf::app::AppCore::new(worker);
        core.base.spacing = 2.0;
        core.set_source(source.clone());
        LiveViewer {
            dir,
            engine,
            port,
            source,
            core,
        }
    }
}
