//! The side panels: surface parameters with the grid estimate ([`surface_ui`]), the look of the
//! picture ([`look_ui`]) and live readouts ([`readouts_ui`]). Each returns [`Command`]s; nothing
//! here changes the app's state directly.

use super::state::{AppCore, Command};
use crate::model::ColorScheme;
use crate::render::{AtomStyle, Background, Projection, Stereo};
use crate::surface::{Quality, SurfaceParams};

/// Parameters being edited (they become the app's parameters only when the grid fits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceDraft {
    /// The edited parameters.
    pub params: SurfaceParams,
}

fn megabytes(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.2} GB", bytes as f64 / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MB", bytes as f64 / (1u64 << 20) as f64)
    }
}

/// Sliders for H, R, I, quality, the bead toggle and colour scheme; the grid the edited values
/// would need (dims, voxels, memory) is shown before it is applied, and a grid above the limit
/// is refused (the previous surface stays).
pub fn surface_ui(ui: &mut egui::Ui, core: &AppCore, draft: &mut SurfaceDraft) -> Vec<Command> {
    let mut out = Vec::new();
    ui.heading("Surface");
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
    match core.grid_estimate(p) {
        Some((grid, bytes)) => {
            let [x, y, z] = grid.dims;
            ui.label(format!(
                "grid {x}×{y}×{z} = {:.2} M voxels, {}",
                grid.voxel_count() as f64 / 1e6,
                megabytes(bytes)
            ));
            if bytes > core.grid_limit_bytes {
                ui.colored_label(
                    ui.visuals().error_fg_color,
                    format!(
                        "refused: needs {} > limit {}; raise H",
                        megabytes(bytes),
                        megabytes(core.grid_limit_bytes)
                    ),
                );
            } else if *p != core.params {
                out.push(Command::SetParams(*p));
            }
        }
        None if *p != core.params => out.push(Command::SetParams(*p)),
        None => {}
    }
    if ui.button("Defaults").clicked() {
        *p = SurfaceParams::default();
    }
    let mut beads = core.options.beads;
    if ui.checkbox(&mut beads, "beads: one per residue").changed() {
        out.push(Command::SetBeads(beads));
    }
    let current = core.options.colours;
    let mut scheme = current;
    egui::ComboBox::from_label("colour")
        .selected_text(scheme.to_string())
        .show_ui(ui, |ui| {
            for s in [
                ColorScheme::Element,
                ColorScheme::Chain,
                ColorScheme::ResidueType,
                ColorScheme::ResidueIndex,
                ColorScheme::BFactor,
                ColorScheme::Single([0.8, 0.8, 0.8]),
            ] {
                let name = if let ColorScheme::Single(_) = s {
                    "single colour".to_string()
                } else {
                    s.to_string()
                };
                let selected = std::mem::discriminant(&scheme) == std::mem::discriminant(&s);
                if ui.selectable_label(selected, name).clicked() && !selected {
                    scheme = s;
                }
            }
        });
    if let ColorScheme::Single(c) = &mut scheme {
        ui.horizontal(|ui| {
            ui.label("surface colour");
            ui.color_edit_button_rgb(c);
        });
    }
    if scheme != current {
        out.push(Command::SetColours(scheme));
    }
    out
}

/// Opacity, atoms, background, projection, depth cue, stereo, turntable.
pub fn look_ui(ui: &mut egui::Ui, core: &AppCore) -> Vec<Command> {
    let mut out = Vec::new();
    ui.heading("Look");
    let mut s = core.render;
    ui.checkbox(&mut s.show_surface, "surface");
    ui.add(egui::Slider::new(&mut s.surface_opacity, 0.0..=1.0).text("opacity"));
    egui::ComboBox::from_label("atoms")
        .selected_text(s.atom_style.name())
        .show_ui(ui, |ui| {
            for a in AtomStyle::ALL {
                ui.selectable_value(&mut s.atom_style, a, a.name());
            }
        });
    if s.atom_style != AtomStyle::Hidden {
        ui.add(egui::Slider::new(&mut s.stick_radius, 0.05..=1.0).text("stick radius (Å)"));
    }
    ui.horizontal(|ui| {
        ui.label("background");
        ui.selectable_value(&mut s.background, Background::Dark, "dark");
        ui.selectable_value(&mut s.background, Background::Light, "light");
    });
    ui.add(egui::Slider::new(&mut s.depth_cue, 0.0..=1.0).text("depth cue"));
    ui.add(egui::Slider::new(&mut s.ambient_occlusion, 0.0..=1.0).text("ambient occlusion"));
    egui::ComboBox::from_label("stereo")
        .selected_text(s.stereo.name())
        .show_ui(ui, |ui| {
            for m in Stereo::ALL {
                ui.selectable_value(&mut s.stereo, m, m.name());
            }
        });
    if s.stereo != Stereo::Off {
        ui.add(egui::Slider::new(&mut s.eye_separation, 0.0..=0.15).text("eye separation"));
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

/// Atoms or beads, triangles, area, volume, stage times and frame rate.
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
    let t = &c.output.timings;
    egui::Grid::new("readouts").num_columns(2).show(ui, |ui| {
        let mut row = |k: &str, v: String| {
            ui.label(k);
            ui.monospace(v);
            ui.end_row();
        };
        row(
            if c.beads { "beads" } else { "atoms" },
            c.particles.positions.len().to_string(),
        );
        row("triangles", c.triangle_count().to_string());
        row("area", format!("{:.1} Å²", c.output.area));
        row("volume", format!("{:.1} Å³", c.output.volume));
        let [x, y, z] = c.output.grid.dims;
        row("grid", format!("{x}×{y}×{z}"));
        row("read", format!("{:.2} ms", c.read_ms));
        row("binning", format!("{:.2} ms", t.bin_ms));
        row("density", format!("{:.2} ms", t.density_ms));
        row("marching cubes", format!("{:.2} ms", t.mc_ms));
        row("render", format!("{render_ms:.2} ms"));
        row("frames/s", format!("{fps:.1}"));
        row("engine", core.engine_name().to_string());
    });
    if core.computing() {
        ui.weak("computing…");
    }
}
