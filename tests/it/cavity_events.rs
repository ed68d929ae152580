//! Cavities in their ids' colours and the Cavities panel's event log (issue 32): a system of
//! two hollow shells has two cavities whose walls are drawn each in the colour the panel gives
//! its id (checked on the wall mesh and on a rendered picture), and the log of the tracking
//! events, fed crafted cavities so that every kind of event happens, reads as expected.

use std::sync::Arc;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::{DVec3, Vec3};
use mdsurf::app::AppCore;
use mdsurf::app::cavity_panel::{EVENT_LOG_LINES, cavity_ui, id_colour};
use mdsurf::app::worker::Worker;
use mdsurf::measure::Cavity;
use mdsurf::model::{Frame, Topology};
use mdsurf::render::{Camera, GpuScene, RenderSettings, Renderer, render_to_rgba};
use mdsurf::scene::cavity_layer::{CavityLayer, cavity_rgb, with_cavity_ids};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{LayerResult, ParticleData, RepRequest, SceneBackend, SceneEngine, SceneFrame};
use mdsurf::surface::{CpuEngine, Mesh, SurfaceOutput};

/// Atoms per shell (about 1 Å apart on the larger one, closer on the smaller).
const SHELL_ATOMS: usize = 600;

/// Centres (Å) and radii (Å) of the two shells: the larger void on the left.
const SHELLS: [(Vec3, f32); 2] = [
    (Vec3::new(-9.0, 0.0, 0.0), 7.0),
    (Vec3::new(9.0, 0.0, 0.0), 5.5),
];

/// Two hollow shells of carbon atoms (radius 1.5 Å), ten atoms per residue.
fn two_shells() -> (Topology, Frame) {
    let positions: Vec<Vec3> = SHELLS
        .iter()
        .flat_map(|&(c, r)| crate::measure_cavities::shell(SHELL_ATOMS, r, c))
        .collect();
    let mut top = Topology::default();
    for a in 0..positions.len() {
        top.names.push("C");
        top.elements.push("C");
        top.radii.push(1.5);
        top.residue_names.push("LEU");
        top.residue_ids.push(a as i64 / 10 + 1);
        top.residue_index.push(a as u32 / 10);
        top.chains.push("A");
        top.b_factors.push(0.0);
    }
    let frame = Frame {
        index: 0,
        time_ps: None,
        positions,
        cell: None,
    };
    (top, frame)
}

/// The two shells' surface at 0.4 Å spacing with its cavities, drawn at `opacity`.
fn rep(opacity: f32) -> Representation {
    Representation {
        spacing: 0.4,
        cavities: true,
        opacity,
        ..Representation::new("shells", "all", RepStyle::Surface)
    }
}

/// The one layer of the two shells' frame, computed on the CPU.
fn shells_layer() -> Arc<LayerResult> {
    shells_layer_with(None)
}

/// The one layer of the two shells' frame, with the cavities of a probe of `probe` Å when
/// given, computed on the CPU.
fn shells_layer_with(probe: Option<f32>) -> Arc<LayerResult> {
    let (top, frame) = two_shells();
    let mut engine = SceneEngine::new(SceneBackend::Host(Box::new(CpuEngine::new())));
    let reps = [RepRequest {
        id: 1,
        rep: Representation {
            cavity_probe: probe,
            ..rep(1.0)
        },
    }];
    let computed = engine
        .frame(&top, 0, &Arc::new(frame), &reps)
        .expect("the shells' frame computes");
    computed.layers[0].clone()
}

/// The distinct vertex colours of `mesh`'s vertices in `range`.
fn colours_of(mesh: &Mesh, range: std::ops::Range<usize>) -> Vec<[f32; 3]> {
    let mut out: Vec<[f32; 3]> = Vec::new();
    for c in &mesh.colours[range] {
        if !out.contains(c) {
            out.push(*c);
        }
    }
    out
}

/// The panel's colour of a linear RGB vertex colour (egui's sRGB bytes of it).
fn as_panel_colour(c: [f32; 3]) -> egui::Color32 {
    egui::Color32::from(egui::Rgba::from_rgb(c[0], c[1], c[2]))
}

/// Each cavity's wall is in one colour, the panel's colour of its id; the two differ; handing
/// the layer other ids (as tracking does) recolours the walls to those ids' colours.
#[test]
fn each_cavity_wall_is_in_its_ids_panel_colour() {
    let layer = shells_layer();
    let found = layer.cavities.as_ref().expect("cavities found");
    assert_eq!(found.cavities.len(), 2, "one void per shell");
    assert_eq!(found.ids, [1, 2]);
    assert_eq!(found.wall_vertices.len(), 2);
    let walls = &found.mesh;
    assert_eq!(colours_of(walls, 0..walls.positions.len()).len(), 2);
    for (k, range) in found.wall_vertices.iter().enumerate() {
        assert!(!range.is_empty(), "cavity {k} has a wall");
        let colours = colours_of(walls, range.clone());
        assert_eq!(colours, [cavity_rgb(found.ids[k])], "cavity {k}");
        assert_eq!(as_panel_colour(colours[0]), id_colour(found.ids[k]));
        // The wall's vertices are those around this cavity's centroid.
        let n = range.len() as f64;
        let mean = walls.positions[range.clone()]
            .iter()
            .fold(DVec3::ZERO, |s, p| s + p.as_dvec3())
            / n;
        let centroid = found.cavities[k].centroid;
        assert!(mean.distance(centroid) < 0.5, "{mean} vs {centroid}");
    }
    assert_ne!(id_colour(1), id_colour(2));
    let mut tracked = layer.clone();
    with_cavity_ids(&mut tracked, &[5, 3]);
    let recoloured = tracked.cavities.as_ref().expect("cavities");
    assert_eq!(recoloured.ids, [5, 3]);
    for (k, id) in [5, 3].into_iter().enumerate() {
        let range = recoloured.wall_vertices[k].clone();
        assert_eq!(colours_of(&recoloured.mesh, range), [cavity_rgb(id)]);
    }
    assert_eq!(found.ids, [1, 2], "the engine's layer is left as it was");
}

/// With a cavity probe (`rep N cavities probe 1.4`) the layer holds the probe's cavities, the
/// ones the library finds over the same atoms with Bondi's carbon radius (1.70 Å), larger than
/// the Gaussian surface's voids, each wall in its id's colour around its cavity.
#[test]
fn a_cavity_probe_draws_the_probes_cavities() {
    let probe_layer = shells_layer_with(Some(1.4));
    let found = probe_layer.cavities.as_ref().expect("cavities found");
    let (_, frame) = two_shells();
    let radii = vec![1.70; frame.positions.len()];
    let atoms = mdsurf::surface::AtomSet {
        positions: &frame.positions,
        radii: &radii,
        colours: None,
    };
    let options = mdsurf::measure::ProbeOptions {
        min_volume: 1.0,
        ..Default::default()
    };
    let library = mdsurf::measure::probe_cavities(&atoms, &options).expect("probe cavities");
    assert_eq!(found.cavities, library);
    assert_eq!(found.cavities.len(), 2, "one void per shell");
    let gaussian = shells_layer();
    let voids = &gaussian.cavities.as_ref().expect("cavities").cavities;
    for (k, range) in found.wall_vertices.iter().enumerate() {
        assert!(found.cavities[k].volume > 2.0 * voids[k].volume, "{k}");
        assert_eq!(
            colours_of(&found.mesh, range.clone()),
            [cavity_rgb(found.ids[k])]
        );
        let n = range.len() as f64;
        let mean = found.mesh.positions[range.clone()]
            .iter()
            .fold(DVec3::ZERO, |s, p| s + p.as_dvec3())
            / n;
        let centroid = found.cavities[k].centroid;
        assert!(mean.distance(centroid) < 0.5, "{mean} vs {centroid}");
    }
    assert_eq!(
        found.lining[0].len(),
        SHELL_ATOMS / 10,
        "every residue of the shell"
    );
}

/// Hue (degrees) and saturation (0..1) of an sRGB pixel.
fn hue_saturation(r: f32, g: f32, b: f32) -> (f32, f32) {
    let (hi, lo) = (r.max(g).max(b), r.min(g).min(b));
    let d = hi - lo;
    if d <= 0.0 {
        return (0.0, 0.0);
    }
    let h = if hi == r {
        60.0 * ((g - b) / d).rem_euclid(6.0)
    } else if hi == g {
        60.0 * ((b - r) / d + 2.0)
    } else {
        60.0 * ((r - g) / d + 4.0)
    };
    (h, d / hi)
}

/// Pixels of `rgba` near `colour`: hue within 15 degrees of its hue, saturation over 0.3 (the
/// grey surface in front only lowers a wall's saturation; the background and the surface alone
/// are grey).
fn pixels_near(rgba: &[u8], colour: egui::Color32) -> usize {
    let [r, g, b] = [colour.r(), colour.g(), colour.b()].map(f32::from);
    let (want, _) = hue_saturation(r, g, b);
    rgba.chunks_exact(4)
        .filter(|p| {
            let [r, g, b] = [p[0], p[1], p[2]].map(f32::from);
            let (h, s) = hue_saturation(r, g, b);
            let dh = (h - want).abs();
            s > 0.3 && dh.min(360.0 - dh) < 15.0
        })
        .count()
}

/// Pixels near the colours of ids 1 and 2 in the left and right halves of the picture of
/// `layer` (the two shells) under its surface at opacity 0.15: `[1 left, 1 right, 2 left,
/// 2 right]`.
fn colour_counts(ctx: &mdsurf::gpu::GpuContext, layer: &LayerResult) -> [usize; 4] {
    let drawn = rep(0.15);
    let mut scene = GpuScene::new();
    let look = RenderSettings::default();
    scene.show_layers(&ctx.device, &ctx.queue, [(layer, &drawn)], &look);
    let mut camera = Camera::default();
    let (lo, hi) = scene.bounds().expect("the scene has bounds");
    camera.fit(lo, hi);
    let renderer = Renderer::new(&ctx.device);
    let size = [640, 400];
    let image = render_to_rgba(
        &ctx.device,
        &ctx.queue,
        &renderer,
        &scene,
        &camera,
        &look,
        size,
    )
    .expect("render");
    let half = |left: bool| -> Vec<u8> {
        image
            .pixels
            .chunks_exact(4 * size[0] as usize)
            .flat_map(|row| {
                let (l, r) = row.split_at(2 * size[0] as usize);
                if left { l } else { r }.to_vec()
            })
            .collect()
    };
    let (left, right) = (half(true), half(false));
    [
        pixels_near(&left, id_colour(1)),
        pixels_near(&right, id_colour(1)),
        pixels_near(&left, id_colour(2)),
        pixels_near(&right, id_colour(2)),
    ]
}

/// The picture of the two shells under a see-through surface shows both walls, each in its
/// id's colour: many pixels near each of the two colours, on the side of its shell. With both
/// walls in one colour (ids 1 and 1) the count tells: no pixel of the second colour.
#[test]
fn rendered_cavities_show_both_colours() {
    let Some(ctx) = crate::gpu_support::context() else {
        return;
    };
    let layer = shells_layer();
    let found = layer.cavities.as_ref().expect("cavities");
    // Cavity 1 is the larger void, the left shell's.
    assert!(found.cavities[0].centroid.x < 0.0 && found.cavities[1].centroid.x > 0.0);
    let counts = colour_counts(&ctx, &layer);
    assert!(
        counts[0] > 1000 && counts[3] > 300,
        "pixels of colour 1 left, 1 right, 2 left, 2 right: {counts:?}"
    );
    assert!(
        counts[1] < counts[0] / 10 && counts[2] < counts[3] / 10,
        "{counts:?}"
    );
    let mut one_colour = layer.clone();
    with_cavity_ids(&mut one_colour, &[1, 1]);
    let same = colour_counts(&ctx, &one_colour);
    assert!(
        same[1] > 300 && same[3] < counts[3] / 10,
        "both walls in colour 1: {same:?} (two colours: {counts:?})"
    );
}

/// A cavity at `x` Å on the x axis, of bounding radius `radius` Å and `volume` Å³.
fn cavity(x: f64, radius: f64, volume: f64) -> Cavity {
    Cavity {
        volume,
        area: volume,
        centroid: DVec3::new(x, 0.0, 0.0),
        radius,
        vertex_count: 0,
        lining_atoms: Vec::new(),
        cell: None,
    }
}

/// Frame `frame` of representation `id` (drawn as `rep`) with `cavities` found.
fn scene_with(id: u64, rep: &Representation, frame: usize, cavities: Vec<Cavity>) -> SceneFrame {
    let n = cavities.len();
    let layer = LayerResult {
        id,
        rep: rep.clone(),
        output: SurfaceOutput::default(),
        gpu_surface: None,
        particles: ParticleData {
            positions: Vec::new(),
            radii: Arc::new(Vec::new()),
            colours: Arc::new(Vec::new()),
            bonds: Arc::new(Vec::new()),
        },
        beads: false,
        gpu_work: None,
        reused: false,
        compute_ms: 0.0,
        closed: true,
        cavities: Some(Arc::new(CavityLayer {
            cavities,
            lining: vec![Vec::new(); n],
            ids: (1..=n as u64).collect(),
            wall_vertices: vec![0..0; n],
            mesh: Mesh::default(),
        })),
    };
    SceneFrame {
        frame,
        time_ps: None,
        gpu_bytes: 0,
        layers: vec![Arc::new(layer)],
    }
}

/// A core showing one surface with its cavities switched on (no system loaded: the frames are
/// handed to its tracks by the test).
fn core_with_cavities() -> (AppCore, Representation) {
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    let rep = Representation {
        cavities: true,
        ..Representation::new("surface", "all", RepStyle::Surface)
    };
    core.set_reps(vec![rep.clone()]);
    (core, rep)
}

/// The log of a crafted run: two cavities at the start (1 at x = 0, 2 at x = 10), cavity 3
/// appears at x = 30, 1 and 2 merge into one at x = 5, that one splits again (4 splits off 1),
/// and 3 goes; each frame's line reads as expected, newest first, in the panel too. The same
/// frame recomputed logs nothing twice; stepping back starts a new log.
#[test]
fn panel_logs_births_merges_splits_and_deaths() {
    let (mut core, rep) = core_with_cavities();
    let id = core.rep_ids[0];
    let two = || vec![cavity(0.0, 2.0, 50.0), cavity(10.0, 2.0, 30.0)];
    let three = || {
        let mut c = two();
        c.push(cavity(30.0, 2.0, 20.0));
        c
    };
    let frames = [
        two(),
        three(),
        vec![cavity(5.0, 6.0, 90.0), cavity(30.0, 2.0, 20.0)],
        three(),
        two(),
    ];
    let mut drawn_ids = Vec::new();
    for (f, cavities) in frames.into_iter().enumerate() {
        let mut scene = scene_with(id, &rep, f, cavities);
        core.cavity_tracks.record(&mut scene);
        let found = scene.layers[0].cavities.as_ref().expect("cavities");
        drawn_ids.push(found.ids.clone());
    }
    let expected = [
        "frame 4: cavity 3 gone (was 20.0 Å³)",
        "frame 3: cavity 4 split off from 1",
        "frame 2: cavities 1 and 2 merged into 1 (90.0 Å³)",
        "frame 1: cavity 3 appeared (20.0 Å³)",
        "frame 0: tracking starts: 2 cavities",
    ];
    let tracks = core.cavity_tracks.of(id).expect("tracks");
    assert_eq!(tracks.log().collect::<Vec<_>>(), expected);
    // The walls drawn take the tracked ids (frame 3: the part that split off is 4).
    let want: [&[u64]; 5] = [&[1, 2], &[1, 2, 3], &[1, 3], &[1, 4, 3], &[1, 4]];
    assert_eq!(drawn_ids, want);

    let mut h = Harness::builder().with_size([500.0, 700.0]).build_ui_state(
        |ui, core: &mut AppCore| {
            for c in cavity_ui(ui, core) {
                core.apply(c);
            }
        },
        core,
    );
    h.run();
    assert!(h.query_by_label("Events, newest first").is_some());
    for line in expected {
        assert!(h.query_by_label(line).is_some(), "{line} shown");
    }
    // Frame 4 shown again (recomputed): its line is not logged twice.
    h.state_mut()
        .cavity_tracks
        .record(&mut scene_with(id, &rep, 4, two()));
    let tracks = h.state().cavity_tracks.of(id).expect("tracks");
    assert_eq!(tracks.log().collect::<Vec<_>>(), expected);
    // Stepping back to frame 2 starts the tracks and the log again.
    h.state_mut().cavity_tracks.record(&mut scene_with(
        id,
        &rep,
        2,
        vec![cavity(5.0, 6.0, 90.0), cavity(30.0, 2.0, 20.0)],
    ));
    h.run();
    let tracks = h.state().cavity_tracks.of(id).expect("tracks");
    assert_eq!(
        tracks.log().collect::<Vec<_>>(),
        ["frame 2: tracking starts: 2 cavities"]
    );
    assert!(
        h.query_by_label(expected[0]).is_none(),
        "the old log is gone"
    );
    assert!(
        h.query_by_label("frame 2: tracking starts: 2 cavities")
            .is_some()
    );
    // Switching cavities off in the panel is still one command away.
    h.get_by_label("Find cavities").click();
    h.run();
    assert!(!h.state().reps[0].cavities);
}

/// The log keeps the newest lines only: a cavity that comes and goes every frame for 300
/// frames leaves the last `EVENT_LOG_LINES` lines, newest first.
#[test]
fn event_log_is_bounded() {
    let (mut core, rep) = core_with_cavities();
    let id = core.rep_ids[0];
    for f in 0..300 {
        let mut cavities = vec![cavity(0.0, 2.0, 50.0)];
        if f % 2 == 1 {
            cavities.push(cavity(20.0, 2.0, 10.0));
        }
        core.cavity_tracks
            .record(&mut scene_with(id, &rep, f, cavities));
    }
    let log: Vec<&str> = core.cavity_tracks.of(id).expect("tracks").log().collect();
    assert_eq!(log.len(), EVENT_LOG_LINES);
    // A new id every odd frame: 2 at frame 1, k + 2 at frame 2k + 1; it goes the frame after.
    assert_eq!(log[0], "frame 299: cavity 151 appeared (10.0 Å³)");
    assert_eq!(log[1], "frame 298: cavity 150 gone (was 10.0 Å³)");
    assert!(log[EVENT_LOG_LINES - 1].starts_with("frame 100: "));
}
