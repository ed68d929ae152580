//! A membrane opens in side view (issue 30 section 3): YiiP in its membrane (normal along z)
//! opens with z up on screen and the view along the membrane; a protein in water keeps the
//! usual view; a saved view's direction is kept.

use std::sync::Arc;
use std::time::Duration;

use glam::Vec3;
use mdsurf::app::source::{FrameSource, open_files};
use mdsurf::app::state::{AppCore, Command};
use mdsurf::app::worker::Worker;
use mdsurf::surface::CpuEngine;

use crate::data_support::data;

fn opened(top: &str, traj: Option<&str>) -> AppCore {
    let source: Arc<dyn FrameSource> =
        open_files(&data(top), traj.map(data).as_deref()).expect("open");
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.base.spacing = 3.0;
    core.set_source(source);
    assert!(core.wait_idle(Duration::from_secs(300)), "timed out");
    assert!(core.error.is_none(), "{:?}", core.error);
    core
}

#[test]
fn a_membrane_opens_in_side_view() {
    let mut core = opened("YiiP_lipids.gro.gz", Some("YiiP_lipids.xtc"));
    let cam = core.camera;
    assert!(cam.up().dot(Vec3::Z).abs() > 0.95, "up {}", cam.up());
    assert!(cam.back().dot(Vec3::Z).abs() < 0.2, "back {}", cam.back());
    // Reset view comes back to the side view after the user turned away.
    core.apply(Command::Orbit(0.0, 1.2));
    assert!(core.camera.back().dot(Vec3::Z).abs() > 0.5);
    core.apply(Command::ResetCamera);
    assert!(core.camera.up().dot(Vec3::Z).abs() > 0.95);
}

#[test]
fn a_protein_in_water_keeps_the_usual_view() {
    let core = opened("adk_oplsaa.gro", None);
    assert_eq!(core.camera.vertical, Vec3::Y);
    assert!(core.camera.up().dot(Vec3::Y) > 0.99);
}
