//! The window's Interface section: the area two selections bury against each other
//! ([`crate::scene::interface`], what `mdsurf surface --interface` computes), measured in the
//! background for each frame shown while it is switched on, with the shown frame's readout, its
//! contact residues and the buried area against frame. The surfaces take the selected
//! representation's parameters, or, with the probe switch, the 1.4 Å probe's solvent-excluded
//! surface (`--interface-probe 1.4`, MSMS's buried SES area). Changing a selection, the switch or
//! the file starts the table again. "Export CSV…" writes the measured frames as
//! `mdsurf surface --interface-csv` writes them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Duration;

use crate::export::ExportError;
use crate::export::atomic::write_atomic;
use crate::measure::{CONTACT_THRESHOLD, InterfaceCsv, Side};
use crate::scene::interface::Interface;

use super::state::AppCore;

/// The probe radius (Å) of the probe switch: water.
pub const WATER_PROBE: f32 = 1.4;

/// One measured frame.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceRow {
    /// Area of A alone, B alone, both together, and buried (Å²).
    pub area_a: f64,
    /// Area of B alone (Å²).
    pub area_b: f64,
    /// Area of A and B together (Å²).
    pub area_ab: f64,
    /// `(area_a + area_b - area_ab) / 2` (Å²).
    pub buried: f64,
    /// Contact residues of A, then of B, in topology order: label (`A:LEU23`) and the area it
    /// loses from alone to the complex (Å²).
    pub contacts: [Vec<(String, f64)>; 2],
    /// This frame's row of `mdsurf surface --interface-csv` (with its newline).
    pub csv_row: String,
}

/// What the section holds between frames.
pub struct InterfaceDraft {
    /// The first selection.
    pub selection_a: String,
    /// The second selection.
    pub selection_b: String,
    /// True: on the water probe's SES; false: on the Gaussian surface.
    pub probe: bool,
    /// True while frames are measured.
    pub on: bool,
    /// The measured frames.
    pub rows: BTreeMap<usize, InterfaceRow>,
    /// The last failure, one line (measuring stops until a setting changes).
    pub error: Option<String>,
    /// The settings and file the rows belong to.
    measured_for: Option<(String, String, bool, usize)>,
    /// The frame being measured and where its result comes.
    job: Option<(usize, Receiver<Result<InterfaceRow, String>>)>,
    /// Where the export dialog's answer comes, while it is open.
    export: Option<Receiver<Option<PathBuf>>>,
    /// What the last export did, one line.
    pub exported: Option<String>,
}

impl Default for InterfaceDraft {
    fn default() -> Self {
        InterfaceDraft {
            selection_a: "chain A".into(),
            selection_b: "chain B".into(),
            probe: false,
            on: false,
            rows: BTreeMap::new(),
            error: None,
            measured_for: None,
            job: None,
            export: None,
            exported: None,
        }
    }
}

impl InterfaceDraft {
    /// True while a frame is being measured.
    pub fn busy(&self) -> bool {
        self.job.is_some()
    }

    /// Writes the measured frames to `path` atomically, in frame order, as `mdsurf surface
    /// --interface-csv` writes them; returns how many. A file that cannot be written is left
    /// as it was.
    pub fn write_csv(&self, path: &Path) -> Result<usize, ExportError> {
        write_atomic(path, |w| {
            writeln!(w, "{}", InterfaceCsv::new().header())?;
            for row in self.rows.values() {
                w.write_all(row.csv_row.as_bytes())?;
            }
            Ok(())
        })?;
        Ok(self.rows.len())
    }

    /// Writes the rows where the export dialog says, once it has answered.
    fn finish_export(&mut self) {
        let Some(receiver) = &self.export else {
            return;
        };
        let answer = match receiver.try_recv() {
            Ok(answer) => answer,
            Err(TryRecvError::Empty) => return,
            Err(TryRecvError::Disconnected) => None,
        };
        self.export = None;
        if let Some(path) = answer {
            self.exported = Some(match self.write_csv(&path) {
                Ok(n) => format!("wrote {n} frame(s) to {}", path.display()),
                Err(e) => e.to_string(),
            });
        }
    }

    /// Takes a finished job's result, forgets the rows when the settings or the file changed,
    /// and starts measuring the shown frame when it has no row yet.
    fn advance(&mut self, core: &AppCore) {
        if let Some((frame, receiver)) = &self.job {
            match receiver.try_recv() {
                Ok(Ok(row)) => {
                    self.rows.insert(*frame, row);
                    self.job = None;
                }
                Ok(Err(line)) => {
                    self.error = Some(line);
                    self.job = None;
                }
                Err(TryRecvError::Empty) => return,
                Err(TryRecvError::Disconnected) => {
                    self.error = Some(format!("frame {frame}: the measurement stopped"));
                    self.job = None;
                }
            }
        }
        let Some(source) = core.source.clone() else {
            return;
        };
        let key = (
            self.selection_a.trim().to_string(),
            self.selection_b.trim().to_string(),
            self.probe,
            Arc::as_ptr(&source) as *const () as usize,
        );
        if self.measured_for.as_ref() != Some(&key) {
            self.rows.clear();
            self.error = None;
            self.measured_for = Some(key);
        }
        let frame = core.timeline.current;
        if !self.on || self.error.is_some() || self.rows.contains_key(&frame) {
            return;
        }
        let base = core
            .reps
            .get(core.selected)
            .cloned()
            .unwrap_or_else(|| core.base.clone());
        let overrides = core.radius_overrides.clone();
        let (a, b) = (self.selection_a.clone(), self.selection_b.clone());
        let probe = self.probe.then_some(WATER_PROBE);
        let (sender, receiver) = channel();
        std::thread::spawn(move || {
            let measured = (|| {
                let topology = source.topology();
                let mut sides = Interface::new(topology, [&a, &b], &base, &overrides, probe)
                    .map_err(|e| e.to_string())?;
                sides
                    .set_periodic(source.periodic().is_some())
                    .map_err(|e| e.to_string())?;
                let data = source.read_frame(frame).map_err(|e| e.to_string())?;
                let m = sides
                    .measure(topology, &data, CONTACT_THRESHOLD)
                    .map_err(|e| format!("frame {frame}: {e}"))?;
                let mut csv = InterfaceCsv::new();
                csv.push(frame, data.time_ps, topology, &m.result, &m.contacts);
                let labels = |side: Side| -> Vec<(String, f64)> {
                    m.contacts
                        .iter()
                        .filter(|c| c.side == side)
                        .map(|c| (c.residue.names(topology).label(), c.buried))
                        .collect()
                };
                Ok(InterfaceRow {
                    area_a: m.result.area_a,
                    area_b: m.result.area_b,
                    area_ab: m.result.area_complex,
                    buried: m.result.buried,
                    contacts: [labels(Side::A), labels(Side::B)],
                    csv_row: csv.rows().to_string(),
                })
            })();
            let _ = sender.send(measured);
        });
        self.job = Some((frame, receiver));
    }

    /// Waits up to `timeout` for the running measurement (for tests and scripts); true when
    /// none is left running.
    pub fn wait(&mut self, core: &AppCore, timeout: Duration) -> bool {
        let until = std::time::Instant::now() + timeout;
        self.advance(core);
        while self.busy() && std::time::Instant::now() < until {
            std::thread::sleep(Duration::from_millis(20));
            self.advance(core);
        }
        !self.busy()
    }
}

/// The Interface section.
pub fn interface_ui(ui: &mut egui::Ui, core: &AppCore, draft: &mut InterfaceDraft) {
    egui::CollapsingHeader::new("Interface")
        .default_open(true)
        .show(ui, |ui| interface_body(ui, core, draft));
}

/// The section's switches, readout and plot.
fn interface_body(ui: &mut egui::Ui, core: &AppCore, draft: &mut InterfaceDraft) {
    ui.checkbox(&mut draft.on, "Measure the buried area");
    for (name, text) in [("A", &mut draft.selection_a), ("B", &mut draft.selection_b)] {
        ui.horizontal(|ui| {
            let label = ui.label(name);
            let width = ui.available_width();
            ui.add(egui::TextEdit::singleline(text).desired_width(width))
                .labelled_by(label.id);
        });
    }
    ui.checkbox(
        &mut draft.probe,
        format!("on the {WATER_PROBE} Å probe's surface (as MSMS)"),
    );
    draft.advance(core);
    if let Some(line) = &draft.error {
        ui.colored_label(ui.visuals().error_fg_color, line);
    }
    if let Some((frame, _)) = &draft.job {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("measuring frame {frame}…"));
        });
        ui.ctx().request_repaint_after(Duration::from_millis(100));
    }
    let current = core.timeline.current;
    if let Some(row) = draft.rows.get(&current) {
        ui.label(format!(
            "frame {current}: buried {:.1} Å² (A {:.1}, B {:.1}, together {:.1} Å²)",
            row.buried, row.area_a, row.area_b, row.area_ab
        ));
        for (name, contacts) in ["A", "B"].iter().zip(&row.contacts) {
            ui.label(contacts_line(name, contacts));
        }
    }
    if !draft.rows.is_empty() {
        buried_plot(ui, &draft.rows, current, core.timeline.len);
    }
    draft.finish_export();
    let can_export = !draft.rows.is_empty() && draft.export.is_none();
    if ui
        .add_enabled(can_export, egui::Button::new("Export CSV…"))
        .on_hover_text("The measured frames, as mdsurf surface --interface-csv writes them")
        .clicked()
    {
        let (sender, receiver) = channel();
        let ctx = ui.ctx().clone();
        std::thread::spawn(move || {
            let path = rfd::FileDialog::new()
                .add_filter("CSV", &["csv"])
                .set_file_name("interface.csv")
                .save_file();
            let _ = sender.send(path);
            ctx.request_repaint();
        });
        draft.export = Some(receiver);
    }
    if let Some(line) = &draft.exported {
        ui.label(line);
    }
}

/// How many residues to name per side.
const NAMED_CONTACTS: usize = 12;

/// One side's contact residues, those that lose most first, each with the area it loses (Å²):
/// `21 contact residues of A (Å² lost): A:LYS353 63.4, A:HIS34 46.9, … and 9 more`.
pub fn contacts_line(side: &str, contacts: &[(String, f64)]) -> String {
    let mut ranked: Vec<&(String, f64)> = contacts.iter().collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    let named: Vec<String> = ranked
        .iter()
        .take(NAMED_CONTACTS)
        .map(|(label, lost)| format!("{label} {lost:.1}"))
        .collect();
    let more = contacts.len().saturating_sub(named.len());
    let tail = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    format!(
        "{} contact residues of {side} (Å² lost): {}{tail}",
        contacts.len(),
        named.join(", ")
    )
}

/// The buried area (Å²) against frame, the shown frame marked.
fn buried_plot(
    ui: &mut egui::Ui,
    rows: &BTreeMap<usize, InterfaceRow>,
    current: usize,
    frames: usize,
) {
    let colour = egui::Color32::from_rgb(120, 200, 120);
    let (painter, rect, x_of) =
        super::plot::frame_axes(ui, ui.available_width(), 80.0, current, frames);
    let (lo, hi) = rows.values().fold((f64::MAX, f64::MIN), |(lo, hi), r| {
        (lo.min(r.buried), hi.max(r.buried))
    });
    let span = (hi - lo).max(hi.abs() * 1e-6).max(1e-9);
    let points: Vec<egui::Pos2> = rows
        .iter()
        .map(|(&f, r)| egui::pos2(x_of(f), super::plot::y_between(rect, r.buried, lo, span)))
        .collect();
    super::plot::draw_series(&painter, points, colour);
    painter.text(
        rect.left_top() + egui::vec2(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("buried {lo:.0} … {hi:.0} Å²"),
        egui::FontId::monospace(10.0),
        colour,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contacts_are_named_most_buried_first_with_their_loss() {
        let contacts: Vec<(String, f64)> = (0..15)
            .map(|i| (format!("A:GLY{i}"), f64::from(i) * 2.5))
            .collect();
        let line = contacts_line("A", &contacts);
        assert!(
            line.starts_with("15 contact residues of A (Å² lost): A:GLY14 35.0, A:GLY13 32.5, "),
            "{line}"
        );
        assert!(line.ends_with("A:GLY3 7.5 and 3 more"), "{line}");
        assert_eq!(
            contacts_line("B", &contacts[1..3]),
            "2 contact residues of B (Å² lost): A:GLY2 5.0, A:GLY1 2.5"
        );
    }
}
