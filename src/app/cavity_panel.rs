//! The window's Cavities section: for the selected surface representation, a switch that finds
//! its cavities every frame ([`Representation::cavities`]; the view draws them in orange inside
//! the surface), the list of the shown frame's cavities with their tracked ids, and each id's
//! volume against frame.
//!
//! Tracking ([`CavityTracks`]) follows the frames in the order the window shows them: a frame
//! after the last one tracked (playing, stepping, or jumping forward) continues the tracks; the
//! same frame shown again (recomputed after a change that keeps the parameters) replaces its
//! own step; a frame before the last one (scrubbing or stepping back, a loop of playback)
//! starts the tracks again from it, with ids from 1. New parameters forget every track.
//!
//! [`Representation::cavities`]: crate::scene::representation::Representation::cavities

use std::collections::{BTreeMap, HashMap};

use crate::measure::{CavityTracker, TrackedCavity};
use crate::scene::SceneFrame;

use super::state::{AppCore, Command};

/// The tracks of one representation's cavities.
#[derive(Debug, Clone, Default)]
pub struct RepTracks {
    tracker: CavityTracker,
    /// The tracker as it was before the last frame's step (to redo that step).
    before_last: CavityTracker,
    /// The last frame tracked.
    last_frame: Option<usize>,
    /// The last frame's cavities with their ids, largest volume first.
    pub current: Vec<TrackedCavity>,
    /// Lining residue labels of each of `current`.
    pub lining: Vec<Vec<String>>,
    /// Volume in Å³ per cavity id, per frame.
    pub volumes: BTreeMap<u64, BTreeMap<usize, f64>>,
}

impl RepTracks {
    /// The last frame tracked.
    pub fn frame(&self) -> Option<usize> {
        self.last_frame
    }
}

/// Cavity tracks of every representation whose cavities are found, by representation id.
#[derive(Debug, Clone, Default)]
pub struct CavityTracks {
    reps: HashMap<u64, RepTracks>,
}

impl CavityTracks {
    /// Forgets every track (new parameters or a new system).
    pub fn clear(&mut self) {
        self.reps.clear();
    }

    /// The tracks of representation `id`, once one of its frames had cavities found.
    pub fn of(&self, id: u64) -> Option<&RepTracks> {
        self.reps.get(&id)
    }

    /// Takes in a shown frame: every layer whose cavities were found steps its tracks (see the
    /// module documentation); a layer shown without cavities forgets its tracks.
    pub fn record(&mut self, scene: &SceneFrame) {
        let frame = scene.frame;
        for layer in &scene.layers {
            let Some(found) = &layer.cavities else {
                self.reps.remove(&layer.id);
                continue;
            };
            let t = self.reps.entry(layer.id).or_default();
            match t.last_frame {
                Some(last) if last == frame => t.tracker = t.before_last.clone(),
                Some(last) if last > frame => *t = RepTracks::default(),
                _ => {}
            }
            t.before_last = t.tracker.clone();
            let update = t.tracker.update(frame, &found.cavities);
            for v in t.volumes.values_mut() {
                v.remove(&frame);
            }
            for c in &update.cavities {
                t.volumes
                    .entry(c.id)
                    .or_default()
                    .insert(frame, c.cavity.volume);
            }
            t.volumes.retain(|_, v| !v.is_empty());
            t.current = update.cavities;
            t.lining = found.lining.clone();
            t.last_frame = Some(frame);
        }
    }
}

/// Colour of cavity `id` in the list and the plot.
fn id_colour(id: u64) -> egui::Color32 {
    const PALETTE: [egui::Color32; 6] = [
        egui::Color32::from_rgb(255, 140, 40),
        egui::Color32::from_rgb(90, 170, 255),
        egui::Color32::from_rgb(120, 210, 110),
        egui::Color32::from_rgb(230, 90, 160),
        egui::Color32::from_rgb(200, 190, 70),
        egui::Color32::from_rgb(170, 130, 255),
    ];
    PALETTE[(id.saturating_sub(1) % PALETTE.len() as u64) as usize]
}

/// Lining residues shown per cavity in the list.
const LINING_SHOWN: usize = 3;

/// Draws the Cavities section for the selected representation; returns the switch's command.
pub fn cavity_ui(ui: &mut egui::Ui, core: &AppCore) -> Vec<Command> {
    let mut out = Vec::new();
    egui::CollapsingHeader::new("Cavities")
        .default_open(true)
        .show(ui, |ui| {
            let Some(rep) = core.reps.get(core.selected) else {
                ui.label("No representation.");
                return;
            };
            if !rep.style.is_surface() {
                ui.label("Cavities are found on surfaces.");
                return;
            }
            let mut on = rep.cavities;
            if ui
                .checkbox(&mut on, "Find cavities")
                .on_hover_text("Enclosed voids of the surface, every frame, drawn in orange")
                .changed()
            {
                let mut edited = rep.clone();
                edited.cavities = on;
                out.push(Command::UpdateRep(core.selected, Box::new(edited)));
            }
            if !rep.cavities {
                return;
            }
            let id = core.rep_ids.get(core.selected).copied();
            let Some(tracks) = id.and_then(|id| core.cavity_tracks.of(id)) else {
                ui.label("Finding cavities…");
                return;
            };
            list_ui(ui, tracks);
            volume_plot_ui(ui, tracks, core.timeline.current, core.timeline.len);
        });
    out
}

/// The shown frame's cavities: id, volume, area and lining residues.
fn list_ui(ui: &mut egui::Ui, tracks: &RepTracks) {
    let frame = tracks.frame().unwrap_or(0);
    ui.label(format!(
        "{} cavities in frame {frame} (at least {} Å³)",
        tracks.current.len(),
        crate::scene::cavity_layer::MIN_CAVITY_VOLUME_A3
    ));
    if tracks.current.is_empty() {
        return;
    }
    egui::Grid::new("cavity list")
        .striped(true)
        .num_columns(4)
        .show(ui, |ui| {
            for head in ["id", "volume Å³", "area Å²", "lining"] {
                ui.strong(head);
            }
            ui.end_row();
            for (k, c) in tracks.current.iter().enumerate() {
                ui.colored_label(id_colour(c.id), format!("#{}", c.id));
                ui.label(format!("{:.1}", c.cavity.volume));
                ui.label(format!("{:.1}", c.cavity.area));
                let labels = tracks.lining.get(k).map_or(&[][..], Vec::as_slice);
                let atoms = c.cavity.lining_atoms.len();
                let text = if labels.is_empty() {
                    format!("{atoms} atoms")
                } else {
                    let first = labels[..labels.len().min(LINING_SHOWN)].join(" ");
                    let more = if labels.len() > LINING_SHOWN {
                        " …"
                    } else {
                        ""
                    };
                    format!("{} res: {first}{more}", labels.len())
                };
                ui.label(text).on_hover_text(labels.join(" "));
                ui.end_row();
            }
        });
}

/// Volume (Å³) against frame for every cavity id tracked, on one scale, with the current frame
/// marked (the style of [`super::plot::plot_ui`]).
fn volume_plot_ui(ui: &mut egui::Ui, tracks: &RepTracks, current: usize, frames: usize) {
    let width = ui.available_width().max(120.0);
    let (painter, rect, x_of) = super::plot::frame_axes(ui, width, 90.0, current, frames);
    let hi = tracks
        .volumes
        .values()
        .flat_map(|v| v.values())
        .fold(0.0f64, |m, &v| m.max(v))
        .max(1e-9);
    let y_of = |v: f64| rect.bottom() - 4.0 - (rect.height() - 16.0) * (v / hi) as f32;
    for (&id, series) in &tracks.volumes {
        let colour = id_colour(id);
        let pts: Vec<egui::Pos2> = series
            .iter()
            .map(|(&f, &v)| egui::pos2(x_of(f), y_of(v)))
            .collect();
        if pts.len() == 1 {
            painter.circle_filled(pts[0], 2.5, colour);
        } else {
            painter.add(egui::Shape::line(pts, (1.5, colour)));
        }
    }
    painter.text(
        rect.left_top() + egui::vec2(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("volume (Å³), 0 … {hi:.0}"),
        egui::FontId::monospace(10.0),
        ui.visuals().text_color(),
    );
}
