//! The window's Cavities section: for the selected surface representation, a switch that finds
//! its cavities every frame ([`Representation::cavities`]; the view draws each inside the
//! surface in its id's colour), the list of the shown frame's cavities with their tracked ids,
//! each id's volume against frame, and the log of what happened to them (appeared, merged,
//! split off, gone), newest first. One colour per id everywhere ([`id_colour`], from
//! [`cavity_layer::cavity_srgb8`], the colour the view draws the id's wall in).
//!
//! Tracking ([`CavityTracks`]) follows the frames in the order the window shows them: a frame
//! after the last one tracked (playing, stepping, or jumping forward) continues the tracks; the
//! same frame shown again (recomputed after a change that keeps the parameters) replaces its
//! own step; a frame before the last one (scrubbing or stepping back, a loop of playback)
//! starts the tracks again from it, with ids from 1, and a new log. New parameters forget every
//! track.
//!
//! [`Representation::cavities`]: crate::scene::representation::Representation::cavities

use std::collections::{BTreeMap, HashMap, VecDeque};

use crate::measure::{CavityEvent, CavityTracker, TrackedCavity};
use crate::scene::SceneFrame;
use crate::scene::cavity_layer;

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
    /// The first frame of these tracks.
    first_frame: Option<usize>,
    /// The event log, newest first, at most [`EVENT_LOG_LINES`]: the frame, the id the line
    /// is about (its colour), the line.
    log: VecDeque<(usize, u64, String)>,
}

/// Lines of the event log kept per representation (the oldest go first).
pub const EVENT_LOG_LINES: usize = 200;

impl RepTracks {
    /// The last frame tracked.
    pub fn frame(&self) -> Option<usize> {
        self.last_frame
    }

    /// The event log, newest first: `frame 12: cavity 3 appeared (41.0 Å³)`, …
    pub fn log(&self) -> impl Iterator<Item = &str> {
        self.log.iter().map(|(_, _, line)| line.as_str())
    }

    /// Logs `frame`'s events (`previous`: the cavities of the frame before), newest first.
    fn log_frame(&mut self, frame: usize, previous: &[TrackedCavity], events: &[CavityEvent]) {
        let mut lines = Vec::new();
        if self.first_frame == Some(frame) {
            let n = self.current.len();
            let first = self.current.first().map_or(0, |c| c.id);
            let noun = if n == 1 { "cavity" } else { "cavities" };
            lines.push((first, format!("frame {frame}: tracking starts: {n} {noun}")));
        } else {
            for e in events {
                lines.push(event_line(frame, e, previous, &self.current));
            }
        }
        for (id, line) in lines.into_iter().rev() {
            self.log.push_front((frame, id, line));
        }
        self.log.truncate(EVENT_LOG_LINES);
    }
}

/// The volume of cavity `id` among `cavities`, as ` (41.0 Å³)` (empty when not there).
fn volume_of(cavities: &[TrackedCavity], id: u64, was: &str) -> String {
    cavities
        .iter()
        .find(|c| c.id == id)
        .map_or(String::new(), |c| {
            format!(" ({was}{:.1} Å³)", c.cavity.volume)
        })
}

/// `3`, `3 and 5`, `3, 5 and 7`.
fn id_list(ids: &[u64]) -> String {
    match ids {
        [] => String::new(),
        [one] => one.to_string(),
        [rest @ .., last] => {
            let rest: Vec<String> = rest.iter().map(u64::to_string).collect();
            format!("{} and {last}", rest.join(", "))
        }
    }
}

/// One line of the log for `event` at `frame` (`previous`, `current`: the cavities of the
/// frame before and of this one), with the id it is about.
fn event_line(
    frame: usize,
    event: &CavityEvent,
    previous: &[TrackedCavity],
    current: &[TrackedCavity],
) -> (u64, String) {
    match event {
        CavityEvent::Birth { id } => (
            *id,
            format!(
                "frame {frame}: cavity {id} appeared{}",
                volume_of(current, *id, "")
            ),
        ),
        CavityEvent::Death { id } => (
            *id,
            format!(
                "frame {frame}: cavity {id} gone{}",
                volume_of(previous, *id, "was ")
            ),
        ),
        CavityEvent::Merge { from, into } => {
            let mut ids = vec![*into];
            ids.extend(from);
            (
                *into,
                format!(
                    "frame {frame}: cavities {} merged into {into}{}",
                    id_list(&ids),
                    volume_of(current, *into, "")
                ),
            )
        }
        CavityEvent::Split { from, into } => {
            let noun = if into.len() == 1 {
                "cavity"
            } else {
                "cavities"
            };
            let first = into.first().copied().unwrap_or(*from);
            (
                first,
                format!(
                    "frame {frame}: {noun} {} split off from {from}",
                    id_list(into)
                ),
            )
        }
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
    /// module documentation) and logs its events, and its cavities take their tracked ids'
    /// colours ([`cavity_layer::with_cavity_ids`]); a layer shown without cavities forgets its
    /// tracks.
    pub fn record(&mut self, scene: &mut SceneFrame) {
        let frame = scene.frame;
        for layer in &mut scene.layers {
            let Some(found) = layer.cavities.clone() else {
                self.reps.remove(&layer.id);
                continue;
            };
            let t = self.reps.entry(layer.id).or_default();
            match t.last_frame {
                Some(last) if last == frame => {
                    t.tracker = t.before_last.clone();
                    while t.log.front().is_some_and(|(f, _, _)| *f == frame) {
                        t.log.pop_front();
                    }
                }
                Some(last) if last > frame => *t = RepTracks::default(),
                _ => {}
            }
            t.first_frame.get_or_insert(frame);
            t.before_last = t.tracker.clone();
            let update = t.tracker.update(frame, &found.cavities);
            let ids: Vec<u64> = update.cavities.iter().map(|c| c.id).collect();
            cavity_layer::with_cavity_ids(layer, &ids);
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
            let previous = t.before_last.current().to_vec();
            t.log_frame(frame, &previous, &update.events);
        }
    }
}

/// Colour of cavity `id` in the list, the plot and the log: the colour the view draws its wall
/// in ([`cavity_layer::cavity_srgb8`]).
pub fn id_colour(id: u64) -> egui::Color32 {
    let [r, g, b] = cavity_layer::cavity_srgb8(id);
    egui::Color32::from_rgb(r, g, b)
}

/// Lining residues shown per cavity in the list.
const LINING_SHOWN: usize = 3;

/// The probe radius (Å) of the panel's probe switch: a water molecule.
const WATER_PROBE_A: f32 = 1.4;

/// Draws the Cavities section for the selected representation; returns the switches' commands.
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
                .on_hover_text(
                    "Enclosed voids of the surface, every frame, each drawn in its id's colour",
                )
                .changed()
            {
                let mut edited = rep.clone();
                edited.cavities = on;
                out.push(Command::UpdateRep(core.selected, Box::new(edited)));
            }
            if !rep.cavities {
                return;
            }
            let mut probe = rep.cavity_probe.is_some();
            if ui
                .checkbox(&mut probe, "as a 1.4 Å probe finds them")
                .on_hover_text(
                    "The voids a water-sized probe fits in but cannot reach from outside, with \
                     Bondi radii, as MSMS finds them (pockets with a narrow mouth included); \
                     off: the enclosed voids of this surface",
                )
                .changed()
            {
                let mut edited = rep.clone();
                edited.cavity_probe = probe.then_some(WATER_PROBE_A);
                out.push(Command::UpdateRep(core.selected, Box::new(edited)));
            }
            let id = core.rep_ids.get(core.selected).copied();
            let Some(tracks) = id.and_then(|id| core.cavity_tracks.of(id)) else {
                ui.label("Finding cavities…");
                return;
            };
            list_ui(ui, tracks);
            volume_plot_ui(ui, tracks, core.timeline.current, core.timeline.len);
            log_ui(ui, tracks);
        });
    out
}

/// The event log, newest first, each line in the colour of the id it is about.
fn log_ui(ui: &mut egui::Ui, tracks: &RepTracks) {
    ui.label("Events, newest first");
    egui::ScrollArea::vertical()
        .id_salt("cavity events")
        .max_height(120.0)
        // Inside the side panel's own scroll area it would otherwise shrink to 64 points.
        .min_scrolled_height(120.0)
        .auto_shrink([false, true])
        .show(ui, |ui| {
            for (_, id, line) in &tracks.log {
                ui.colored_label(id_colour(*id), line);
            }
        });
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
        super::plot::draw_series(&painter, pts, colour);
    }
    painter.text(
        rect.left_top() + egui::vec2(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("volume (Å³), 0 … {hi:.0}"),
        egui::FontId::monospace(10.0),
        ui.visuals().text_color(),
    );
}
