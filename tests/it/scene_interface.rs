//! The window's Interface section (issue 32: the buried area in the window's readouts and
//! plot) on the HIV protease dimer 1hpv: switched on, it measures each frame shown in the
//! background, as `mdsurf surface --interface` does (the library's [`Interface`] on the
//! selected representation); with the probe switch, the probe's SES; a selection that picks
//! nothing is one error line and the window stays.

use std::sync::Arc;
use std::time::Duration;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::Vec3;
use mdsurf::app::interface_panel::{self, InterfaceDraft, WATER_PROBE, interface_ui};
use mdsurf::app::source::MemorySource;
use mdsurf::app::timeline::TimelineCmd;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Command};
use mdsurf::measure::CONTACT_THRESHOLD;
use mdsurf::model::{Frame, RadiusOverrides};
use mdsurf::scene::interface::Interface;
use mdsurf::surface::CpuEngine;

use crate::app_panels::WAIT;
use crate::data_support::data;

const SIDES: [&str; 2] = ["protein and chain A", "protein and chain B"];

/// 1hpv as it is (frame 0) and with chain B moved 40 Å away (frame 1).
fn apart_source() -> MemorySource {
    let traj = mdsurf::io::open(&data("1hpv.pdb"), None).expect("open 1hpv");
    let first = traj.read_frame(0).expect("frame 0");
    let topology = traj.topology().clone();
    let mut moved: Frame = first.clone();
    for (k, p) in moved.positions.iter_mut().enumerate() {
        if &topology.chains[k] == "B" {
            *p += Vec3::new(40.0, 0.0, 0.0);
        }
    }
    MemorySource {
        topology,
        frames: vec![first, moved],
        name: "1hpv".into(),
    }
}

type State = (AppCore, InterfaceDraft);

/// Waits until the frame shown is measured (or failed), then shows it.
fn measured(h: &mut Harness<'_, State>) {
    for _ in 0..4 {
        let (core, draft) = h.state_mut();
        assert!(
            draft.wait(core, Duration::from_secs(300)),
            "measured in time"
        );
        // Takes the result; starts the shown frame when another frame was being measured.
        h.step();
        if !h.state().1.busy() {
            break;
        }
    }
    h.run();
}

#[test]
fn interface_panel_measures_each_frame_shown() {
    let source = apart_source();
    let frame0 = source.frames[0].clone();
    let topology = source.topology.clone();
    let mut core = AppCore::new(Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {})));
    core.set_source(Arc::new(source));
    assert!(core.wait_idle(WAIT));
    let base = core.reps[core.selected].clone();
    let mut draft = InterfaceDraft::default();
    draft.selection_a = SIDES[0].into();
    draft.selection_b = SIDES[1].into();
    let mut h = Harness::builder().with_size([500.0, 700.0]).build_ui_state(
        |ui, (core, draft): &mut State| interface_ui(ui, core, draft),
        (core, draft),
    );
    h.run();
    assert!(
        h.query_by_label_contains("frame 0: buried").is_none(),
        "off at first"
    );
    h.get_by_label("Measure the buried area").click();
    h.step();
    measured(&mut h);
    // The library's interface on the selected representation, as `surface --interface`.
    let mut library =
        Interface::new(&topology, SIDES, &base, &RadiusOverrides::default(), None).expect("sides");
    let want = library
        .measure(&topology, &frame0, CONTACT_THRESHOLD)
        .expect("interface");
    let row = h.state().1.rows[&0].clone();
    assert_eq!(row.buried, want.result.buried);
    assert!(row.buried > 800.0, "{}", row.buried);
    assert!(row.contacts[0].len() > 10, "{:?}", row.contacts);
    // Each contact with the area it loses, as the library's contact residues.
    let lost: Vec<f64> = want.contacts.iter().map(|c| c.buried).collect();
    let shown: Vec<f64> = row.contacts.iter().flatten().map(|c| c.1).collect();
    assert_eq!(shown, lost);
    let line = interface_panel::contacts_line("A", &row.contacts[0]);
    assert!(h.query_by_label_contains(&line).is_some(), "{line}");
    let label = format!("frame 0: buried {:.1} Å²", row.buried);
    assert!(h.query_by_label_contains(&label).is_some(), "{label}");
    // Frame 1, chain B far away: nothing buried; the plot has both frames.
    h.state_mut()
        .0
        .apply(Command::Timeline(TimelineCmd::Step(1)));
    assert!(h.state_mut().0.wait_idle(WAIT));
    h.step();
    measured(&mut h);
    let rows = &h.state().1.rows;
    assert_eq!(rows.keys().copied().collect::<Vec<_>>(), [0, 1]);
    assert!(rows[&1].buried.abs() < 1e-6, "{}", rows[&1].buried);
    assert!(
        h.query_by_label_contains("frame 1: buried 0.0 Å²")
            .is_some()
    );
    // Export: the measured frames as `surface --interface-csv` writes them; frame 0 is the
    // command line's row on the same file.
    assert!(h.query_by_label("Export CSV…").is_some());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("window.csv");
    assert_eq!(h.state().1.write_csv(&path).expect("written"), 2);
    let text = std::fs::read_to_string(&path).expect("read back");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert_eq!(
        lines[0],
        "frame,time_ps,area_a_A2,area_b_A2,area_ab_A2,buried_A2,contacts_a,contacts_b"
    );
    assert!(lines[2].starts_with("1,"), "{}", lines[2]);
    let pdb = data("1hpv.pdb").display().to_string();
    let run = crate::cli_common::mdsurf(
        dir.path(),
        &[
            "surface",
            &pdb,
            "--backend",
            "cpu",
            "-q",
            "--select",
            "protein",
            "--interface",
            SIDES[0],
            SIDES[1],
            "--interface-csv",
            "cli.csv",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let cli = std::fs::read_to_string(dir.path().join("cli.csv")).expect("the CLI's table");
    assert_eq!(
        cli.lines().nth(1),
        Some(lines[1]),
        "the window's frame 0 is the CLI's"
    );
    // The probe's SES: the table starts again; MSMS buries 1,193.0 Å² on frame 0.
    h.get_by_label(&format!("on the {WATER_PROBE} Å probe's surface (as MSMS)"))
        .click();
    h.step();
    h.state_mut()
        .0
        .apply(Command::Timeline(TimelineCmd::Step(-1)));
    assert!(h.state_mut().0.wait_idle(WAIT));
    h.step();
    measured(&mut h);
    let rows = &h.state().1.rows;
    assert!(
        (rows[&0].buried / 1193.0 - 1.0).abs() < 0.05,
        "{}",
        rows[&0].buried
    );
    assert!(
        rows.get(&1).is_none_or(|r| r.buried.abs() < 1e-6),
        "{rows:?}"
    );
    // A side that picks nothing: one line naming it, the rows of before gone, no panic.
    h.state_mut().1.selection_b = "resname XYZ".into();
    h.step();
    measured(&mut h);
    let error = h.state().1.error.clone().expect("an error");
    assert!(
        error.contains("selection 'resname XYZ' matches no atom"),
        "{error}"
    );
    assert!(!error.contains('\n'), "{error}");
    assert!(h.query_by_label_contains("matches no atom").is_some());
    assert!(h.state().1.rows.is_empty());
}
