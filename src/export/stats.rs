//! Per-frame statistics as CSV (`mdsurf surface --stats`): one row per computed frame, written to
//! a temporary file and renamed into place by [`StatsWriter::finish`].

use std::io::Write;
use std::path::Path;

use super::{AtomicFile, ExportError};
use crate::surface::StageTimings;

/// The CSV header columns, in order.
pub const STATS_COLUMNS: [&str; 17] = [
    "frame",
    "rep",
    "time_ps",
    "atoms",
    "nx",
    "ny",
    "nz",
    "vertices",
    "triangles",
    "area_A2",
    "volume_A3",
    "ms_total",
    "ms_read",
    "ms_upload",
    "ms_bin",
    "ms_density",
    "ms_mc",
];

/// Measurements of one frame's surface.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StatsRow {
    /// Frame index in the trajectory, from 0.
    pub frame: usize,
    /// Name of the surface representation (one row per frame and surface representation).
    pub rep: String,
    /// Simulation time in ps (empty in the CSV when the file has none).
    pub time_ps: Option<f64>,
    /// Number of particles the surface was built from (atoms or beads).
    pub atoms: usize,
    /// Grid samples along x, y, z.
    pub dims: [u32; 3],
    /// Mesh vertices.
    pub vertices: usize,
    /// Mesh triangles.
    pub triangles: usize,
    /// Surface area in Å².
    pub area: f64,
    /// Enclosed volume in Å³.
    pub volume: f64,
    /// Wall-clock time to read the frame and compute its surface, in ms.
    pub total_ms: f64,
    /// Time to read the frame from its file, in ms.
    pub read_ms: f64,
    /// The engine's per-stage times, in ms.
    pub timings: StageTimings,
}

impl StatsRow {
    /// The row as CSV fields, in [`STATS_COLUMNS`] order.
    pub fn fields(&self) -> [String; 17] {
        let t = &self.timings;
        [
            self.frame.to_string(),
            csv_text(&self.rep),
            self.time_ps.map(|t| format!("{t}")).unwrap_or_default(),
            self.atoms.to_string(),
            self.dims[0].to_string(),
            self.dims[1].to_string(),
            self.dims[2].to_string(),
            self.vertices.to_string(),
            self.triangles.to_string(),
            format!("{:.4}", self.area),
            format!("{:.4}", self.volume),
            format!("{:.3}", self.total_ms),
            format!("{:.3}", self.read_ms),
            format!("{:.3}", t.upload_ms),
            format!("{:.3}", t.bin_ms),
            format!("{:.3}", t.density_ms),
            format!("{:.3}", t.mc_ms),
        ]
    }
}

/// `text` as one CSV field: quoted (with doubled quotes) when it holds a comma, quote or newline.
fn csv_text(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// Writes a stats CSV atomically: rows go to a temporary file, [`StatsWriter::finish`] renames
/// it into place; dropping the writer unfinished leaves any existing file untouched.
pub struct StatsWriter {
    file: AtomicFile,
    rows: usize,
}

impl StatsWriter {
    /// Starts a CSV at `path` and writes its header.
    pub fn create(path: &Path) -> Result<StatsWriter, ExportError> {
        let mut file = AtomicFile::create(path)?;
        writeln!(file.writer(), "{}", STATS_COLUMNS.join(","))
            .map_err(|e| ExportError::io(path, e))?;
        Ok(StatsWriter { file, rows: 0 })
    }

    /// Appends one row.
    pub fn write_row(&mut self, row: &StatsRow) -> Result<(), ExportError> {
        let line = row.fields().join(",");
        writeln!(self.file.writer(), "{line}")
            .map_err(|e| ExportError::io(self.file.target(), e))?;
        self.rows += 1;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Renames the finished CSV into place.
    pub fn finish(self) -> Result<(), ExportError> {
        self.file.commit()
    }
}
