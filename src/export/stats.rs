//! Per-frame statistics as CSV (`mdsurf surface --stats`): one row per computed frame, written to
//! a temporary file and renamed into place by [`StatsWriter::finish`]. A chunk of a job array
//! writes a part file whose first line records the run (see [`super::stats_merge`]).

use std::io::Write;
use std::path::Path;

use super::stats_merge::PartHeader;
use super::{AtomicFile, ExportError};
use crate::scene::SceneFrame;
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
    /// The rows of a computed frame, one per surface representation in its order; the first
    /// row's times include `read_ms`, the time it took to read the frame (ms).
    pub fn of_scene(scene: &SceneFrame, read_ms: f64) -> Vec<StatsRow> {
        scene
            .surfaces()
            .enumerate()
            .map(|(k, layer)| {
                let read_ms = if k == 0 { read_ms } else { 0.0 };
                let surface = &layer.output;
                StatsRow {
                    frame: scene.frame,
                    rep: layer.rep.name.clone(),
                    time_ps: scene.time_ps,
                    atoms: layer.particles.positions.len(),
                    dims: surface.grid.dims,
                    vertices: surface.vertex_count(),
                    triangles: surface.triangle_count(),
                    area: surface.area,
                    volume: surface.volume,
                    total_ms: layer.compute_ms + read_ms,
                    read_ms,
                    timings: surface.timings,
                }
            })
            .collect()
    }

    /// The row as CSV fields, in [`STATS_COLUMNS`] order.
    pub fn fields(&self) -> [String; 17] {
        self.fields_with(true)
    }

    /// The row as CSV fields; without `timings` the `ms_*` fields are empty (a file that two
    /// runs reproduce byte for byte).
    pub fn fields_with(&self, timings: bool) -> [String; 17] {
        let t = &self.timings;
        let ms = |v: f64| {
            if timings {
                format!("{v:.3}")
            } else {
                String::new()
            }
        };
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
            super::Fixed(self.area, 4).to_string(),
            super::Fixed(self.volume, 4).to_string(),
            ms(self.total_ms),
            ms(self.read_ms),
            ms(t.upload_ms),
            ms(t.bin_ms),
            ms(t.density_ms),
            ms(t.mc_ms),
        ]
    }
}

/// `text` as one CSV field: quoted (with doubled quotes) when it holds a comma, quote or newline.
pub(crate) fn csv_text(text: &str) -> String {
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
    timings: bool,
}

impl StatsWriter {
    /// Starts a CSV at `path` and writes its header.
    pub fn create(path: &Path) -> Result<StatsWriter, ExportError> {
        StatsWriter::create_with(path, None)
    }

    /// Starts a CSV at `path`; a chunk's part file first gets the line of its `part` header.
    pub fn create_with(path: &Path, part: Option<&PartHeader>) -> Result<StatsWriter, ExportError> {
        let mut file = AtomicFile::create(path)?;
        if let Some(part) = part {
            writeln!(file.writer(), "{}", part.line()).map_err(|e| ExportError::io(path, e))?;
        }
        writeln!(file.writer(), "{}", STATS_COLUMNS.join(","))
            .map_err(|e| ExportError::io(path, e))?;
        Ok(StatsWriter {
            file,
            rows: 0,
            timings: true,
        })
    }

    /// Whether the `ms_*` columns are written (default) or left empty, so that two runs give
    /// the same file byte for byte.
    pub fn set_timings(&mut self, timings: bool) {
        self.timings = timings;
    }

    /// Appends one row.
    pub fn write_row(&mut self, row: &StatsRow) -> Result<(), ExportError> {
        let line = row.fields_with(self.timings).join(",");
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
