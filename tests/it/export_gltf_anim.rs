//! Animated glTF (`mdsurf surface TOP TRAJ --frames A:B -o movie.glb`), read back with the `gltf`
//! crate (an independent reader that validates the document): one node per frame whose mesh has
//! the triangle count of the stats CSV, and one STEP animation whose key times follow the
//! trajectory's frame times at `--fps`, showing exactly one frame at any time.

use std::fs;

use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};

use crate::cli_common::{Csv, data, mdsurf};

/// Scale of a STEP track at time `t` (s): the value of the last key at or before `t`, the first
/// key's before it.
fn step_at(keys: &[f32], values: &[[f32; 3]], t: f32) -> f32 {
    let k = keys.iter().rposition(|&k| k <= t).unwrap_or(0);
    values[k][0]
}

#[test]
fn movie_glb_holds_every_frame_and_a_step_animation_over_their_times() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let run = mdsurf(
        d,
        &[
            "surface",
            &top,
            &traj,
            "--frames",
            "3:15:2",
            "--spacing",
            "2",
            "--backend",
            "cpu",
            "--fps",
            "10",
            "-q",
            "--stats",
            "s.csv",
            "-o",
            "movie.glb",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    // One file, no per-frame files.
    let names: Vec<String> = fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");

    let csv = Csv::read(&d.join("s.csv"));
    let frames = csv.col("frame");
    assert_eq!(frames, [3.0, 5.0, 7.0, 9.0, 11.0, 13.0]);
    let triangles = csv.col("triangles");
    let times = csv.col("time_ps");

    let (doc, buffers, _) = gltf::import(d.join("movie.glb")).expect("a valid glTF file");
    let scene = doc.default_scene().expect("a default scene");
    let nodes: Vec<gltf::Node> = scene.nodes().collect();
    assert_eq!(nodes.len(), 6);
    for (k, node) in nodes.iter().enumerate() {
        let mesh = node.mesh().expect("every frame has a mesh");
        let prim = mesh.primitives().next().unwrap();
        let tris = prim.indices().unwrap().count() / 3;
        assert_eq!(tris as f64, triangles[k], "frame {}", frames[k]);
        assert!(
            node.name()
                .unwrap()
                .starts_with(&format!("frame {} ", frames[k])),
            "{:?}",
            node.name()
        );
        let positions = prim.get(&gltf::Semantic::Positions).unwrap();
        assert!(positions.min().is_some() && positions.max().is_some());
        // Without the animation only the first frame shows.
        let scale = node.transform().decomposed().2;
        assert_eq!(scale, if k == 0 { [1.0; 3] } else { [0.0; 3] }, "node {k}");
    }

    let anims: Vec<gltf::Animation> = doc.animations().collect();
    assert_eq!(anims.len(), 1);
    let anim = &anims[0];
    let mut tracks = vec![None; nodes.len()];
    for channel in anim.channels() {
        assert_eq!(channel.target().property(), Property::Scale);
        assert_eq!(channel.sampler().interpolation(), Interpolation::Step);
        let reader = channel.reader(|b| Some(&buffers[b.index()]));
        let keys: Vec<f32> = reader.read_inputs().unwrap().collect();
        let Some(ReadOutputs::Scales(values)) = reader.read_outputs() else {
            panic!("scale outputs expected");
        };
        let values: Vec<[f32; 3]> = values.collect();
        let k = nodes
            .iter()
            .position(|n| n.index() == channel.target().node().index())
            .unwrap();
        tracks[k] = Some((keys, values));
    }
    let tracks: Vec<(Vec<f32>, Vec<[f32; 3]>)> = tracks.into_iter().map(Option::unwrap).collect();

    // Key times: the frames' simulation times, one selected step (2 frames of adk_dims.dcd,
    // whatever its ps) per 1/10 s.
    let dt = times[1] - times[0];
    assert!(dt > 0.0, "{times:?}");
    for (k, (keys, values)) in tracks.iter().enumerate() {
        let shown_at = keys[values.iter().position(|v| v[0] == 1.0).unwrap()];
        let expected = (times[k] - times[0]) / dt / 10.0;
        assert!(
            (shown_at as f64 - expected).abs() < 1e-4,
            "frame {k}: key {shown_at} s, expected {expected} s"
        );
    }
    // At every moment of the animation (mid-way between keys) exactly one frame is visible.
    let end = tracks
        .iter()
        .flat_map(|t| t.0.iter())
        .fold(0f32, |a, &b| a.max(b));
    assert!(
        (end - 0.6).abs() < 1e-4,
        "6 frames at 10 fps last 0.6 s, got {end}"
    );
    for step in 0..6 {
        let t = (step as f32 + 0.5) / 10.0;
        let visible: Vec<usize> = tracks
            .iter()
            .enumerate()
            .filter(|(_, (keys, values))| step_at(keys, values, t) == 1.0)
            .map(|(k, _)| k)
            .collect();
        assert_eq!(visible, [step], "at {t} s");
    }
}

#[test]
fn a_frame_pattern_glb_stays_one_static_file_per_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let run = mdsurf(
        d,
        &[
            "surface",
            &top,
            &traj,
            "--frames",
            "0:2",
            "--spacing",
            "2",
            "--backend",
            "cpu",
            "-q",
            "-o",
            "f_{frame}.glb",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    for f in 0..2 {
        let (doc, _, _) = gltf::import(d.join(format!("f_{f}.glb"))).unwrap();
        assert_eq!(doc.nodes().count(), 1);
        assert_eq!(doc.animations().count(), 0);
    }
    // An animation cannot be chunked: one line says why.
    let bad = mdsurf(
        d,
        &[
            "surface",
            &top,
            &traj,
            "--frames",
            "0:4",
            "--backend",
            "cpu",
            "--chunk",
            "0/2",
            "-o",
            "movie.glb",
        ],
    );
    assert_eq!(bad.code, 2);
    assert!(bad.last_line().contains("animated .glb"), "{}", bad.stderr);
    assert_eq!(bad.stderr.trim().lines().count(), 1, "{}", bad.stderr);
}
