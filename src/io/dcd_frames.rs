//! Our DCD reader (CHARMM, NAMD and MDAnalysis files, X-PLOR headers too): both byte orders,
//! 32-bit Fortran record markers, the CHARMM unit-cell record, fixed atoms (the first frame
//! holds every atom, later frames only the free ones) and the fourth-dimension record
//! (skipped). Frames are located by arithmetic from the header; every frame's record markers
//! are checked when the file opens, so a cut or damaged frame `k` leaves frames `0..k`
//! readable and is reported as one line naming frame `k`. Nothing is allocated from a header
//! size before the file is known to hold it.
//!
//! Time and box follow chemfiles exactly: time = `delta × (nsavc × frame + istart)` in AKMA
//! units, converted to ps; the cell record is `A, gamma, B, beta, alpha, C` (angles in degrees,
//! or their cosines when all three are within ±1), or, for CHARMM versions above 25, the
//! symmetric box matrix `[A, B, C; B, D, E; C, E, F]` packed as `A, B, D, C, E, F`.
//!
//! A DCD file read over HTTP ([`Bytes::Remote`]) is indexed from its header and size alone (fixed
//! frame sizes: nothing past the header is read when it opens); its frames' record markers are
//! checked when each frame is read.
//!
//! Errors are [`DcdError`]s, wrapped in an [`IoError`] naming the file (and frame).

use std::path::Path;

use glam::{DMat3, DVec3, Vec3};

use super::IoError;
use super::native::NativeOpen;
use super::positioned::Positioned;
use super::positioned_frames::{Bytes, FrameDecoder, PositionedFrames};
use super::reader_errors::DcdError;
use super::unit_cell;
use crate::model::Frame;

/// Picoseconds per AKMA time unit (CHARMM and NAMD write DCD time steps in AKMA units).
const PS_PER_AKMA: f64 = 0.048_888_21;

/// What the header says about the frames.
#[derive(Debug, Clone)]
struct Layout {
    little: bool,
    atoms: usize,
    /// 0-based indices of the atoms each later frame holds, when some atoms are fixed.
    free: Option<Vec<usize>>,
    has_cell: bool,
    four_d: bool,
    charmm_version: i32,
    /// Time of frame `k` is `dt × (step × k + start)` (AKMA), when `dt` and `step` are not 0.
    start: i64,
    step: i64,
    dt: f64,
    /// Byte offsets: end of the header, size of the first and of every later frame.
    header_bytes: u64,
    first_bytes: u64,
    frame_bytes: u64,
}

impl Layout {
    /// Atoms stored in frame `index`.
    fn stored(&self, index: usize) -> usize {
        match (&self.free, index) {
            (Some(free), 1..) => free.len(),
            _ => self.atoms,
        }
    }

    fn offset(&self, index: usize) -> u64 {
        match index {
            0 => self.header_bytes,
            k => self.header_bytes + self.first_bytes + (k as u64 - 1) * self.frame_bytes,
        }
    }

    fn int(&self, bytes: &[u8]) -> i64 {
        let b = [bytes[0], bytes[1], bytes[2], bytes[3]];
        i64::from(if self.little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        })
    }

    fn f32(&self, bytes: &[u8]) -> f32 {
        let b = [bytes[0], bytes[1], bytes[2], bytes[3]];
        if self.little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    }

    fn f64(&self, bytes: &[u8]) -> f64 {
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[..8]);
        if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        }
    }

    /// The records of one frame, in order: (payload bytes, what it holds).
    fn records(&self, index: usize) -> Vec<(u64, &'static str)> {
        let coordinates = 4 * self.stored(index) as u64;
        let mut records = Vec::with_capacity(5);
        if self.has_cell {
            records.push((48, "unit cell"));
        }
        records.extend([(coordinates, "x"), (coordinates, "y"), (coordinates, "z")]);
        if self.four_d {
            records.push((coordinates, "fourth dimension"));
        }
        records
    }
}

/// Bytes of a frame of `stored` atoms.
fn frame_size(stored: usize, has_cell: bool, four_d: bool) -> u64 {
    let record = 8 + 4 * stored as u64;
    (if has_cell { 56 } else { 0 }) + record * if four_d { 4 } else { 3 }
}

/// Opens the DCD file `path` (a local file, or a URL read through range requests: then only
/// the header is read here) and indexes its frames.
pub(crate) fn open(path: &Path, bytes: Bytes) -> Result<NativeOpen, IoError> {
    let (bytes, total, prepared) = bytes.open(path)?;
    let layout = read_header(&bytes, total).map_err(|e| IoError::unreadable(path, e))?;
    let (len, damage) = count_frames(&bytes, &layout, total);
    let mut decoder = DcdDecoder {
        layout,
        fixed: Vec::new(),
        buffer: Vec::new(),
    };
    if len > 0 && decoder.layout.free.is_some() {
        decoder.fixed = decoder
            .read(&bytes, 0)
            .map_err(|reason| IoError::bad_frame(path, 0, reason))?
            .positions;
    }
    PositionedFrames::open(
        path,
        (bytes, prepared),
        len,
        damage,
        decoder,
        DcdError::NoFrames,
    )
}

/// Reads `len` bytes at `offset`, or says the file ends first.
fn read_at(file: &Positioned, offset: u64, len: u64, total: u64) -> Result<Vec<u8>, DcdError> {
    if offset.checked_add(len).is_none_or(|end| end > total) {
        return Err(DcdError::HeaderCut { len, offset, total });
    }
    let mut bytes = vec![0u8; len as usize];
    file.read_exact_at(&mut bytes, offset)?;
    Ok(bytes)
}

/// Parses the header records; see the module documentation.
fn read_header(file: &Positioned, total: u64) -> Result<Layout, DcdError> {
    let head = read_at(file, 0, 92, total).map_err(|_| DcdError::TooShort)?;
    let little = match (&head[0..4], &head[4..8]) {
        ([84, 0, 0, 0], b"CORD") => true,
        ([0, 0, 0, 84], b"CORD") => false,
        ([84, 0, 0, 0], [0, 0, 0, 0]) | ([0, 0, 0, 0], [0, 0, 0, 84])
            if &head[8..12] == b"CORD" =>
        {
            return Err(DcdError::Markers64);
        }
        _ => return Err(DcdError::NotDcd),
    };
    let mut layout = Layout {
        little,
        atoms: 0,
        free: None,
        has_cell: false,
        four_d: false,
        charmm_version: 0,
        start: 0,
        step: 0,
        dt: 0.0,
        header_bytes: 0,
        first_bytes: 0,
        frame_bytes: 0,
    };
    let control = |k: usize| layout.int(&head[8 + 4 * k..]);
    let charmm_version = control(19);
    let fixed = control(8);
    let (start, step) = (control(1), control(2));
    let (dt, has_cell, four_d) = if charmm_version != 0 {
        (
            f64::from(layout.f32(&head[8 + 36..])),
            control(10) != 0,
            control(11) == 1,
        )
    } else {
        (layout.f64(&head[8 + 36..]), false, false)
    };
    if layout.int(&head[88..92]) != 84 {
        return Err(DcdError::HeaderMarker);
    }
    // Title record: skipped (its line count is never trusted).
    let title = layout.int(&read_at(file, 92, 4, total)?);
    if title < 0 || title as u64 > total {
        return Err(DcdError::TitleSize { title, total });
    }
    let after_title = 96 + title as u64;
    if layout.int(&read_at(file, after_title, 4, total)?) != title {
        return Err(DcdError::TitleMarker);
    }
    let natom = read_at(file, after_title + 4, 12, total)?;
    if layout.int(&natom[0..4]) != 4 || layout.int(&natom[8..12]) != 4 {
        return Err(DcdError::AtomCountMarkers);
    }
    let atoms = layout.int(&natom[4..8]);
    // Nothing is allocated from the atom count before a whole frame is known to be in the
    // file (a file cut inside frame 0 is damage at frame 0, an absurd count no frame).
    if atoms <= 0 {
        return Err(DcdError::BadAtomCount(atoms));
    }
    if fixed < 0 || fixed > atoms {
        return Err(DcdError::BadFixed { fixed, atoms });
    }
    let mut header_bytes = after_title + 16;
    let free = if fixed > 0 {
        let count = (atoms - fixed) as u64;
        let record = read_at(file, header_bytes, 8 + 4 * count, total)?;
        let bytes = record.len();
        let marker = (4 * count) as i64;
        if layout.int(&record[0..4]) != marker || layout.int(&record[bytes - 4..]) != marker {
            return Err(DcdError::FreeAtomMarkers);
        }
        let mut free = Vec::with_capacity(count as usize);
        for k in 0..count as usize {
            let index = layout.int(&record[4 + 4 * k..]);
            if index < 1 || index > atoms {
                return Err(DcdError::FreeAtomIndex { k, index, atoms });
            }
            free.push(index as usize - 1);
        }
        header_bytes += 8 + 4 * count;
        Some(free)
    } else {
        None
    };
    let stored_later = free.as_ref().map_or(atoms as usize, Vec::len);
    layout = Layout {
        atoms: atoms as usize,
        has_cell,
        four_d,
        charmm_version: charmm_version as i32,
        start,
        step,
        dt,
        header_bytes,
        first_bytes: frame_size(atoms as usize, has_cell, four_d),
        frame_bytes: frame_size(stored_later, has_cell, four_d),
        free,
        ..layout
    };
    Ok(layout)
}

/// Counts the frames `bytes` holds whole and checks every frame's record markers (over HTTP,
/// each frame's when it is read): the count, and why the next frame cannot be read when the
/// file holds more bytes.
fn count_frames(bytes: &Positioned, layout: &Layout, total: u64) -> (usize, Option<DcdError>) {
    let body = total.saturating_sub(layout.header_bytes);
    let whole = if body < layout.first_bytes {
        0
    } else {
        1 + ((body - layout.first_bytes) / layout.frame_bytes) as usize
    };
    let walk = if bytes.is_remote() { 0 } else { whole };
    for index in 0..walk {
        if let Err(reason) = check_markers(bytes, layout, index) {
            return (index, Some(reason));
        }
    }
    let end = layout.offset(whole);
    if total > end {
        let expected = if whole == 0 {
            layout.first_bytes
        } else {
            layout.frame_bytes
        };
        let cut = DcdError::FrameCut {
            have: total - end,
            expected,
            atoms: layout.stored(whole),
        };
        return (whole, Some(cut));
    }
    (whole, None)
}

/// Checks the Fortran record markers of frame `index` (which the file holds whole).
fn check_markers(bytes: &Positioned, layout: &Layout, index: usize) -> Result<(), DcdError> {
    let mut offset = layout.offset(index);
    let mut marker = [0u8; 4];
    for (record_bytes, what) in layout.records(index) {
        for at in [offset, offset + 4 + record_bytes] {
            bytes.read_exact_at(&mut marker, at)?;
            let found = layout.int(&marker);
            if found != record_bytes as i64 {
                return Err(DcdError::RecordMarker {
                    record: what,
                    found,
                    expected: record_bytes,
                });
            }
        }
        offset += 8 + record_bytes;
    }
    Ok(())
}

/// How a DCD file's frames are read: the layout its header gives.
struct DcdDecoder {
    layout: Layout,
    /// Frame 0's positions (Å), for the fixed atoms of later frames; empty without fixed atoms.
    fixed: Vec<Vec3>,
    /// One frame's bytes.
    buffer: Vec<u8>,
}

impl DcdDecoder {
    /// The box of a frame from its cell record's six doubles.
    fn cell(&self, values: [f64; 6]) -> Result<Option<[Vec3; 3]>, DcdError> {
        if self.layout.charmm_version > 25 {
            let [a, b, d, c, e, f] = values;
            let matrix = DMat3::from_cols(
                DVec3::new(a, b, c),
                DVec3::new(b, d, e),
                DVec3::new(c, e, f),
            );
            return unit_cell::from_columns(matrix).map_err(DcdError::Cell);
        }
        let [a, gamma, b, beta, alpha, c] = values;
        let mut angles = [alpha, beta, gamma];
        if angles.iter().all(|x| x.abs() <= 1.0) {
            // Cosines: 90° − asin(cos) keeps a cosine of 0 at exactly 90°.
            angles = angles.map(|cos| 90.0 - cos.asin() * 90.0 / (std::f64::consts::PI / 2.0));
        }
        unit_cell::from_lengths_angles([a, b, c], angles).map_err(DcdError::Cell)
    }
}

/// Checks the record markers of frame `index` in its bytes `frame` (what
/// [`check_markers`] checks in the file, for a frame read over HTTP).
fn check_markers_in(layout: &Layout, index: usize, frame: &[u8]) -> Result<(), DcdError> {
    let mut offset = 0usize;
    for (bytes, what) in layout.records(index) {
        let end = offset + 4 + bytes as usize;
        for at in [offset, end] {
            let found = frame.get(at..at + 4).map_or(-1, |b| layout.int(b));
            if found != bytes as i64 {
                return Err(DcdError::RecordMarker {
                    record: what,
                    found,
                    expected: bytes,
                });
            }
        }
        offset = end + 4;
    }
    Ok(())
}

impl FrameDecoder for DcdDecoder {
    const BASE: &'static str = "DCD";
    type Error = DcdError;

    fn read(&mut self, bytes: &Positioned, index: usize) -> Result<Frame, DcdError> {
        let size = if index == 0 {
            self.layout.first_bytes
        } else {
            self.layout.frame_bytes
        } as usize;
        self.buffer.resize(size, 0);
        bytes.read_exact_at(&mut self.buffer, self.layout.offset(index))?;
        check_markers_in(&self.layout, index, &self.buffer)?;
        let layout = &self.layout;
        let mut at = 0usize;
        let cell = if layout.has_cell {
            let values: [f64; 6] = std::array::from_fn(|k| layout.f64(&self.buffer[4 + 8 * k..]));
            at += 56;
            self.cell(values)?
        } else {
            None
        };
        let stored = layout.stored(index);
        let mut positions = if stored == layout.atoms {
            vec![Vec3::ZERO; layout.atoms]
        } else {
            self.fixed.clone()
        };
        for axis in 0..3 {
            let record = &self.buffer[at + 4..at + 4 + 4 * stored];
            let values = record.chunks_exact(4).map(|b| layout.f32(b));
            match (&layout.free, stored == layout.atoms) {
                (Some(free), false) => {
                    for (&atom, value) in free.iter().zip(values) {
                        positions[atom][axis] = value;
                    }
                }
                _ => {
                    for (position, value) in positions.iter_mut().zip(values) {
                        position[axis] = value;
                    }
                }
            }
            at += 8 + 4 * stored;
        }
        let time_ps = (layout.dt != 0.0 && layout.step != 0).then(|| {
            let step = layout.step * index as i64 + layout.start;
            layout.dt * step as f64 * PS_PER_AKMA
        });
        Ok(Frame {
            index,
            time_ps: time_ps.filter(|t| t.is_finite()),
            positions,
            cell,
        })
    }
}
