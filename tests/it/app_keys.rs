//! Keyboard shortcuts pressed into the whole viewer inside an egui_kittest harness (a real CPU
//! engine on a small in-memory helix): arrows, Shift+arrows, Home/End and Space drive the
//! timeline; O, F and R change the camera; number keys show and hide representations; `?`, F1
//! and the Help menu open the list of every shortcut, Escape closes it; and keys typed into a
//! text field stay in the field. With a wgpu adapter, one more test checks that the picture
//! changes with the keys.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use mdsurf::app::keys::{OVERLAY_TITLE, SHORTCUTS};
use mdsurf::app::source::helix_source;
use mdsurf::app::viewport::GpuView;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Command, Script, Viewer};
use mdsurf::render::Projection;
use mdsurf::surface::CpuEngine;

/// Frames of the test helix.
const FRAMES: usize = 15;

/// The viewer on a 20-residue (60-atom), [`FRAMES`]-frame helix, with its GPU view when the
/// harness has a wgpu device.
fn viewer(cc: &eframe::CreationContext<'_>) -> Viewer {
    let ctx = cc.egui_ctx.clone();
    let worker = Worker::spawn(
        Box::new(CpuEngine::new()),
        Box::new(move || ctx.request_repaint()),
    );
    let mut core = AppCore::new(worker);
    core.set_source(Arc::new(helix_source(20, FRAMES)));
    let gpu = cc.wgpu_render_state.as_ref().map(GpuView::new);
    Viewer::new(core, gpu, Script::default(), Arc::new(Mutex::new(None)))
}

/// The viewer window without a GPU (nothing is drawn in the 3D view; the state is all there).
fn harness() -> Harness<'static, Viewer> {
    let mut h = Harness::builder()
        .with_size([1200.0, 800.0])
        .build_eframe(|cc| viewer(cc));
    settle(&mut h);
    h
}

/// Runs the window until the worker is idle and the surface of the current frame is on screen
/// (the worker turns idle just before it sends its reply: the next frame, after a pause,
/// takes it).
fn settle(h: &mut Harness<'static, Viewer>) {
    let start = Instant::now();
    loop {
        let idle = !h.state().core().computing();
        std::thread::sleep(Duration::from_millis(10));
        h.step();
        let core = h.state().core();
        assert!(core.error.is_none(), "{:?}", core.error);
        let shown = core.shown.as_ref().map(|s| s.computed.frame);
        if idle && !core.computing() && shown == Some(core.timeline.current) {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "frame {} not shown after a minute",
            core.timeline.current
        );
    }
    h.step();
}

/// Presses `key` with `modifiers` and runs one frame.
fn press(h: &mut Harness<'static, Viewer>, modifiers: Modifiers, key: Key) {
    h.key_press_modifiers(modifiers, key);
    h.step();
}

/// The frame requested and the frame whose surface is on screen, after settling.
fn frame(h: &mut Harness<'static, Viewer>) -> (usize, usize) {
    settle(h);
    let core = h.state().core();
    let shown = core.shown.as_ref().expect("a surface").computed.frame;
    (core.timeline.current, shown)
}

fn command(h: &mut Harness<'static, Viewer>, cmd: Command) {
    let ctx = h.ctx.clone();
    h.state_mut().command(&ctx, cmd);
    h.step();
}

#[test]
fn arrows_home_end_and_space_drive_the_timeline() {
    let mut h = harness();
    assert_eq!(frame(&mut h), (0, 0));
    press(&mut h, Modifiers::NONE, Key::ArrowRight);
    assert_eq!(frame(&mut h), (1, 1));
    press(&mut h, Modifiers::SHIFT, Key::ArrowRight);
    assert_eq!(frame(&mut h), (11, 11));
    // Ten more would pass the end: clamped at the last frame.
    press(&mut h, Modifiers::SHIFT, Key::ArrowRight);
    assert_eq!(frame(&mut h), (FRAMES - 1, FRAMES - 1));
    press(&mut h, Modifiers::NONE, Key::ArrowLeft);
    assert_eq!(frame(&mut h), (FRAMES - 2, FRAMES - 2));
    press(&mut h, Modifiers::SHIFT, Key::ArrowLeft);
    assert_eq!(frame(&mut h), (FRAMES - 12, FRAMES - 12));
    press(&mut h, Modifiers::NONE, Key::Home);
    assert_eq!(frame(&mut h), (0, 0));
    press(&mut h, Modifiers::NONE, Key::End);
    assert_eq!(frame(&mut h), (FRAMES - 1, FRAMES - 1));

    assert!(!h.state().core().timeline.playing);
    press(&mut h, Modifiers::NONE, Key::Space);
    assert!(h.state().core().timeline.playing, "Space did not play");
    press(&mut h, Modifiers::NONE, Key::Space);
    assert!(!h.state().core().timeline.playing, "Space did not pause");
}

#[test]
fn o_f_and_r_change_the_camera() {
    let mut h = harness();
    let fitted = h.state().core().camera;
    assert_eq!(fitted.projection, Projection::Perspective);
    press(&mut h, Modifiers::NONE, Key::O);
    assert_eq!(h.state().core().camera.projection, Projection::Orthographic);
    press(&mut h, Modifiers::NONE, Key::O);
    assert_eq!(h.state().core().camera.projection, Projection::Perspective);

    // Turned and zoomed out: F fits the distance again and keeps the direction.
    command(&mut h, Command::Orbit(0.7, 0.3));
    command(&mut h, Command::Zoom(3.0));
    let moved = h.state().core().camera;
    assert!(moved.distance > 2.0 * fitted.distance);
    press(&mut h, Modifiers::NONE, Key::F);
    let after_fit = h.state().core().camera;
    assert!(
        (after_fit.distance - fitted.distance).abs() < 1e-3 * fitted.distance,
        "F: distance {} (fitted {})",
        after_fit.distance,
        fitted.distance
    );
    assert_eq!((after_fit.yaw, after_fit.pitch), (moved.yaw, moved.pitch));

    // R: back to the default direction, fitted.
    press(&mut h, Modifiers::NONE, Key::R);
    let reset = h.state().core().camera;
    assert_ne!(reset, after_fit);
    assert_eq!((reset.yaw, reset.pitch), (fitted.yaw, fitted.pitch));
    assert!((reset.distance - fitted.distance).abs() < 1e-3 * fitted.distance);
}

#[test]
fn number_keys_show_and_hide_representations() {
    let mut h = harness();
    command(&mut h, Command::AddRep);
    let visible = |h: &Harness<'static, Viewer>| -> Vec<bool> {
        h.state().core().reps.iter().map(|r| r.visible).collect()
    };
    assert_eq!(visible(&h), [true, true]);
    press(&mut h, Modifiers::NONE, Key::Num1);
    assert_eq!(
        visible(&h),
        [false, true],
        "1 did not hide representation 1"
    );
    // The surface on screen follows: only representation 2 is computed.
    settle(&mut h);
    let core = h.state().core();
    let shown = &core.shown.as_ref().expect("a surface").computed;
    assert_eq!(shown.layers.len(), 1, "representation 1 still on screen");
    assert!(shown.layer(core.rep_ids[0]).is_none());
    press(&mut h, Modifiers::NONE, Key::Num2);
    assert_eq!(visible(&h), [false, false]);
    press(&mut h, Modifiers::NONE, Key::Num1);
    assert_eq!(
        visible(&h),
        [true, false],
        "1 did not show representation 1"
    );
    // No representation 9: nothing happens.
    press(&mut h, Modifiers::NONE, Key::Num9);
    assert_eq!(visible(&h), [true, false]);
}

#[test]
fn question_mark_f1_and_help_menu_list_every_shortcut() {
    let mut h = harness();
    let listed = |h: &Harness<'static, Viewer>| {
        SHORTCUTS
            .iter()
            .filter(|s| {
                // Descriptions may repeat (`?` and F1); labels are unique.
                h.query_all_by_label(s.description).next().is_some()
                    && h.query_by_label(&s.label(false)).is_some()
            })
            .count()
    };
    assert!(!h.state().shortcuts_shown());
    assert_eq!(listed(&h), 0);
    // `?` as a US keyboard sends it: Shift+/ gives the logical key `?` with Shift held.
    press(&mut h, Modifiers::SHIFT, Key::Questionmark);
    h.step();
    assert!(h.state().shortcuts_shown(), "? did not open the list");
    assert!(h.query_by_label(OVERLAY_TITLE).is_some());
    assert_eq!(listed(&h), SHORTCUTS.len(), "a shortcut is missing");
    for s in SHORTCUTS {
        assert!(
            h.query_all_by_label(s.description).next().is_some(),
            "{} not listed",
            s.description
        );
    }
    press(&mut h, Modifiers::NONE, Key::Escape);
    h.step();
    assert!(
        !h.state().shortcuts_shown(),
        "Escape did not close the list"
    );
    assert_eq!(listed(&h), 0);

    press(&mut h, Modifiers::NONE, Key::F1);
    h.step();
    assert!(h.state().shortcuts_shown(), "F1 did not open the list");
    assert_eq!(listed(&h), SHORTCUTS.len());
    press(&mut h, Modifiers::NONE, Key::F1);
    h.step();
    assert!(!h.state().shortcuts_shown(), "F1 did not close the list");

    h.get_by_label("Help").click();
    h.step();
    h.step();
    h.get_by_label_contains(OVERLAY_TITLE).click();
    h.step();
    h.step();
    assert!(h.state().shortcuts_shown(), "the Help menu did not open it");
    assert_eq!(listed(&h), SHORTCUTS.len());
}

/// Types `text` into the focused widget as a keyboard does: a key press and a text event per
/// character.
fn type_keys(h: &mut Harness<'static, Viewer>, text: &str) {
    for c in text.chars() {
        let key = if c == ' ' {
            Key::Space
        } else {
            Key::from_name(&c.to_string()).expect("a key")
        };
        h.key_down(key);
        h.event(egui::Event::Text(c.to_string()));
        h.key_up(key);
        h.step();
    }
}

#[test]
fn keys_typed_into_a_text_field_stay_there() {
    let mut h = harness();
    command(&mut h, Command::Orbit(0.7, 0.3));
    let camera = h.state().core().camera;
    let field = h.get_by_role_and_label(Role::TextInput, "selection");
    let before = field.value().unwrap_or_default();
    field.focus();
    h.step();
    h.step();
    type_keys(&mut h, "1 r");
    h.step();
    let field = h.get_by_role_and_label(Role::TextInput, "selection");
    assert_eq!(
        field.value().unwrap_or_default(),
        format!("{before}1 r"),
        "the typed text is not in the field"
    );
    let core = h.state().core();
    assert!(core.reps[0].visible, "typing 1 hid representation 1");
    assert_eq!(core.camera, camera, "typing r reset the view");
    assert!(!core.timeline.playing, "typing a space started playback");

    // Escape leaves the field; then the same keys are shortcuts again.
    press(&mut h, Modifiers::NONE, Key::Escape);
    h.step();
    press(&mut h, Modifiers::NONE, Key::Num1);
    assert!(
        !h.state().core().reps[0].visible,
        "1 outside the field did nothing"
    );
    press(&mut h, Modifiers::NONE, Key::R);
    assert_ne!(
        h.state().core().camera,
        camera,
        "R outside the field did nothing"
    );
}

/// egui_kittest's wgpu set-up on the viewer's backends (as in app_window.rs).
fn harness_wgpu() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_kittest::wgpu::default_wgpu_setup();
    if let egui_wgpu::WgpuSetup::CreateNew(new) = &mut setup {
        new.instance_descriptor.backends = mdsurf::gpu::GpuContext::window_backends();
    }
    setup
}

/// The 3D view's centre (the window's middle) of a rendered window.
fn centre(h: &mut Harness<'static, Viewer>) -> Vec<[u8; 4]> {
    let image = h.render().expect("render the window");
    let (w, hgt) = image.dimensions();
    (0..60)
        .flat_map(|dy| (0..60).map(move |dx| (w / 2 - 30 + dx, hgt / 2 - 30 + dy)))
        .map(|(x, y)| image.get_pixel(x, y).0)
        .collect()
}

#[test]
fn keys_change_the_picture() {
    if let Err(e) = mdsurf::render::HeadlessGpu::new() {
        if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") {
            panic!("REQUIRE_GPU=1 but {e}");
        }
        eprintln!("note: skipping: {e}");
        return;
    }
    let mut h = Harness::builder()
        .with_size([1000.0, 700.0])
        .wgpu_setup(harness_wgpu())
        .build_eframe(|cc| viewer(cc));
    settle(&mut h);
    h.step();
    let first = centre(&mut h);
    let mut colours = first.clone();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 20,
        "3D view looks flat: {} colours",
        colours.len()
    );

    press(&mut h, Modifiers::SHIFT, Key::ArrowRight);
    settle(&mut h);
    assert_eq!(h.state().core().timeline.current, 10);
    let stepped = centre(&mut h);
    assert_ne!(stepped, first, "Shift+Right did not change the picture");

    press(&mut h, Modifiers::NONE, Key::O);
    h.step();
    let ortho = centre(&mut h);
    assert_ne!(ortho, stepped, "O did not change the picture");

    // The shortcut list over the view (saved for a look with MDSURF_SAVE_WINDOW=DIR).
    press(&mut h, Modifiers::NONE, Key::F1);
    h.step();
    let image = h.render().expect("render the window");
    if let Ok(dir) = std::env::var("MDSURF_SAVE_WINDOW") {
        let _ = image.save(std::path::PathBuf::from(dir).join("shortcuts.png"));
    }
    assert_ne!(centre(&mut h), ortho, "the list is not drawn over the view");
}
