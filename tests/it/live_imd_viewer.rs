//! Pausing, resuming and detaching from a running GROMACS simulation (issue 35) from the
//! viewer: the console's `imd pause`, `imd resume` and `imd detach`, and the Simulation section's
//! buttons (driven through egui_kittest), which send the same commands.

use std::time::{Duration, Instant};

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use mdsurf::app::AppCore;
use mdsurf::app::console;
use mdsurf::app::simulation_panel::simulation_ui;

use crate::live_imd::LiveViewer;

/// Waits until `more` frames beyond those the core has now have arrived (at most two minutes
/// after `start`).
fn grow(core: &mut AppCore, more: usize, start: Instant) {
    let from = core.timeline.len;
    while core.timeline.len < from + more {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no frames arrive"
        );
        core.follow_live();
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The console's `imd pause`, `imd resume` and `imd detach` (issue 35): a paused GROMACS run
/// sends no more frames until it is resumed; after a detach the frames received stay, the status
/// says so, and the simulation goes on without us.
#[test]
fn the_console_pauses_resumes_and_detaches_from_a_running_simulation() {
    let LiveViewer {
        dir,
        mut engine,
        source,
        mut core,
        ..
    } = LiveViewer::start();
    let start = Instant::now();
    // Runs a console line against the core, as the window's console does.
    let run = |core: &mut AppCore, line: &str| {
        let cmd = console::parse(line).unwrap().expect("a command");
        let outcome = cmd.resolve(core).map_err(|e| e.to_string())?;
        for c in outcome.commands {
            core.apply(c);
        }
        match core.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    };
    let grow = |core: &mut AppCore, more: usize| grow(core, more, start);
    grow(&mut core, 5);
    assert!(
        run(&mut core, "imd resume").is_err(),
        "resumed a running simulation"
    );
    run(&mut core, "imd pause").unwrap();
    assert_eq!(core.status, "simulation paused");
    // The frames already on their way land; then nothing comes while paused.
    std::thread::sleep(Duration::from_millis(500));
    core.follow_live();
    let paused_at = core.timeline.len;
    std::thread::sleep(Duration::from_millis(1500));
    core.follow_live();
    assert!(
        core.timeline.len <= paused_at + 1,
        "frames kept coming while paused: {paused_at} -> {}",
        core.timeline.len
    );
    run(&mut core, "imd resume").unwrap();
    assert_eq!(core.status, "simulation resumed");
    grow(&mut core, 5);
    // Detach: the frames stay, the status says why the stream ended, the engine goes on.
    run(&mut core, "imd detach").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    core.follow_live();
    core.follow_live();
    let received = core.timeline.len;
    assert!(
        core.status
            .contains(&format!("ended after {received} frames"))
            && core
                .status
                .contains("detached from the simulation (it goes on)"),
        "{}",
        core.status
    );
    assert!(
        run(&mut core, "imd pause").is_err(),
        "paused after a detach"
    );
    let last = source.read_frame(received - 1).unwrap();
    assert_eq!(last.positions.len(), source.topology().len());
    engine.assert_running(dir.path(), "the simulation stopped when we detached");
}

/// The Simulation section: shown for a running simulation, its Pause button pauses GROMACS (no
/// frames come), the button then reads Resume and resumes it, Detach leaves the simulation
/// running and the section goes away.
#[test]
fn the_simulation_buttons_pause_resume_and_detach() {
    let LiveViewer {
        dir,
        mut engine,
        mut core,
        ..
    } = LiveViewer::start();
    let start = Instant::now();
    grow(&mut core, 3, start);
    let mut harness = Harness::builder().with_size([400.0, 300.0]).build_ui_state(
        |ui, core: &mut AppCore| {
            for c in simulation_ui(ui, core) {
                core.apply(c);
            }
        },
        core,
    );
    harness.run();
    assert!(harness.query_by_label("Resume simulation").is_none());
    harness.get_by_label("Pause simulation").click();
    harness.run();
    assert_eq!(harness.state().status, "simulation paused");
    assert!(harness.state().live_paused);
    // The frames on their way land; then none come while paused.
    std::thread::sleep(Duration::from_millis(500));
    harness.state_mut().follow_live();
    let paused_at = harness.state().timeline.len;
    std::thread::sleep(Duration::from_millis(1500));
    harness.state_mut().follow_live();
    let after = harness.state().timeline.len;
    assert!(
        after <= paused_at + 1,
        "frames kept coming while paused: {paused_at} -> {after}"
    );
    harness.run();
    harness.get_by_label("Resume simulation").click();
    harness.run();
    assert_eq!(harness.state().status, "simulation resumed");
    grow(harness.state_mut(), 3, start);
    harness.run();
    harness.get_by_label("Detach").click();
    harness.run();
    assert!(
        harness.state().error.is_none(),
        "{:?}",
        harness.state().error
    );
    std::thread::sleep(Duration::from_millis(300));
    harness.state_mut().follow_live();
    harness.run();
    harness.run();
    assert!(
        harness.query_by_label("Detach").is_none(),
        "the section stays after a detach"
    );
    engine.assert_running(dir.path(), "the simulation stopped when we detached");
}
