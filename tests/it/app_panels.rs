//! The viewer's panels driven through egui_kittest with a real CPU engine on a small in-memory
//! helix: moving the isovalue slider changes the parameters and the surface, the bead toggle cuts
//! the particle count, a too-large grid is refused, and the timeline buttons step frames.

use std::sync::Arc;
use std::time::Duration;

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use mdsurf::app::panels::{SurfaceDraft, surface_ui};
use mdsurf::app::source::helix_source;
use mdsurf::app::timeline::timeline_ui;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Command};
use mdsurf::scene::representation::RepStyle;
use mdsurf::surface::CpuEngine;

pub(crate) const WAIT: Duration = Duration::from_secs(60);

/// The app core and the Surface section's draft a panel test drives.
pub(crate) struct State {
    pub(crate) core: AppCore,
    pub(crate) draft: SurfaceDraft,
}

/// A core showing frame 0 of a 20-residue (60-atom), 5-frame helix.
pub(crate) fn loaded() -> State {
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.set_source(Arc::new(helix_source(20, 5)));
    assert!(core.wait_idle(WAIT), "first surface not computed in time");
    assert!(core.error.is_none(), "{:?}", core.error);
    let draft = SurfaceDraft::new(core.reps[0].params());
    State { core, draft }
}

fn apply_all(core: &mut AppCore, cmds: Vec<Command>) {
    for c in cmds {
        core.apply(c);
    }
}

fn panel_harness(state: State) -> Harness<'static, State> {
    panel_harness_sized(state, 600.0)
}

/// The Surface section alone in a 500-pixel-wide window `height` pixels high.
pub(crate) fn panel_harness_sized(state: State, height: f32) -> Harness<'static, State> {
    Harness::builder()
        .with_size([500.0, height])
        .build_ui_state(
            |ui, s: &mut State| {
                let cmds = surface_ui(ui, &s.core, &mut s.draft);
                apply_all(&mut s.core, cmds);
            },
            state,
        )
}

/// The first representation on screen (the helix's one default surface).
fn shown(core: &AppCore) -> &mdsurf::app::worker::LayerResult {
    let c = &core.shown.as_ref().expect("a surface is shown").computed;
    c.layers.first().expect("a representation is shown")
}

#[test]
fn isovalue_slider_changes_params_and_surface() {
    let mut h = panel_harness(loaded());
    let before = shown(&h.state().core).output.clone();
    assert!(before.mesh.triangle_count() > 0);
    h.get_by_role_and_label(Role::Slider, "I isovalue")
        .set_value_accesskit(1.0);
    h.run();
    let s = h.state_mut();
    assert_eq!(s.core.reps[0].isovalue, 1.0);
    assert!(s.core.wait_idle(WAIT));
    let after = &shown(&s.core).output;
    assert_ne!(after.mesh.triangle_count(), before.mesh.triangle_count());
    assert!(
        after.area < before.area,
        "area {} -> {}",
        before.area,
        after.area
    );
    assert!(
        after.volume < before.volume,
        "volume {} -> {}",
        before.volume,
        after.volume
    );
}

#[test]
fn bead_toggle_cuts_the_particle_count() {
    let mut h = panel_harness(loaded());
    assert_eq!(shown(&h.state().core).particles.positions.len(), 60);
    h.get_by_label("beads: one per residue").click();
    h.run();
    let s = h.state_mut();
    assert_eq!(s.core.reps[0].style, RepStyle::Beads);
    assert!(s.core.wait_idle(WAIT));
    let c = shown(&s.core);
    assert!(c.beads);
    assert_eq!(c.particles.positions.len(), 20);
    assert!(c.output.mesh.triangle_count() > 0);
}

#[test]
fn too_large_grid_is_refused_and_the_surface_stays() {
    let mut state = loaded();
    state.core.grid_limit_bytes = 1 << 20;
    let params = state.core.reps[0].params();
    let mut h = panel_harness(state);
    h.get_by_role_and_label(Role::Slider, "H grid spacing (Å)")
        .set_value_accesskit(0.25);
    h.run();
    assert!(
        h.query_by_label_contains("refused").is_some(),
        "no refusal shown"
    );
    let s = h.state();
    assert_eq!(
        s.core.reps[0].params(),
        params,
        "refused parameters must not be applied"
    );
    assert_eq!(s.draft.params.spacing, 0.25);
}

#[test]
fn timeline_buttons_step_frames() {
    let state = loaded();
    let mut h = Harness::builder().with_size([1200.0, 80.0]).build_ui_state(
        |ui, s: &mut State| {
            let cmds = timeline_ui(ui, &s.core.timeline, None);
            apply_all(&mut s.core, cmds);
        },
        state,
    );
    h.get_by_label(">").click();
    h.run();
    assert_eq!(h.state().core.timeline.current, 1);
    assert!(h.state_mut().core.wait_idle(WAIT));
    assert_eq!(
        h.state().core.shown.as_ref().expect("shown").computed.frame,
        1
    );
    h.get_by_label(">|").click();
    h.run();
    assert_eq!(h.state().core.timeline.current, 4);
    h.get_by_label("<").click();
    h.run();
    assert_eq!(h.state().core.timeline.current, 3);
    assert!(h.state_mut().core.wait_idle(WAIT));
    assert_eq!(
        h.state().core.shown.as_ref().expect("shown").computed.frame,
        3
    );
    assert_eq!(
        h.state()
            .core
            .shown
            .as_ref()
            .expect("shown")
            .computed
            .time_ps,
        Some(3.0)
    );
}

/// A selection typed in the panel: a bad one shows its error (with the column) and changes
/// nothing; a good one is applied and recomputes that representation.
#[test]
fn typed_selection_shows_its_error_and_keeps_the_last_good_one() {
    let mut state = loaded();
    let mut rep = state.core.reps[0].clone();
    rep.selection = "protein".into();
    state.core.apply(Command::UpdateRep(0, Box::new(rep)));
    let mut h = panel_harness(state);
    let before = h.state().core.reps[0].selection.clone();
    let field = h.get_by_role_and_label(Role::TextInput, "selection");
    field.focus();
    field.type_text(" and resid");
    h.run();
    assert!(
        h.query_by_label_contains("column").is_some(),
        "no error shown for '{}'",
        h.state().draft.selection
    );
    assert_eq!(
        h.state().core.reps[0].selection,
        before,
        "a bad selection was applied"
    );
    let field = h.get_by_role_and_label(Role::TextInput, "selection");
    field.type_text(" 1 to 5");
    h.run();
    let s = h.state_mut();
    assert!(
        s.draft.selection_error.is_none(),
        "{:?}",
        s.draft.selection_error
    );
    assert_eq!(
        s.core.reps[0].selection,
        format!("{before} and resid 1 to 5")
    );
    assert!(s.core.wait_idle(WAIT));
    assert_eq!(shown(&s.core).particles.positions.len(), 15);
}

/// The Export panel's movie formats: GIF and MP4 name the movie file accordingly (the file's
/// name picks the writer), PNG sequence drops it; the export button says which.
#[test]
fn export_panel_switches_between_mp4_gif_and_pngs() {
    use mdsurf::app::export::{MoviePlan, export_ui};
    let mut h = Harness::builder().with_size([400.0, 700.0]).build_ui_state(
        |ui, plan: &mut MoviePlan| {
            export_ui(ui, plan, &mut 1, 10, None);
        },
        MoviePlan::default(),
    );
    h.run();
    h.get_by_label("Export movie (PNG sequence)");
    let extension = |plan: &MoviePlan| {
        plan.video
            .as_ref()
            .and_then(|v| v.path.extension())
            .map(|e| e.to_string_lossy().into_owned())
    };
    h.get_by_label("GIF").click();
    h.run();
    assert_eq!(extension(h.state()).as_deref(), Some("gif"));
    h.get_by_label("Export movie (GIF)");
    h.get_by_label("MP4 (H.264)").click();
    h.run();
    assert_eq!(extension(h.state()).as_deref(), Some("mp4"));
    h.get_by_label("Export movie (MP4)");
    h.get_by_label("PNG sequence").click();
    h.run();
    assert!(h.state().video.is_none());
    h.get_by_label("Export movie (PNG sequence)");
}
