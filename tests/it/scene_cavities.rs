//! Cavities in the scene engine and the window (issue 32, section 3): a surface representation
//! with its `cavities` switch on carries the cavities [`measure::cavities`] finds on the very
//! mesh it computed (the host mesh, or the GPU mesh read back) and their walls as an extra
//! mesh; with the switch off nothing is found. The window's Cavities section lists the tracked
//! cavities of the shown frame and follows them over the frames shown. The system is a hollow
//! shell of atoms around a void (as in `measure_cavities`).

use std::sync::Arc;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::Vec3;
use mdsurf::app::cavity_panel::cavity_ui;
use mdsurf::app::source::MemorySource;
use mdsurf::app::timeline::TimelineCmd;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Command};
use mdsurf::measure::{self, Cavity};
use mdsurf::model::{Frame, Topology};
use mdsurf::render::{GpuScene, RenderSettings};
use mdsurf::scene::cavity_layer::{cavity_options, cavity_rgb};
use mdsurf::scene::representation::{RepStyle, Representation};
use mdsurf::scene::{LayerResult, RepRequest, SceneBackend, SceneEngine};
use mdsurf::surface::{AtomSet, CpuEngine, Mesh};

use crate::app_panels::WAIT;

/// Atoms on the shell (about 1 Å apart at 7 Å, so their Gaussians close the wall).
const SHELL_ATOMS: usize = 600;

/// `SHELL_ATOMS` points spread evenly (Fibonacci) on a sphere of `radius` Å around the origin.
fn shell(radius: f32) -> Vec<Vec3> {
    crate::measure_cavities::shell(SHELL_ATOMS, radius, Vec3::ZERO)
}

/// A topology of `SHELL_ATOMS` carbon atoms of radius 1.5 Å, ten per residue.
fn topology() -> Topology {
    let mut top = Topology::default();
    for a in 0..SHELL_ATOMS {
        top.names.push("C");
        top.elements.push("C");
        top.radii.push(1.5);
        top.residue_names.push("LEU");
        top.residue_ids.push(a as i64 / 10 + 1);
        top.residue_index.push(a as u32 / 10);
        top.chains.push("A");
        top.b_factors.push(0.0);
    }
    top
}

/// The shell at radii 7, 7.3, 7.6 Å: one frame each.
fn frames() -> Vec<Frame> {
    [7.0, 7.3, 7.6]
        .iter()
        .enumerate()
        .map(|(f, &r)| Frame {
            index: f,
            time_ps: Some(f as f64),
            positions: shell(r),
            cell: None,
        })
        .collect()
}

/// The shell's surface at 0.4 Å spacing, cavities on or off.
fn rep(cavities: bool) -> Representation {
    Representation {
        spacing: 0.4,
        cavities,
        ..Representation::new("shell", "all", RepStyle::Surface)
    }
}

/// Frame 0 of the shell through `engine`, its one layer, and that layer's mesh on the host.
fn shell_layer(engine: &mut SceneEngine, cavities: bool) -> (Arc<LayerResult>, Mesh) {
    let frame = Arc::new(frames().remove(0));
    let reps = [RepRequest {
        id: 1,
        rep: rep(cavities),
    }];
    let computed = engine
        .frame(&topology(), 0, &frame, &reps)
        .expect("the shell's frame computes");
    let layer = computed.layers[0].clone();
    let mesh = engine.read_mesh(0, &layer).expect("the mesh reads back");
    (layer, mesh)
}

/// What `measure::cavities` finds on `mesh`, the surface of `layer`'s atoms.
fn measured(layer: &LayerResult, mesh: &Mesh) -> Vec<Cavity> {
    let p = &layer.particles;
    let atoms = AtomSet {
        positions: &p.positions,
        radii: &p.radii,
        colours: None,
    };
    let params = layer.rep.vertices.effective(&layer.rep.params());
    measure::cavities(mesh, &atoms, &params, &cavity_options()).expect("cavities measure")
}

/// The layer's cavities are those of its own mesh: one void, its walls in id 1's colour,
/// as many triangles as the void's wall, facing out of the void (the mesh's winding reversed:
/// a positive enclosed volume).
fn check_layer(backend: &str, layer: &LayerResult, mesh: &Mesh) {
    let found = layer
        .cavities
        .as_ref()
        .expect("cavities found with the switch on");
    let expected = measured(layer, mesh);
    assert_eq!(found.cavities, expected, "{backend}");
    assert_eq!(found.cavities.len(), 1, "{backend}: one void in the shell");
    assert_eq!(found.lining.len(), 1, "{backend}");
    assert!(
        found.lining[0].len() >= 50 && found.lining[0][0].contains("LEU"),
        "{backend}: {:?}",
        found.lining[0]
    );
    let walls = &found.mesh;
    assert!(
        walls.colours.iter().all(|c| *c == cavity_rgb(1)),
        "{backend}"
    );
    let wall = measure::components(mesh)
        .expect("components")
        .into_iter()
        .find(|c| c.volume < 0.0)
        .expect("the void's wall is a component");
    assert_eq!(walls.indices.len(), 3 * wall.triangles.len(), "{backend}");
    assert_eq!(walls.positions.len(), wall.vertices.len(), "{backend}");
    let turned = measure::components(walls).expect("components of the walls");
    assert_eq!(turned.len(), 1, "{backend}");
    let rel = (turned[0].volume + wall.volume).abs() / wall.volume.abs();
    assert!(
        rel < 1e-9,
        "{backend}: {} vs {}",
        turned[0].volume,
        wall.volume
    );
}

#[test]
fn cpu_layer_carries_the_cavities_of_its_mesh_only_when_asked() {
    let mut engine = SceneEngine::new(SceneBackend::Host(Box::new(CpuEngine::new())));
    let (off, _) = shell_layer(&mut engine, false);
    assert!(
        off.cavities.is_none(),
        "nothing is found with the switch off"
    );
    let (on, mesh) = shell_layer(&mut engine, true);
    assert!(!on.reused, "turning the switch on recomputes");
    check_layer("cpu", &on, &mesh);
    assert_eq!(mesh, on.output.mesh);
}

#[test]
fn gpu_layer_carries_the_cavities_of_its_read_back_mesh() {
    let Some(gpu) = crate::gpu_support::engine() else {
        return;
    };
    let mut engine = SceneEngine::new(SceneBackend::Gpu(Box::new(gpu)));
    let (off, _) = shell_layer(&mut engine, false);
    assert!(off.gpu_surface.is_some() && off.cavities.is_none());
    let (on, mesh) = shell_layer(&mut engine, true);
    assert!(on.gpu_surface.is_some());
    check_layer("gpu", &on, &mesh);
}

/// What the window and `render` draw ([`GpuScene::show_layers`]): the surface, then its
/// cavities as one more layer, opaque and in its walls' own colours under a see-through surface; no
/// cavity layer once the switch is off in the representation drawn.
#[test]
fn cavities_are_drawn_as_an_opaque_layer_after_their_surface() {
    let Some(ctx) = crate::gpu_support::context() else {
        return;
    };
    let mut engine = SceneEngine::new(SceneBackend::Host(Box::new(CpuEngine::new())));
    let (layer, mesh) = shell_layer(&mut engine, true);
    let walls = &layer.cavities.as_ref().expect("cavities").mesh;
    let mut scene = GpuScene::new();
    let look = RenderSettings::default();
    let drawn = Representation {
        opacity: 0.3,
        ..rep(true)
    };
    scene.show_layers(&ctx.device, &ctx.queue, [(layer.as_ref(), &drawn)], &look);
    assert_eq!(scene.surface_count(), 2);
    assert_eq!(
        scene.triangle_count() as usize,
        mesh.triangle_count() + walls.triangle_count()
    );
    assert_eq!(scene.layer_mut(0).opacity, Some(0.3));
    assert_eq!(scene.layer_mut(0).colour, None);
    assert_eq!(scene.layer_mut(1).opacity, Some(1.0));
    assert_eq!(scene.layer_mut(1).colour, None, "the walls' vertex colours");
    // The surface is closed (back faces may be culled); the walls, seen from inside the
    // surface, are drawn on both sides.
    assert!(layer.closed && scene.layer_mut(0).closed);
    assert!(!scene.layer_mut(1).closed);
    let off = Representation {
        cavities: false,
        ..drawn
    };
    scene.show_layers(&ctx.device, &ctx.queue, [(layer.as_ref(), &off)], &look);
    assert_eq!(scene.surface_count(), 1);
    assert_eq!(scene.triangle_count() as usize, mesh.triangle_count());
}

/// The window's Cavities section on the shell: the switch turns cavity finding on, the list
/// shows the void with id 1 in every frame played forward, its volume grows with the shell,
/// and stepping back restarts the tracks at the frame shown.
#[test]
fn cavity_panel_lists_the_tracked_void() {
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.set_source(Arc::new(MemorySource {
        topology: topology(),
        frames: frames(),
        name: "shell".into(),
    }));
    assert!(core.wait_idle(WAIT));
    let mut first = core.reps[0].clone();
    first.spacing = 0.4;
    core.apply(Command::UpdateRep(0, Box::new(first)));
    assert!(core.wait_idle(WAIT));
    assert!(core.error.is_none(), "{:?}", core.error);
    let mut h = Harness::builder().with_size([500.0, 500.0]).build_ui_state(
        |ui, core: &mut AppCore| {
            for c in cavity_ui(ui, core) {
                core.apply(c);
            }
        },
        core,
    );
    h.run();
    assert!(h.query_by_label_contains("cavities in frame").is_none());
    h.get_by_label("Find cavities").click();
    h.run();
    assert!(h.state().reps[0].cavities);
    let mut volumes = Vec::new();
    for f in 0..3 {
        if f > 0 {
            h.state_mut().apply(Command::Timeline(TimelineCmd::Step(1)));
        }
        assert!(h.state_mut().wait_idle(WAIT));
        assert!(h.state().error.is_none(), "{:?}", h.state().error);
        h.run();
        let label = format!("1 cavities in frame {f}");
        assert!(h.query_by_label_contains(&label).is_some(), "{label}");
        assert!(h.query_by_label("#1").is_some(), "frame {f}: id 1 listed");
        let id = h.state().rep_ids[0];
        let tracks = h.state().cavity_tracks.of(id).expect("tracks");
        assert_eq!(tracks.current.len(), 1);
        volumes.push(tracks.current[0].cavity.volume);
        assert_eq!(
            tracks.volumes[&1].len(),
            f + 1,
            "one volume per frame shown"
        );
    }
    assert!(
        volumes[0] < volumes[1] && volumes[1] < volumes[2],
        "{volumes:?}"
    );
    h.state_mut()
        .apply(Command::Timeline(TimelineCmd::Step(-1)));
    assert!(h.state_mut().wait_idle(WAIT));
    h.run();
    let id = h.state().rep_ids[0];
    let tracks = h.state().cavity_tracks.of(id).expect("tracks");
    assert_eq!(tracks.frame(), Some(1));
    assert_eq!(tracks.volumes.len(), 1);
    assert_eq!(tracks.volumes[&1].keys().copied().collect::<Vec<_>>(), [1]);
    // The probe switch: the same void as a 1.4 Å probe sees it, larger than the surface's.
    let surface_void = tracks.current[0].cavity.volume;
    h.get_by_label("as a 1.4 Å probe finds them").click();
    h.run();
    assert_eq!(h.state().reps[0].cavity_probe, Some(1.4));
    assert!(h.state_mut().wait_idle(WAIT));
    assert!(h.state().error.is_none(), "{:?}", h.state().error);
    h.run();
    let tracks = h.state().cavity_tracks.of(id).expect("tracks");
    assert_eq!(tracks.current.len(), 1);
    let probe_void = tracks.current[0].cavity.volume;
    assert!(probe_void > surface_void, "{probe_void} vs {surface_void}");
}

/// A periodic surface is open at the cell's faces: its layer says so, and the renderer draws
/// both of its sides.
#[test]
fn periodic_layers_are_open() {
    let Some(ctx) = crate::gpu_support::context() else {
        return;
    };
    let mut engine = SceneEngine::new(SceneBackend::Host(Box::new(CpuEngine::new())));
    engine.set_periodic(Some(mdsurf::surface::periodic::Replicate::default()));
    // The shell in a 12 Å box: its atoms cross the faces.
    let frame = Arc::new(Frame {
        cell: Some([Vec3::X * 12.0, Vec3::Y * 12.0, Vec3::Z * 12.0]),
        ..frames().remove(0)
    });
    let reps = [RepRequest {
        id: 1,
        rep: rep(false),
    }];
    let computed = engine
        .frame(&topology(), 0, &frame, &reps)
        .expect("the periodic frame computes");
    let layer = computed.layers[0].clone();
    assert!(!layer.closed, "a periodic surface is open at the faces");
    assert!(!layer.output.mesh.is_closed());
    let mut scene = GpuScene::new();
    let look = RenderSettings::default();
    scene.show_layers(
        &ctx.device,
        &ctx.queue,
        [(layer.as_ref(), &rep(false))],
        &look,
    );
    assert!(!scene.layer_mut(0).closed);
}
