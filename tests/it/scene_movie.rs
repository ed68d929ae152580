//! Camera scripts (`[movie]` in a state file): the images a script makes, the camera at each
//! segment's end equal to the segment's target, one-line errors naming the segment, and
//! `mdsurf render --state` writing one image per shot.

use crate::cli_common::{data, mdsurf};

use mdsurf::scene::movie::{MovieScript, Segment, ShotCamera, TurnAxis};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::state_file::StateFile;

const SCRIPT: &str = r#"
version = 1

[[representation]]
name = "protein"
selection = "protein"
style = "surface"

[movie]
fps = 4

[[movie.view]]
name = "top"
pitch_deg = 60.0
zoom = 2.0

[[movie.segment]]
kind = "play"
from = 0
to = 4
step = 2

[[movie.segment]]
kind = "turn"
degrees = 90.0
seconds = 1.0

[[movie.segment]]
kind = "fly"
view = "top"
seconds = 0.5
"#;

fn script() -> MovieScript {
    StateFile::parse(SCRIPT, "movie.toml")
        .expect("the script parses")
        .movie
        .expect("a [movie] section")
}

fn close(a: ShotCamera, b: ShotCamera) -> bool {
    (a.yaw_deg - b.yaw_deg).abs() < 1e-4
        && (a.pitch_deg - b.pitch_deg).abs() < 1e-4
        && (a.zoom - b.zoom).abs() < 1e-6
}

#[test]
fn three_segments_give_their_images_and_end_on_their_targets() {
    let shots = script().shots(0, 10, |_| Some(1.0)).unwrap();
    // Play 0, 2, 4 (3 images); turn 1 s at 4 fps (4); fly 0.5 s (2).
    assert_eq!(shots.len(), 9);
    let frames: Vec<usize> = shots.iter().map(|s| s.frame).collect();
    assert_eq!(frames, [0, 2, 4, 4, 4, 4, 4, 4, 4]);
    let start = ShotCamera {
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        zoom: 1.0,
    };
    assert_eq!(shots[2].camera, start, "playing does not move the camera");
    assert_eq!(
        shots[6].camera,
        ShotCamera {
            yaw_deg: 90.0,
            ..start
        },
        "the turn ends on its angle"
    );
    // Turning is linear: a quarter of the angle per image.
    assert!((shots[3].camera.yaw_deg - 22.5).abs() < 1e-4);
    // The fly goes the short way back to yaw 0 and ends on the view.
    let top = ShotCamera {
        yaw_deg: 0.0,
        pitch_deg: 60.0,
        zoom: 2.0,
    };
    assert!(close(shots[8].camera, top), "{:?}", shots[8].camera);
    assert!(shots[7].camera.pitch_deg > 0.0 && shots[7].camera.pitch_deg < 60.0);
}

#[test]
fn fades_and_tilts_reach_their_targets() {
    let script = MovieScript {
        fps: 10.0,
        views: Vec::new(),
        segments: vec![
            Segment::Fade {
                rep: "membrane".into(),
                to: 0.0,
                seconds: 0.3,
            },
            Segment::Turn {
                degrees: -30.0,
                axis: TurnAxis::Horizontal,
                seconds: 0.2,
            },
            Segment::Zoom {
                factor: 0.5,
                seconds: 0.4,
            },
            Segment::Hold { seconds: 0.1 },
        ],
    };
    let shots = script
        .shots(3, 5, |name| (name == "membrane").then_some(0.8))
        .unwrap();
    assert_eq!(shots.len(), 3 + 2 + 4 + 1);
    assert!(shots.iter().all(|s| s.frame == 3));
    let opacity = |i: usize| shots[i].opacity[0].1;
    assert!(opacity(0) < 0.8 && opacity(0) > 0.0);
    assert_eq!(opacity(2), 0.0, "the fade ends on its target");
    assert_eq!(shots[4].camera.pitch_deg, -30.0);
    assert_eq!(shots[8].camera.zoom, 0.5);
    assert_eq!(shots[9].camera, shots[8].camera, "a hold keeps the camera");
    assert_eq!(opacity(9), 0.0, "a fade lasts");
}

#[test]
fn bad_scripts_fail_in_one_line_naming_the_segment() {
    let mut bad = script();
    bad.segments.push(Segment::Fly {
        view: "side".into(),
        seconds: 1.0,
    });
    let e = bad.shots(0, 10, |_| Some(1.0)).unwrap_err().to_string();
    assert!(
        e.contains("segment 4") && e.contains("'side'") && e.contains("top"),
        "{e}"
    );
    let e = script().shots(0, 3, |_| Some(1.0)).unwrap_err().to_string();
    assert!(e.contains("segment 1") && e.contains("to = 4"), "{e}");
    let mut fps = script();
    fps.fps = 0.0;
    assert!(fps.shots(0, 10, |_| Some(1.0)).is_err());
    let fade = MovieScript {
        fps: 24.0,
        views: Vec::new(),
        segments: vec![Segment::Fade {
            rep: "ghost".into(),
            to: 0.5,
            seconds: 1.0,
        }],
    };
    let e = fade.shots(0, 1, |_| None).unwrap_err().to_string();
    assert!(e.contains("'ghost'") && !e.contains('\n'), "{e}");
    // Unknown keys are refused when the file is read.
    let typo = SCRIPT.replace("degrees = 90.0", "degree = 90.0");
    let e = StateFile::parse(&typo, "movie.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("movie.toml") && !e.contains('\n'), "{e}");
}

#[test]
fn a_state_file_keeps_its_script() {
    let mut state = StateFile::new(vec![Representation::new(
        "protein",
        "protein",
        RepStyle::Surface,
    )]);
    state.movie = Some(script());
    let back = StateFile::parse(&state.to_toml(), "s.toml").unwrap();
    assert_eq!(back, state);
}

#[test]
fn render_plays_the_script_one_image_per_shot() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("movie.toml"), SCRIPT).unwrap();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let run = mdsurf(
        dir.path(),
        &[
            "render",
            &top,
            &traj,
            "--state",
            "movie.toml",
            "--backend",
            "cpu",
            "--spacing",
            "2",
            "--size",
            "64x48",
            "-o",
            "shot_{image}.png",
            "-v",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let mut pngs: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".png"))
        .collect();
    pngs.sort();
    assert_eq!(pngs.len(), 9, "{pngs:?}");
    // The turn moves the camera: the image after it differs from the one before.
    let read = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
    assert_ne!(read("shot_00002.png"), read("shot_00006.png"));
    // The same frame and camera twice give the same image (a hold would).
    assert!(run.stderr.contains("frame 4"), "{}", run.stderr);
}
