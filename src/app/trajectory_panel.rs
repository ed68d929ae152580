//! The Trajectory section of the window's side panel: the per-frame transformations (make
//! whole, centre, fit, smooth; see [`crate::transform`]) and the periodic surface (with its
//! replicated images), as the command line's flags set them.
//! Edits are a draft until Apply, which reloads the files with the new transformations (the
//! representations stay).

use crate::surface::periodic::MAX_REPLICATE;
use crate::transform::{FitReference, MAX_SMOOTH, Replicate, TransformOptions};

/// The transformations in use and the section's unapplied edits.
#[derive(Debug, Clone, Default)]
pub struct TransformDraft {
    applied: TransformOptions,
    whole: Option<bool>,
    center_on: bool,
    center: String,
    fit_on: bool,
    fit: String,
    fit_reference: FitReference,
    smooth: usize,
    periodic: bool,
    replicate: [u32; 3],
    /// A reload with `applied` is due (set by Apply or a state file).
    reload: bool,
}

impl TransformDraft {
    /// A draft showing `options`, which are in use.
    pub fn new(options: TransformOptions) -> TransformDraft {
        TransformDraft {
            whole: options.whole,
            center_on: options.center.is_some(),
            center: options.center.clone().unwrap_or_else(|| "protein".into()),
            fit_on: options.fit.is_some(),
            fit: options
                .fit
                .clone()
                .unwrap_or_else(|| "protein and name CA".into()),
            fit_reference: options.fit_reference,
            smooth: options.smooth,
            periodic: options.periodic,
            replicate: options.replicate.0,
            applied: options,
            reload: false,
        }
    }

    /// The transformations in use.
    pub fn applied(&self) -> &TransformOptions {
        &self.applied
    }

    /// Asks for the files to be reloaded with the transformations in use.
    pub fn request_reload(&mut self) {
        self.reload = true;
    }

    /// True once when a reload is due.
    pub fn take_reload(&mut self) -> bool {
        std::mem::take(&mut self.reload)
    }

    fn edited(&self) -> TransformOptions {
        let text = |on: bool, s: &str| (on && !s.trim().is_empty()).then(|| s.trim().to_string());
        TransformOptions {
            whole: self.whole,
            center: text(self.center_on, &self.center),
            fit: text(self.fit_on, &self.fit),
            fit_reference: self.fit_reference,
            smooth: self.smooth,
            periodic: self.periodic,
            replicate: if self.periodic {
                Replicate(self.replicate)
            } else {
                Replicate::default()
            },
        }
    }
}

/// Draws the Trajectory section; returns true when the files should be reloaded with
/// [`TransformDraft::applied`] (Apply pressed, or a reload requested elsewhere).
pub fn trajectory_ui(ui: &mut egui::Ui, draft: &mut TransformDraft) -> bool {
    egui::CollapsingHeader::new("Trajectory")
        .default_open(false)
        .show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.label("Make whole");
                ui.selectable_value(&mut draft.whole, None, "auto")
                    .on_hover_text("On when the file has a box and bonds or residues");
                ui.selectable_value(&mut draft.whole, Some(true), "on");
                ui.selectable_value(&mut draft.whole, Some(false), "off");
            });
            ui.horizontal(|ui| {
                let label = ui
                    .checkbox(&mut draft.center_on, "Centre")
                    .on_hover_text("Put this selection's centre at the box centre");
                ui.add_enabled(
                    draft.center_on,
                    egui::TextEdit::singleline(&mut draft.center).desired_width(140.0),
                )
                .labelled_by(label.id);
            });
            ui.horizontal(|ui| {
                let label = ui
                    .checkbox(&mut draft.fit_on, "Fit")
                    .on_hover_text("Superpose every frame on the reference (least squares)");
                ui.add_enabled(
                    draft.fit_on,
                    egui::TextEdit::singleline(&mut draft.fit).desired_width(140.0),
                )
                .labelled_by(label.id);
            });
            ui.add_enabled_ui(draft.fit_on, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Fit onto");
                    ui.selectable_value(
                        &mut draft.fit_reference,
                        FitReference::First,
                        "first frame",
                    );
                    ui.selectable_value(
                        &mut draft.fit_reference,
                        FitReference::Topology,
                        "topology",
                    );
                });
            });
            ui.add(
                egui::Slider::new(&mut draft.smooth, 0..=MAX_SMOOTH.min(20))
                    .text("smooth ± frames"),
            );
            ui.checkbox(&mut draft.periodic, "Periodic surface")
                .on_hover_text(
                    "Gaussians reach across the box faces: no walls at the faces; area and \
                     volume per cell (any box, triclinic too; computed on the CPU)",
                );
            ui.add_enabled_ui(draft.periodic, |ui| {
                ui.horizontal(|ui| {
                    ui.label("Images");
                    for (n, axis) in draft.replicate.iter_mut().zip(["x", "y", "z"]) {
                        ui.add(
                            egui::DragValue::new(n)
                                .range(1..=MAX_REPLICATE)
                                .prefix(format!("{axis} ")),
                        )
                        .on_hover_text("Copies of the box side by side along this axis");
                    }
                });
            });
            let edited = draft.edited();
            let changed = edited != draft.applied;
            if ui
                .add_enabled(changed, egui::Button::new("Apply"))
                .on_hover_text("Reload the files with these transformations")
                .clicked()
            {
                draft.applied = edited;
                draft.reload = true;
            }
        });
    draft.take_reload()
}
