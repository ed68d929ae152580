//! The side panels: surface parameters with the grid estimate ([`surface_ui`]), the look of the
//! picture ([`look_ui`]) and live readouts ([`readouts_ui`]). Each returns [`Command`]s; nothing
//! here changes the app's state directly.

use super::state::{AppCore, Command};
use crate::model::ColorScheme;
use crate::render::{Background, Projection, Stereo};
use crate::scene::representation::RepStyle;
use crate::selection::Selection;
use crate::surface::{Preset, Quality, RadiusSet, SurfaceParams, VertexMode};

/// The selected representation's edits in progress: surface parameters become the
/// representation's only when the grid fits, and a selection only when it parses.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceDraft {
    /// The edited parameters.
    pub params: SurfaceParams,
    /// Which representation the draft belongs to (its id; the draft restarts when another is
    /// selected).
    pub rep_id: Option<u64>,
    /// The selection text being typed.
    pub selection: String,
    /// The parse error of `selection`, shown live (one line with the column).
    pub selection_error: Option<String>,
}

impl SurfaceDraft {
    /// A draft of `params` for no representation yet.
    pub fn new(params: SurfaceParams) -> Self {
        SurfaceDraft {
            params,
            rep_id: None,
            selection: String::new(),
            selection_error: None,
        }
    }

    /// Restarts the draft from representation `i` of `core` when it is not the one drafted.
    fn follow(&mut self, core: &AppCore) {
        let id = core.rep_ids.get(core.selected).copied();
        if id != self.rep_id {
            self.rep_id = id;
            if let Some(rep) = core.selected_rep() {
                self.params = rep.params();
                self.selection = rep.selection.clone();
                self.selection_error = None;
            }
        }
    }
}

fn megabytes(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.2} GB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MB", bytes as f64 / (1u64 << 20) as f64)
    }
}

/// The representations: the list (show/hide, select, add, duplicate, delete) and the selected
/// one's editor: name, selection (its error shown live; only a selection that parses is
/// applied), style, colours, opacity and, for surfaces, H, R, I, quality and the bead toggle.
/// The grid the edited values would need (dims, voxels, memory, and the total of every visible
/// surface) is shown before it is applied, and a grid above the limit is refused (the previous
/// surface stays).
pub fn surface_ui(ui: &mut egui::Ui, core: &AppCore, draft: &mut SurfaceDraft) -> Vec<Command> {
    let mut out = Vec::new();
    ui.heading("Representations");
    for (i, rep) in core.reps.iter().enumerate() {
        ui.horizontal(|ui| {
            let label = format!("{} · {}", rep.name, rep.style);
            let name = ui.selectable_label(i == core.selected, label);
            if name.clicked() {
                out.push(Command::SelectRep(i));
            }
            let mut visible = rep.visible;
            if ui
                .checkbox(&mut visible, "shown")
                .on_hover_text("show or hide this representation")
                .changed()
            {
                let mut r = rep.clone();
                r.visible = visible;
                out.push(Command::UpdateRep(i, Box::new(r)));
            }
        });
    }
    ui.horizontal(|ui| {
        if ui.button("Add").clicked() {
            out.push(Command::AddRep);
        }
        let any = !core.reps.is_empty();
        if ui
            .add_enabled(any, egui::Button::new("Duplicate"))
            .clicked()
        {
            out.push(Command::DuplicateRep(core.selected));
        }
        if ui.add_enabled(any, egui::Button::new("Delete")).clicked() {
            out.push(Command::DeleteRep(core.selected));
        }
    });
    draft.follow(core);
    let Some(rep) = core.selected_rep() else {
        ui.label("no representation: Add one");
        return out;
    };
    let i = core.selected;
    ui.separator();
    let mut edited = rep.clone();
    ui.horizontal(|ui| {
        let label = ui.label("name");
        ui.text_edit_singleline(&mut edited.name)
            .labelled_by(label.id);
    });
    ui.horizontal(|ui| {
        let label = ui.label("selection");
        let field = ui
            .text_edit_singleline(&mut draft.selection)
            .labelled_by(label.id);
        if field.changed() {
            draft.selection_error = Selection::parse(&draft.selection)
                .err()
                .map(|e| e.to_string());
        }
    });
    match &draft.selection_error {
        Some(e) => {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        None => edited.selection = draft.selection.clone(),
    }
    if let Some(c) = core.shown.as_ref().and_then(|s| {
        let id = *core.rep_ids.get(i)?;
        s.computed.layer(id)
    }) {
        let kind = if c.beads { "beads" } else { "atoms" };
        ui.label(format!("{} {kind}", c.particles.positions.len()));
    }
    egui::ComboBox::from_label("style")
        .selected_text(edited.style.name())
        .show_ui(ui, |ui| {
            for st in RepStyle::ALL {
                ui.selectable_value(&mut edited.style, st, st.name());
            }
        });
    ui.add(egui::Slider::new(&mut edited.opacity, 0.0..=1.0).text("opacity"));
    colour_ui(ui, &mut edited.colour);
    if rep.style.is_surface() {
        named_choice(
            ui,
            "vertices",
            &mut edited.vertices,
            VertexMode::ALL,
            VertexMode::name,
            "interpolated: linear along grid edges; refined: on the exact Gaussian sum, analytic \
             normals, area and volume that hold at any H (slower)",
        );
        let ses_radii: Vec<String> = (RadiusSet::Ses.radii().iter())
            .map(|(e, r)| format!("{e} {r} Å"))
            .collect();
        named_choice(
            ui,
            "radii",
            &mut edited.radii,
            RadiusSet::ALL,
            RadiusSet::name,
            &format!(
                "mdsurf: the element table; ses: the SES preset's ({}), in each frame shrunk on \
                 atoms with few heavy atoms within {} Å (exposed); radius overrides apply on top",
                ses_radii.join(", "),
                RadiusSet::Ses.exposure().map_or(0.0, |m| m.radius)
            ),
        );
    }
    if edited != *rep {
        out.push(Command::UpdateRep(i, Box::new(edited)));
    }
    if rep.style.is_surface() {
        out.extend(params_ui(ui, core, draft, i));
        let mut beads = rep.style == RepStyle::Beads;
        if ui.checkbox(&mut beads, "beads: one per residue").changed() {
            out.push(Command::SetBeads(beads));
        }
    }
    out
}

/// A drop-down box labelled `label` choosing `value` among `all`, each shown by `name`.
fn named_choice<T: Copy + PartialEq, const N: usize>(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut T,
    all: [T; N],
    name: fn(T) -> &'static str,
    hover: &str,
) {
    egui::ComboBox::from_label(label)
        .selected_text(name(*value))
        .show_ui(ui, |ui| {
            for v in all {
                ui.selectable_value(value, v, name(v));
            }
        })
        .response
        .on_hover_text(hover);
}

/// H, R, I and quality of surface representation `i`, with its grid and the total.
fn params_ui(
    ui: &mut egui::Ui,
    core: &AppCore,
    draft: &mut SurfaceDraft,
    i: usize,
) -> Vec<Command> {
    let mut out = Vec::new();
    let current = core.reps[i].params();
    let p = &mut draft.params;
    ui.add(
        egui::Slider::new(&mut p.spacing, 0.25..=4.0)
            .logarithmic(true)
            .text("H grid spacing (Å)"),
    );
    ui.add(egui::Slider::new(&mut p.radius_scale, 0.5..=3.0).text("R radius scale"));
    ui.add(
        egui::Slider::new(&mut p.isovalue, 0.05..=2.0)
            .logarithmic(true)
            .text("I isovalue"),
    );
    egui::ComboBox::from_label("quality")
        .selected_text(p.quality.name())
        .show_ui(ui, |ui| {
            for q in Quality::ALL {
                ui.selectable_value(
                    &mut p.quality,
                    q,
                    format!("{} (cutoff {} α)", q.name(), q.cutoff()),
                );
            }
        });
    ui.horizontal(|ui| {
        ui.label("preset");
        for preset in Preset::ALL {
            if ui
                .button(preset.name())
                .on_hover_text(format!(
                    "R, I, quality, {} vertices and {} radii: {}",
                    preset.vertices(),
                    preset.radius_set(),
                    preset.description()
                ))
                .clicked()
            {
                *p = preset.apply(*p);
                out.push(Command::ApplyPreset(preset));
            }
        }
    });
    // A preset in use (its R, I and quality) at a spacing it does not hold at.
    for preset in Preset::ALL {
        if preset.apply(*p) == *p
            && let Some(note) = preset.spacing_note(p.spacing)
        {
            ui.colored_label(ui.visuals().warn_fg_color, note);
        }
    }
    match core.grid_estimate(i, p) {
        Some((grid, bytes)) => {
            let [x, y, z] = grid.dims;
            let total = core.total_grid_bytes(i, p);
            ui.label(format!(
                "grid {x}×{y}×{z} = {:.2} M voxels, {}; all surfaces {}",
                grid.voxel_count() as f64 / 1e6,
                megabytes(bytes),
                megabytes(total)
            ));
            if total > core.grid_limit_bytes {
                ui.colored_label(
                    ui.visuals().error_fg_color,
                    format!(
                        "refused: needs {} > limit {}; raise H",
                        megabytes(total),
                        megabytes(core.grid_limit_bytes)
                    ),
                );
            } else if *p != current {
                out.push(Command::SetParams(*p));
            }
        }
        None if *p != current => out.push(Command::SetParams(*p)),
        None => {}
    }
    if ui.button("Defaults").clicked() {
        *p = SurfaceParams::default();
    }
    out
}

/// The colour scheme picker (a colour button for the single colour).
fn colour_ui(ui: &mut egui::Ui, scheme: &mut ColorScheme) {
    egui::ComboBox::from_label("colour")
        .selected_text(scheme.to_string())
        .show_ui(ui, |ui| {
            for s in [
                ColorScheme::Element,
                ColorScheme::Chain,
                ColorScheme::ResidueType,
                ColorScheme::ResidueIndex,
                ColorScheme::BFactor,
                ColorScheme::Exposure(crate::model::ColourMap::default()),
                ColorScheme::Single([0.8, 0.8, 0.8]),
            ] {
                let name = if let ColorScheme::Single(_) = s {
                    "single colour".to_string()
                } else {
                    s.to_string()
                };
                let selected = std::mem::discriminant(scheme) == std::mem::discriminant(&s);
                if ui.selectable_label(selected, name).clicked() && !selected {
                    *scheme = s;
                }
            }
        });
    if let ColorScheme::Single(c) = scheme {
        ui.horizontal(|ui| {
            ui.label("colour");
            ui.color_edit_button_rgb(c);
        });
    }
    if let ColorScheme::Data(d) = scheme {
        data_colour_ui(ui, d);
    }
    if let ColorScheme::Exposure(map) = scheme {
        colour_map_ui(ui, map);
        ui.label("0 buried … 1 as exposed as alone");
    }
}

/// The colour map picker of data and exposure colours.
fn colour_map_ui(ui: &mut egui::Ui, map: &mut crate::model::ColourMap) {
    egui::ComboBox::from_label("colour map")
        .selected_text(map.name())
        .show_ui(ui, |ui| {
            for m in crate::model::ColourMap::ALL {
                ui.selectable_value(map, m, m.name());
            }
        });
}

/// Colour map and range of data colours (`--color data:FILE.csv`): the range is the data's
/// (see [`crate::model::ColourMap::default_range`]) until "fixed range" is ticked.
fn data_colour_ui(ui: &mut egui::Ui, d: &mut crate::model::DataColours) {
    colour_map_ui(ui, &mut d.map);
    let mut fixed = d.range.is_some();
    let mut range = d.effective_range();
    ui.horizontal(|ui| {
        ui.checkbox(&mut fixed, "fixed range");
        let step = ((range[1] - range[0]).abs() / 100.0).max(1e-4) as f64;
        ui.add_enabled(fixed, egui::DragValue::new(&mut range[0]).speed(step));
        ui.add_enabled(fixed, egui::DragValue::new(&mut range[1]).speed(step));
    });
    d.range = match (fixed, range[0] < range[1]) {
        (false, _) => None,
        (true, true) => Some(range),
        (true, false) => d.range.or(Some(d.effective_range())),
    };
}

/// Stick radius, background, projection, depth cue, ambient occlusion, outlines, shadows, stereo,
/// turntable (opacity and atom styles
/// are per representation, in [`surface_ui`]).
pub fn look_ui(ui: &mut egui::Ui, core: &AppCore) -> Vec<Command> {
    let mut out = Vec::new();
    ui.heading("Look");
    let mut s = core.render;
    ui.add(egui::Slider::new(&mut s.stick_radius, 0.05..=1.0).text("stick radius (Å)"));
    ui.horizontal(|ui| {
        ui.label("background");
        ui.selectable_value(&mut s.background, Background::Dark, "dark");
        ui.selectable_value(&mut s.background, Background::Light, "light");
    });
    ui.add(egui::Slider::new(&mut s.depth_cue, 0.0..=1.0).text("depth cue"));
    ui.add(egui::Slider::new(&mut s.ambient_occlusion, 0.0..=1.0).text("ambient occlusion"));
    ui.add(egui::Slider::new(&mut s.outline_width, 0.0..=4.0).text("outline (px)"));
    ui.add(egui::Slider::new(&mut s.shadows, 0.0..=1.0).text("shadows"));
    ui.add(
        egui::Slider::new(&mut s.samples, 1..=64)
            .logarithmic(true)
            .text("samples"),
    )
    .on_hover_text(
        "progressive samples: while the view is still the window adds one per repaint; \
         screenshots and movies draw them all",
    );
    egui::ComboBox::from_label("stereo")
        .selected_text(s.stereo.name())
        .show_ui(ui, |ui| {
            for m in Stereo::ALL {
                ui.selectable_value(&mut s.stereo, m, m.name());
            }
        });
    if s.stereo != Stereo::Off {
        ui.add(
            egui::Slider::new(&mut s.eye_separation, 0.0..=0.1)
                .text("eye separation (× focal distance)"),
        );
        ui.horizontal(|ui| {
            let mut fixed = s.focal_distance.is_some();
            let mut focal = s.focal_distance.unwrap_or(core.camera.distance);
            ui.checkbox(&mut fixed, "fixed focal distance (Å)")
                .on_hover_text("off: the zero-parallax plane follows the camera's target");
            if fixed {
                ui.add(egui::DragValue::new(&mut focal).range(1.0..=10000.0));
            }
            s.focal_distance = fixed.then_some(focal);
        });
    }
    if s != core.render {
        out.push(Command::SetRender(s));
    }
    ui.horizontal(|ui| {
        let mut ortho = core.camera.projection == Projection::Orthographic;
        if ui.checkbox(&mut ortho, "orthographic").changed() {
            out.push(Command::SetProjection(if ortho {
                Projection::Orthographic
            } else {
                Projection::Perspective
            }));
        }
        if ui.button("Reset view").clicked() {
            out.push(Command::ResetCamera);
        }
        if ui.button("Fit").clicked() {
            out.push(Command::FitCamera);
        }
    });
    ui.horizontal(|ui| {
        let mut on = core.turntable.is_some();
        let mut speed = core.turntable.unwrap_or(30.0);
        let a = ui.checkbox(&mut on, "turntable");
        let b = ui.add(
            egui::DragValue::new(&mut speed)
                .range(-360.0..=360.0)
                .suffix(" °/s"),
        );
        if a.changed() || b.changed() {
            out.push(Command::SetTurntable(on.then_some(speed)));
        }
    });
    out
}

/// One row of a readouts grid: a label and a monospaced value.
fn readout_row(ui: &mut egui::Ui, key: &str, value: String) {
    ui.label(key);
    ui.monospace(value);
    ui.end_row();
}

/// Per representation: atoms or beads, triangles, area, volume, grid and stage times; then the
/// frame's read time, render time and frame rate.
pub fn readouts_ui(ui: &mut egui::Ui, core: &AppCore, render_ms: f64, fps: f64) {
    ui.heading("Readouts");
    let Some(shown) = &core.shown else {
        ui.label(if core.source.is_some() {
            "computing…"
        } else {
            "no data"
        });
        return;
    };
    let c = &shown.computed;
    for l in &c.layers {
        ui.strong(format!("{} ({})", l.rep.name, l.rep.style));
        let t = &l.output.timings;
        egui::Grid::new(("readouts", l.id))
            .num_columns(2)
            .show(ui, |ui| {
                let mut row = |k: &str, v: String| readout_row(ui, k, v);
                row(
                    if l.beads { "beads" } else { "atoms" },
                    l.particles.positions.len().to_string(),
                );
                if l.is_surface() {
                    row("triangles", l.triangle_count().to_string());
                    row("area", format!("{:.1} Å²", l.output.area));
                    row("volume", format!("{:.1} Å³", l.output.volume));
                    let [x, y, z] = l.output.grid.dims;
                    row("grid", format!("{x}×{y}×{z}"));
                    if !l.reused {
                        row("binning", format!("{:.2} ms", t.bin_ms));
                        row("density", format!("{:.2} ms", t.density_ms));
                        row("marching cubes", format!("{:.2} ms", t.mc_ms));
                    }
                }
            });
    }
    ui.separator();
    egui::Grid::new("readouts-frame")
        .num_columns(2)
        .show(ui, |ui| {
            let mut row = |k: &str, v: String| readout_row(ui, k, v);
            row("triangles (all)", c.triangle_count().to_string());
            row("read", format!("{:.2} ms", c.read_ms));
            row("render", format!("{render_ms:.2} ms"));
            row("frames/s", format!("{fps:.1}"));
            row("engine", core.engine_name().to_string());
        });
    if core.computing() {
        ui.weak("computing…");
    }
}
