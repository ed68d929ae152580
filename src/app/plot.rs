//! Area and volume against frame for the frames computed so far with the current parameters,
//! one line per surface representation: the [`History`], a small line plot drawn with egui's
//! painter ([`plot_ui`]), and CSV export.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use super::state::Command;

/// Area (Å²) and volume (Å³) per frame index and surface representation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct History {
    /// Representation names in the order they were first recorded.
    reps: Vec<String>,
    /// (frame, representation index in `reps`) -> (area, volume).
    values: BTreeMap<(usize, usize), (f64, f64)>,
}

impl History {
    /// Forgets everything (parameters changed).
    pub fn clear(&mut self) {
        self.values.clear();
        self.reps.clear();
    }

    /// Records frame `frame`'s area (Å²) and volume (Å³) of representation `rep`.
    pub fn record(&mut self, frame: usize, rep: &str, area: f64, volume: f64) {
        let r = match self.reps.iter().position(|n| n == rep) {
            Some(r) => r,
            None => {
                self.reps.push(rep.to_string());
                self.reps.len() - 1
            }
        };
        self.values.insert((frame, r), (area, volume));
    }

    /// Number of frames recorded (for any representation).
    pub fn len(&self) -> usize {
        let mut frames: Vec<usize> = self.values.keys().map(|k| k.0).collect();
        frames.dedup();
        frames.len()
    }

    /// True when nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The representations recorded, in first-recorded order.
    pub fn reps(&self) -> &[String] {
        &self.reps
    }

    /// (frame, representation, area Å², volume Å³), in frame order, then representation order.
    pub fn rows(&self) -> impl Iterator<Item = (usize, &str, f64, f64)> + '_ {
        self.values
            .iter()
            .map(|(&(f, r), &(a, v))| (f, self.reps[r].as_str(), a, v))
    }

    /// (frame, area, volume) of representation `rep`, in frame order.
    pub fn series<'a>(&'a self, rep: &'a str) -> impl Iterator<Item = (usize, f64, f64)> + 'a {
        self.rows()
            .filter(move |(_, r, _, _)| *r == rep)
            .map(|(f, _, a, v)| (f, a, v))
    }

    /// The history as CSV text: a header line, then `frame,rep,area_A2,volume_A3` rows.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("frame,rep,area_A2,volume_A3\n");
        for (f, r, a, v) in self.rows() {
            let r = if r.contains([',', '"']) {
                format!("\"{}\"", r.replace('"', "\"\""))
            } else {
                r.to_string()
            };
            s.push_str(&format!("{f},{r},{a:.4},{v:.4}\n"));
        }
        s
    }

    /// Writes [`History::to_csv`] to `path` atomically (temporary file, then rename).
    pub fn write_csv(&self, path: &Path) -> Result<(), CsvWriteError> {
        let err = |source: std::io::Error| CsvWriteError {
            path: path.to_path_buf(),
            source,
        };
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(err)?;
        tmp.write_all(self.to_csv().as_bytes()).map_err(err)?;
        tmp.persist(path).map_err(|e| err(e.error))?;
        Ok(())
    }
}

/// The history's CSV could not be written; prints as one line naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct CsvWriteError {
    /// The CSV file.
    pub path: std::path::PathBuf,
    /// What the operating system said.
    pub source: std::io::Error,
}

/// Draws area and volume (each scaled to its own range) against frame, with the current frame
/// marked, and a CSV export button.
pub fn plot_ui(
    ui: &mut egui::Ui,
    history: &History,
    current: usize,
    frames: usize,
) -> Vec<Command> {
    let mut out = Vec::new();
    ui.horizontal(|ui| {
        ui.colored_label(AREA, "— area (Å²)");
        ui.colored_label(VOLUME, "— volume (Å³)");
        ui.label(format!("{} frames", history.len()));
        if ui
            .add_enabled(!history.is_empty(), egui::Button::new("Export CSV…"))
            .clicked()
        {
            out.push(Command::ExportCsv(None));
        }
    });
    let (painter, rect, x_of) = frame_axes(ui, ui.available_width(), 110.0, current, frames);
    let lines = history.reps().iter().enumerate().flat_map(|(k, rep)| {
        let fade = |c: egui::Color32| c.gamma_multiply(1.0 / (1.0 + k as f32 * 0.6));
        [(0, fade(AREA), rep), (1, fade(VOLUME), rep)]
    });
    for (line, (series, colour, rep)) in lines.enumerate() {
        let vals: Vec<(usize, f64)> = history
            .series(rep)
            .map(|(f, a, v)| (f, if series == 0 { a } else { v }))
            .collect();
        let (lo, hi) = vals.iter().fold((f64::MAX, f64::MIN), |(lo, hi), (_, v)| {
            (lo.min(*v), hi.max(*v))
        });
        let span = (hi - lo).max(hi.abs() * 1e-6).max(1e-9);
        let pts: Vec<egui::Pos2> = vals
            .iter()
            .map(|&(f, v)| egui::pos2(x_of(f), y_between(rect, v, lo, span)))
            .collect();
        draw_series(&painter, pts, colour);
        if !vals.is_empty() {
            let text = format!("{rep}: {lo:.0} … {hi:.0}");
            let row = (line / 2) as f32 * 12.0;
            let at = if series == 0 {
                rect.left_top() + egui::vec2(0.0, row)
            } else {
                rect.left_bottom() - egui::vec2(0.0, 14.0 + row)
            };
            painter.text(
                at + egui::vec2(4.0, 2.0),
                egui::Align2::LEFT_TOP,
                text,
                egui::FontId::monospace(10.0),
                colour,
            );
        }
    }
    out
}

const AREA: egui::Color32 = egui::Color32::from_rgb(90, 170, 255);
const VOLUME: egui::Color32 = egui::Color32::from_rgb(255, 160, 60);

/// The y (px) of `value` in `rect` when values `lo` to `lo + span` fill its height, 6 px kept
/// free at the top and bottom.
pub(crate) fn y_between(rect: egui::Rect, value: f64, lo: f64, span: f64) -> f32 {
    rect.bottom() - 6.0 - (rect.height() - 12.0) * ((value - lo) / span) as f32
}

/// Draws one series of a plot (screen positions): a dot when it has one point, else a line.
pub(crate) fn draw_series(painter: &egui::Painter, points: Vec<egui::Pos2>, colour: egui::Color32) {
    if points.len() == 1 {
        painter.circle_filled(points[0], 2.5, colour);
    } else {
        painter.add(egui::Shape::line(points, (1.5, colour)));
    }
}

/// The frame of a plot over frames: `height` px tall and `width` px wide, the background
/// filled and the `current` frame of `frames` marked by a vertical line. Returns the painter,
/// the plot's rectangle and the x of a frame.
pub(crate) fn frame_axes(
    ui: &mut egui::Ui,
    width: f32,
    height: f32,
    current: usize,
    frames: usize,
) -> (egui::Painter, egui::Rect, impl Fn(usize) -> f32 + use<>) {
    let size = egui::vec2(width, height);
    let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    let x_of = move |f: usize| {
        rect.left() + rect.width() * f as f32 / frames.saturating_sub(1).max(1) as f32
    };
    let x = x_of(current);
    painter.line_segment(
        [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
        (1.0, egui::Color32::GRAY),
    );
    (painter, rect, x_of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_has_header_and_rows_in_frame_order() {
        let mut h = History::default();
        h.record(3, "protein", 10.0, 20.5);
        h.record(1, "protein", 1.0, 2.0);
        h.record(1, "lipids", 5.0, 6.0);
        assert_eq!(
            h.to_csv(),
            "frame,rep,area_A2,volume_A3\n1,protein,1.0000,2.0000\n1,lipids,5.0000,6.0000\n3,protein,10.0000,20.5000\n"
        );
        assert_eq!(h.len(), 2);
        assert_eq!(h.series("lipids").count(), 1);
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("h.csv");
        h.write_csv(&p).expect("write");
        assert_eq!(std::fs::read_to_string(&p).expect("read"), h.to_csv());
    }
}
