//! Our Amber NetCDF trajectory reader (the AMBER convention on classic NetCDF, CDF-1 and
//! CDF-2): `coordinates (frame, atom, spatial)` in Å, `cell_lengths`/`cell_angles` for the box,
//! `time (frame)` in ps, with `scale_factor` and `units` attributes applied. The header is
//! parsed by `header` (bounded by the file size); frames are record-variable slices read at
//! computed offsets. A file announcing more frames than it holds (or a streaming file, whose
//! header says -1) keeps the frames it holds whole, and the cut one is the damage. A file with
//! no `coordinates` (sander's velocity-only `mdvel`) is refused, not read as atoms at 0.
//!
//! Differences from chemfiles (on purpose): the `time` variable is read (chemfiles gives no
//! time), nanometre coordinates are scaled by 10 (chemfiles uses 10⁴), and `Conventions` may
//! list AMBER among others.
//!
//! Over HTTP ([`Bytes::Remote`]) only the header is read when the file opens (record variables
//! lie at computed offsets), then the slices of each frame read.
//!
//! Errors are [`NetcdfError`]s, wrapped in an [`IoError`] naming the file (and frame).

mod error;
mod header;

use std::path::Path;

use glam::Vec3;

use self::error::NetcdfError;
use self::header::{Header, HeaderError, NcType, Value, Variable};
use super::IoError;
use super::native::NativeOpen;
use super::positioned::Positioned;
use super::positioned_frames::{Bytes, FrameDecoder, PositionedFrames};
use super::unit_cell;
use crate::model::Frame;

/// Headers are read in pieces of this many bytes, growing until they parse.
const HEADER_CHUNK: u64 = 1 << 16;

/// A header larger than this is damage (real headers are a few kB).
const MAX_HEADER: u64 = 1 << 26;

/// One record variable we read: where record 0 of it starts, its type and values per record,
/// and the factor to Å (or degrees, or ps).
#[derive(Debug, Clone, Copy)]
struct Slice {
    begin: u64,
    kind: NcType,
    values: u64,
    scale: f64,
}

impl Slice {
    fn bytes(&self) -> u64 {
        self.values * self.kind.size()
    }
}

/// Opens the Amber NetCDF file `path` (a local file, or a URL read through range requests:
/// then only the header is read here) and indexes its frames.
pub(crate) fn open(path: &Path, bytes: Bytes) -> Result<NativeOpen, IoError> {
    let (file, total, prepared) = bytes.open(path)?;
    let header = read_header(&file, total).map_err(|e| IoError::unreadable(path, e))?;
    let layout = Layout::new(&header, total).map_err(|e| match e {
        NetcdfError::FirstFrameCut { .. } => IoError::bad_frame(path, 0, e),
        e => IoError::unreadable(path, e),
    })?;
    let (len, damage) = layout.count_frames(header.records, total);
    let decoder = NetcdfDecoder {
        layout,
        buffer: Vec::new(),
    };
    PositionedFrames::open(
        path,
        (file, prepared),
        len,
        damage,
        decoder,
        NetcdfError::NoFrames,
    )
}

/// Reads and parses the header, reading more of the file while it needs more.
fn read_header(file: &Positioned, total: u64) -> Result<Header, NetcdfError> {
    let mut bytes = Vec::new();
    let mut want = HEADER_CHUNK.min(total);
    loop {
        // `want` is at most the file size (and `MAX_HEADER`).
        bytes.resize(want as usize, 0);
        file.read_exact_at(&mut bytes, 0)?;
        match header::parse(&bytes, total) {
            Ok(header) => return Ok(header),
            Err(HeaderError::Damaged(reason)) => return Err(reason),
            Err(HeaderError::NeedMore) if want < total.min(MAX_HEADER) => {
                want = (want * 4).min(total).min(MAX_HEADER);
            }
            Err(HeaderError::NeedMore) => {
                return Err(NetcdfError::HeaderTooLarge { limit: MAX_HEADER });
            }
        }
    }
}

/// Where each frame's data lies.
#[derive(Debug, Clone)]
struct Layout {
    atoms: usize,
    /// Bytes from one record to the next.
    record_bytes: u64,
    /// Where the first record starts (the lowest `begin` of the record variables).
    records_begin: u64,
    coordinates: Slice,
    cell: Option<(Slice, Slice)>,
    time: Option<Slice>,
}

/// The text of attribute `value`, if it is text.
fn text(value: Option<&Value>) -> Option<&str> {
    match value {
        Some(Value::Text(t)) => Some(t.as_str()),
        _ => None,
    }
}

/// Å per unit of a distance unit named `units`.
fn distance_scale(units: &str) -> Result<f64, NetcdfError> {
    Ok(match units.trim().to_ascii_lowercase().as_str() {
        "" | "angstrom" | "angstroms" | "a" => 1.0,
        "nanometer" | "nanometers" | "nm" => 10.0,
        "bohr" | "bohrs" => 0.529_177_210_9,
        "meter" | "meters" | "m" => 1e10,
        other => return Err(NetcdfError::UnknownUnit(other.to_string())),
    })
}

impl Layout {
    fn new(header: &Header, total: u64) -> Result<Layout, NetcdfError> {
        let conventions = text(header.attribute("Conventions")).unwrap_or("");
        let names: Vec<&str> = conventions
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        if names.contains(&"AMBERRESTART") {
            return Err(NetcdfError::Restart);
        }
        if !names.contains(&"AMBER") {
            return Err(NetcdfError::NotAmber(conventions.to_string()));
        }
        let record_dim = header
            .dimension("frame")
            .filter(|&d| header.dimensions[d].len == 0)
            .ok_or(NetcdfError::NoRecordDimension)?;
        let atom_dim = header
            .dimension("atom")
            .ok_or(NetcdfError::MissingDimension("atom"))?;
        let atoms = header.dimensions[atom_dim].len;
        let Some(coordinates) = header.variable("coordinates") else {
            return Err(if header.variable("velocities").is_some() {
                NetcdfError::VelocitiesOnly
            } else {
                NetcdfError::MissingVariable("coordinates")
            });
        };
        let dims = |v: &Variable| -> Vec<&str> {
            v.dimensions
                .iter()
                .map(|&d| header.dimensions[d].name.as_str())
                .collect()
        };
        let is_real = |v: &Variable| matches!(v.kind, NcType::Float | NcType::Double);
        if dims(coordinates) != ["frame", "atom", "spatial"] || !is_real(coordinates) {
            return Err(NetcdfError::BadCoordinates {
                kind: coordinates.kind,
                dimensions: dims(coordinates).into_iter().map(String::from).collect(),
            });
        }
        let spatial = header.dimensions[coordinates.dimensions[2]].len;
        if spatial != 3 {
            return Err(NetcdfError::BadDimension {
                name: "spatial",
                value: spatial,
            });
        }
        // Bytes of one record of every record variable (each padded to 4 bytes unless it is
        // the only one).
        let per_record = |v: &Variable| -> Result<u64, NetcdfError> {
            let bytes = v.dimensions[1..]
                .iter()
                .try_fold(v.kind.size(), |acc, &d| {
                    acc.checked_mul(header.dimensions[d].len)
                })
                .ok_or_else(|| NetcdfError::RecordTooLarge {
                    variable: v.name.clone(),
                    file_len: total,
                })?;
            if bytes > total {
                // A record larger than the file: where the header promises frames, the file
                // ends inside frame 0.
                return Err(match header.records {
                    Some(0) => NetcdfError::RecordTooLarge {
                        variable: v.name.clone(),
                        file_len: total,
                    },
                    _ => NetcdfError::FirstFrameCut {
                        variable: v.name.clone(),
                        bytes,
                        file_len: total,
                    },
                });
            }
            Ok(bytes)
        };
        let record_vars: Vec<&Variable> = header
            .variables
            .iter()
            .filter(|v| v.dimensions.first() == Some(&record_dim))
            .collect();
        let mut record_bytes = 0u64;
        for v in &record_vars {
            let bytes = per_record(v)?;
            let padded = if record_vars.len() == 1 {
                bytes
            } else {
                bytes.div_ceil(4) * 4
            };
            record_bytes = record_bytes.saturating_add(padded);
        }
        let records_begin = record_vars.iter().map(|v| v.begin).min().unwrap_or(0);
        let slice = |v: &Variable, scale: f64| -> Result<Slice, NetcdfError> {
            let values = per_record(v)? / v.kind.size();
            let factor = match v.attribute("scale_factor") {
                None => 1.0,
                Some(Value::Numbers(NcType::Float | NcType::Double, n)) if n.len() == 1 => n[0],
                Some(_) => return Err(NetcdfError::BadScaleFactor(v.name.clone())),
            };
            Ok(Slice {
                begin: v.begin,
                kind: v.kind,
                values,
                scale: factor * scale,
            })
        };
        let units = |v: &Variable| text(v.attribute("units")).unwrap_or("").to_string();
        let coordinates = slice(coordinates, distance_scale(&units(coordinates))?)?;
        let cell = match (
            header.variable("cell_lengths"),
            header.variable("cell_angles"),
        ) {
            (Some(lengths), Some(angles)) => {
                for (v, dim) in [(lengths, "cell_spatial"), (angles, "cell_angular")] {
                    let d = dims(v);
                    if d.len() != 2 || d[0] != "frame" || d[1] != dim || !is_real(v) {
                        return Err(NetcdfError::BadCellVariable {
                            variable: v.name.clone(),
                            dimension: dim,
                        });
                    }
                    if header.dimensions[v.dimensions[1]].len != 3 {
                        return Err(NetcdfError::BadCellDimension(dim));
                    }
                }
                let angle_scale = match units(angles).trim().to_ascii_lowercase().as_str() {
                    "radian" | "radians" => 180.0 / std::f64::consts::PI,
                    _ => 1.0,
                };
                Some((
                    slice(lengths, distance_scale(&units(lengths))?)?,
                    slice(angles, angle_scale)?,
                ))
            }
            (None, None) => None,
            _ => return Err(NetcdfError::HalfCell),
        };
        let time = match header.variable("time") {
            Some(v) if dims(v) == ["frame"] && is_real(v) => {
                let scale = match units(v).trim().to_ascii_lowercase().as_str() {
                    "" | "picosecond" | "picoseconds" | "ps" => Some(1.0),
                    "femtosecond" | "femtoseconds" | "fs" => Some(1e-3),
                    "nanosecond" | "nanoseconds" | "ns" => Some(1e3),
                    _ => None,
                };
                scale.map(|s| slice(v, s)).transpose()?
            }
            _ => None,
        };
        Ok(Layout {
            atoms: atoms as usize,
            record_bytes,
            records_begin,
            coordinates,
            cell,
            time,
        })
    }

    /// The slices read for each frame.
    fn slices(&self) -> impl Iterator<Item = &Slice> {
        std::iter::once(&self.coordinates)
            .chain(self.cell.iter().flat_map(|(l, a)| [l, a]))
            .chain(self.time.iter())
    }

    /// Frames the file holds whole (at most `announced`, when the header says), and why the
    /// next one is unreadable when it is.
    fn count_frames(&self, announced: Option<u64>, total: u64) -> (usize, Option<NetcdfError>) {
        // Frame k is whole when every slice we read of it ends inside the file.
        let whole = self
            .slices()
            .map(
                |s| match total.checked_sub(s.begin.saturating_add(s.bytes())) {
                    None => 0,
                    Some(_) if self.record_bytes == 0 => 1,
                    Some(room) => room / self.record_bytes + 1,
                },
            )
            .min()
            .unwrap_or(0);
        match announced {
            Some(n) if n <= whole => (n as usize, None),
            Some(n) => (
                whole as usize,
                Some(NetcdfError::FewerFrames { announced: n }),
            ),
            None => {
                let next = self
                    .records_begin
                    .saturating_add(whole.saturating_mul(self.record_bytes));
                let cut = (total > next && self.record_bytes > 0).then_some(NetcdfError::CutFrame);
                (whole as usize, cut)
            }
        }
    }
}

/// An open Amber NetCDF file.
/// How an Amber NetCDF file's frames are read: where each variable's slices lie.
struct NetcdfDecoder {
    layout: Layout,
    /// One slice's bytes.
    buffer: Vec<u8>,
}

impl NetcdfDecoder {
    /// The values of `slice` in frame `index` of `file`, as f64 times its scale.
    fn read_slice(
        &mut self,
        file: &Positioned,
        slice: Slice,
        index: usize,
    ) -> Result<Vec<f64>, NetcdfError> {
        let offset = slice.begin + index as u64 * self.layout.record_bytes;
        self.buffer.resize(slice.bytes() as usize, 0);
        file.read_exact_at(&mut self.buffer, offset)?;
        let scale = slice.scale;
        Ok(match slice.kind {
            NcType::Float => self
                .buffer
                .chunks_exact(4)
                .map(|b| scale * f64::from(f32::from_be_bytes([b[0], b[1], b[2], b[3]])))
                .collect(),
            _ => self
                .buffer
                .chunks_exact(8)
                .map(|b| {
                    scale * f64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
                })
                .collect(),
        })
    }
}

impl FrameDecoder for NetcdfDecoder {
    const BASE: &'static str = "Amber NetCDF";
    type Error = NetcdfError;

    fn read(&mut self, file: &Positioned, index: usize) -> Result<Frame, NetcdfError> {
        let layout = self.layout.clone();
        let values = self.read_slice(file, layout.coordinates, index)?;
        let positions: Vec<Vec3> = values
            .chunks_exact(3)
            .take(layout.atoms)
            .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
            .collect();
        let cell = match layout.cell {
            Some((lengths, angles)) => {
                let l = self.read_slice(file, lengths, index)?;
                let a = self.read_slice(file, angles, index)?;
                unit_cell::from_lengths_angles([l[0], l[1], l[2]], [a[0], a[1], a[2]])
                    .map_err(NetcdfError::Cell)?
            }
            None => None,
        };
        let time_ps = match layout.time {
            Some(slice) => self.read_slice(file, slice, index)?.first().copied(),
            None => None,
        };
        Ok(Frame {
            index,
            time_ps: time_ps.filter(|t| t.is_finite()),
            positions,
            cell,
        })
    }
}
