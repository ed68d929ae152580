//! The chemfiles side of reading: a `Send` handle on one open file that reads frames by index
//! (random access; chemfiles indexes the file once when it opens it), and the conversion of
//! chemfiles' frames and topologies into our [`Frame`] and [`Topology`].

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use chemfiles::{CellShape, Property};
use glam::Vec3;

use super::format::FileFormat;
use super::{IoError, warnings};
use crate::model::elements::canonical_symbol;
use crate::model::{Frame, Topology};

/// Picoseconds per AKMA time unit (CHARMM and NAMD write DCD time steps in AKMA units).
const PS_PER_AKMA: f64 = 0.048_888_21;

/// One open file, read through chemfiles.
pub(crate) struct ChemReader {
    path: PathBuf,
    base: &'static str,
    inner: chemfiles::Trajectory,
    scratch: chemfiles::Frame,
    len: usize,
}

// SAFETY: `chemfiles::Trajectory` and `chemfiles::Frame` are `!Send` only because they hold raw
// pointers to C++ objects. Those objects are owned exclusively by this struct (never shared or
// aliased), have no thread affinity (plain file handles and buffers), and the C API's shared
// bookkeeping is guarded by its own mutex; the last-error string is read on the thread that made
// the failing call. Moving the whole reader to another thread is therefore sound; it is not
// `Sync`, so it is never used from two threads at once.
unsafe impl Send for ChemReader {}

impl ChemReader {
    /// Opens `path` in `format`; fails when chemfiles cannot open it or it holds no frame.
    pub(crate) fn open(path: &Path, format: &FileFormat) -> Result<Self, IoError> {
        warnings::install();
        sniff(path, format.base)?;
        let inner = chemfiles::Trajectory::open_with_format(path, 'r', format.chemfiles.as_str())
            .map_err(|e| IoError::unreadable(path, &e.message))?;
        let mut reader = ChemReader {
            path: path.to_path_buf(),
            base: format.base,
            inner,
            scratch: chemfiles::Frame::new(),
            len: 0,
        };
        // `nsteps` panics (inside the Rust binding) if the C++ side fails.
        let steps = catch_unwind(AssertUnwindSafe(|| reader.inner.nsteps()));
        reader.len = steps.map_err(|_| IoError::unreadable(path, "cannot count the frames"))?;
        if reader.len == 0 {
            return Err(IoError::Empty {
                path: path.to_path_buf(),
                what: "no frames",
            });
        }
        Ok(reader)
    }

    /// The file this reader reads.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// The format without compression (`DCD`, `GRO`).
    pub(crate) fn base(&self) -> &'static str {
        self.base
    }

    /// Number of frames.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Reads frame `index` into the scratch frame and returns it.
    fn read_raw(&mut self, index: usize) -> Result<&chemfiles::Frame, IoError> {
        if index >= self.len {
            return Err(IoError::FrameOutOfRange {
                path: self.path.clone(),
                frame: index,
                len: self.len,
            });
        }
        self.inner
            .read_step(index, &mut self.scratch)
            .map_err(|e| IoError::bad_frame(&self.path, index, &e.message))?;
        Ok(&self.scratch)
    }

    /// Reads frame `index` and converts it; positions are checked to be finite.
    pub(crate) fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        let base = self.base;
        let raw = self.read_raw(index)?;
        let positions = to_vec3(raw.positions());
        let cell = cell_rows(raw);
        let time_ps = frame_time_ps(raw, base);
        if let Some(atom) = positions.iter().position(|p| !p.is_finite()) {
            return Err(IoError::NonFiniteCoordinate {
                path: self.path.clone(),
                frame: index,
                atom,
            });
        }
        Ok(Frame {
            index,
            time_ps,
            positions,
            cell,
        })
    }

    /// Reads frame `index` and returns its raw positions in Å (not checked to be finite).
    pub(crate) fn read_positions(&mut self, index: usize) -> Result<Vec<Vec3>, IoError> {
        let raw = self.read_raw(index)?;
        Ok(to_vec3(raw.positions()))
    }

    /// Reads frame `index` and returns the topology it carries (names, residues, chains, bonds;
    /// elements only where the file states them, radii left at 0 for the caller to complete).
    pub(crate) fn read_topology(&mut self, index: usize) -> Result<Topology, IoError> {
        let raw = self.read_raw(index)?;
        Ok(convert_topology(&raw.topology()))
    }
}

/// Rejects files that plainly are not in `base` format before a C library sees them. The TNG
/// library prints straight to stderr (past chemfiles' warning callback) and tries huge
/// allocations on garbage, so a TNG file must start with its GENERAL INFO block.
fn sniff(path: &Path, base: &str) -> Result<(), IoError> {
    if base != "TNG" {
        return Ok(());
    }
    let mut head = [0u8; 64];
    let read = std::fs::File::open(path).and_then(|mut f| std::io::Read::read(&mut f, &mut head));
    let n = read.map_err(|e| IoError::unreadable(path, e.to_string()))?;
    if head[..n].windows(12).any(|w| w == b"GENERAL INFO") {
        Ok(())
    } else {
        Err(IoError::unreadable(
            path,
            "not a TNG file (it does not start with a GENERAL INFO block)",
        ))
    }
}

/// Converts chemfiles' positions (f64, Å) to ours (f32, Å).
fn to_vec3(positions: &[[f64; 3]]) -> Vec<Vec3> {
    positions
        .iter()
        .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect()
}

/// The periodic box as rows a, b, c in Å, or `None` for an infinite (absent) box.
fn cell_rows(frame: &chemfiles::Frame) -> Option<[Vec3; 3]> {
    let cell = frame.cell();
    if cell.shape() == CellShape::Infinite {
        return None;
    }
    // chemfiles stores the cell vectors as the matrix columns.
    let m = cell.matrix();
    let column = |j: usize| Vec3::new(m[0][j] as f32, m[1][j] as f32, m[2][j] as f32);
    let rows = [column(0), column(1), column(2)];
    rows.iter().all(|r| r.is_finite()).then_some(rows)
}

/// The frame's time in ps when the format records it in a known unit.
fn frame_time_ps(frame: &chemfiles::Frame, base: &str) -> Option<f64> {
    // Looked up by iterating: `get` on a missing property makes chemfiles warn.
    let Some((_, Property::Double(t))) = frame.properties().find(|(name, _)| name == "time") else {
        return None;
    };
    let t = match base {
        "XTC" | "TRR" | "TNG" | "Amber NetCDF" => t,
        "DCD" => t * PS_PER_AKMA,
        _ => return None, // LAMMPS and text formats: unit unknown
    };
    t.is_finite().then_some(t)
}

/// Converts a chemfiles topology; see [`ChemReader::read_topology`].
fn convert_topology(top: &chemfiles::Topology) -> Topology {
    let n = top.size();
    let mut out = Topology {
        names: Vec::with_capacity(n),
        elements: Vec::with_capacity(n),
        radii: vec![0.0; n],
        residue_names: vec![String::new(); n],
        residue_ids: vec![0; n],
        residue_index: vec![u32::MAX; n],
        chains: vec![String::new(); n],
        b_factors: vec![0.0; n],
        bonds: Vec::new(),
    };
    for i in 0..n {
        let atom = top.atom(i);
        let kind = atom.atomic_type();
        // LAMMPS dumps give each particle a numeric type and no name: the type is the name.
        let name = match atom.name() {
            name if name.trim().is_empty() => kind.clone(),
            name => name,
        };
        // A type equal to the name is chemfiles' default, not an element column.
        let element = if kind != name {
            canonical_symbol(&kind).unwrap_or_default()
        } else {
            ""
        };
        out.elements.push(element.to_string());
        out.names.push(name);
    }
    let residues = top.residues_count() as usize;
    for r in 0..residues {
        let Some(residue) = top.residue(r) else {
            continue;
        };
        let name = residue.name();
        let id = residue.id().unwrap_or(r as i64 + 1);
        let chain = residue_chain(&residue);
        for a in residue.atoms().into_iter().filter(|&a| a < n) {
            out.residue_names[a].clone_from(&name);
            out.residue_ids[a] = id;
            out.residue_index[a] = r as u32;
            out.chains[a].clone_from(&chain);
        }
    }
    // Atoms outside every residue each get a residue of their own, after the real ones.
    let mut next = residues as u32;
    for r in out.residue_index.iter_mut().filter(|r| **r == u32::MAX) {
        *r = next;
        next += 1;
    }
    renumber_by_first_atom(&mut out.residue_index);
    out.bonds = top
        .bonds()
        .into_iter()
        .map(|[a, b]| [a as u32, b as u32])
        .collect();
    out
}

/// Renumbers residue indices so they count up in order of each residue's first atom (chemfiles
/// may list residues sorted by chain and number rather than as they appear in the file).
fn renumber_by_first_atom(index: &mut [u32]) {
    let mut map = std::collections::HashMap::new();
    for r in index.iter_mut() {
        let next = map.len() as u32;
        *r = *map.entry(*r).or_insert(next);
    }
}

/// The chain id of a residue (`chainid`), else its segment name, else empty.
fn residue_chain(residue: &chemfiles::Residue) -> String {
    let properties: Vec<(String, Property)> = residue.properties().collect();
    for key in ["chainid", "chainname", "segname"] {
        for (name, value) in &properties {
            if let (true, Property::String(s)) = (name == key, value) {
                let s = s.trim();
                if !s.is_empty() {
                    return s.to_string();
                }
            }
        }
    }
    String::new()
}
