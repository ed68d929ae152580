//! One frame path: the same state file (two surface representations, one of them a `within`
//! selection that changes with the frame, plus atoms) goes through the viewer's compute worker,
//! `mdsurf surface` and `mdsurf render`, and every one of them reports the same area and volume
//! per representation and frame (the same digits in the CSVs; the worker's numbers printed as
//! the CSV prints them), on the CPU engine.

use crate::cli_common::{Csv, data, mdsurf};

use std::sync::Arc;
use std::time::Duration;

use mdsurf::app::source::FrameSource;
use mdsurf::app::worker::{RepRequest, Reply, Request, Worker};
use mdsurf::io;
use mdsurf::model::RadiusOverrides;
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;
use mdsurf::surface::CpuEngine;

/// Frames of adk_dims.dcd the test runs.
const FRAMES: usize = 3;

fn state() -> StateFile {
    StateFile::new(vec![
        Representation {
            spacing: 0.8,
            ..Representation::new("protein", "protein", RepStyle::Surface)
        },
        Representation::new("pocket", "within 6 of resid 10", RepStyle::Surface),
        Representation::new("atoms", "resid 10", RepStyle::BallAndStick),
    ])
}

/// `(frame, rep, area, volume)` rows of a stats CSV, as the CSV prints them.
fn rows(csv: &Csv) -> Vec<[String; 4]> {
    let (f, r, a, v) = (
        csv.text_col("frame"),
        csv.text_col("rep"),
        csv.text_col("area_A2"),
        csv.text_col("volume_A3"),
    );
    (0..f.len())
        .map(|i| [f[i].clone(), r[i].clone(), a[i].clone(), v[i].clone()])
        .collect()
}

#[test]
fn worker_surface_and_render_report_the_same_areas_and_volumes() {
    let dir = tempfile::tempdir().unwrap();
    let state_path = dir.path().join("view.toml");
    std::fs::write(&state_path, state().to_toml()).unwrap();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let frames = format!("0:{FRAMES}");
    let common = [
        top.as_str(),
        traj.as_str(),
        "--state",
        "view.toml",
        "--frames",
        &frames,
        "--backend",
        "cpu",
        "--no-whole",
    ];

    let surface = mdsurf(
        dir.path(),
        &[&["surface"], &common[..], &["--stats", "surface.csv", "-q"]].concat(),
    );
    assert_eq!(surface.code, 0, "{}", surface.stderr);
    let render = mdsurf(
        dir.path(),
        &[
            &["render"],
            &common[..],
            &[
                "--stats",
                "render.csv",
                "--size",
                "64x48",
                "-o",
                "img_{frame}.png",
            ],
        ]
        .concat(),
    );
    assert_eq!(render.code, 0, "{}", render.stderr);
    let from_surface = rows(&Csv::read(&dir.path().join("surface.csv")));
    let from_render = rows(&Csv::read(&dir.path().join("render.csv")));
    assert_eq!(from_surface.len(), 2 * FRAMES, "{from_surface:?}");
    assert_eq!(from_surface, from_render);

    // The viewer's worker on the same file and representations.
    let source: Arc<dyn FrameSource> = Arc::new(
        io::open(
            std::path::Path::new(&top),
            Some(std::path::Path::new(&traj)),
        )
        .unwrap(),
    );
    let reps: Vec<RepRequest> = state()
        .representations
        .into_iter()
        .enumerate()
        .map(|(i, rep)| RepRequest { id: i as u64, rep })
        .collect();
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut from_worker = Vec::new();
    for frame in 0..FRAMES {
        worker.submit(Request {
            generation: frame as u64,
            frame,
            source: source.clone(),
            reps: reps.clone(),
            radius_overrides: RadiusOverrides::default(),
        });
        let computed = match worker.recv_timeout(Duration::from_secs(120)) {
            Some(Reply::Done(c)) => c,
            other => panic!("frame {frame}: {other:?}"),
        };
        assert_eq!(computed.layers.len(), 3, "atoms are computed too");
        for l in computed.surfaces() {
            from_worker.push([
                frame.to_string(),
                l.rep.name.clone(),
                format!("{:.4}", l.output.area),
                format!("{:.4}", l.output.volume),
            ]);
        }
    }
    assert_eq!(from_worker, from_surface);

    // The `within` surface follows the frame: not every frame gives the same area.
    let pocket: Vec<&String> = from_surface
        .iter()
        .filter(|r| r[1] == "pocket")
        .map(|r| &r[2])
        .collect();
    assert!(pocket.iter().any(|a| *a != pocket[0]), "{pocket:?}");
}
