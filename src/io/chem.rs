//! The chemfiles side of reading: a `Send` handle on one open file that reads frames by index
//! (random access; chemfiles indexes the file once when it opens it), and the conversion of
//! chemfiles' frames and topologies into our [`Frame`] and [`Topology`].

use std::path::{Path, PathBuf};

use chemfiles::{CellShape, Property};
use glam::Vec3;

use super::format::FileFormat;
use super::prepare::prepare;
use super::{IoError, dcd, quiet, warnings};
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
    /// The temporary copy (or link) chemfiles reads, when the file needed one (see [`prepare`]).
    copy: Option<PathBuf>,
    /// Keeps that copy alive (`None` in a reader process: its parent owns the copy).
    _temp: Option<tempfile::TempDir>,
    /// Why the (compressed) file ends early, when it does, and whether the cut frame was left
    /// out of the copy (see [`super::prepare::Prepared::cut_removed`]).
    truncated: Option<(String, bool)>,
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
        let prepared = check_and_prepare(path, format)?;
        let copy = (prepared.open_path != path).then(|| prepared.open_path.clone());
        let truncated = prepared.truncated.map(|t| (t, prepared.cut_removed));
        let mut reader =
            Self::open_prepared(path, format.base, copy, &prepared.chemfiles, prepared.temp)?;
        reader.truncated = truncated;
        Ok(reader)
    }

    /// Opens with chemfiles what [`check_and_prepare`] made of `path`: `copy` (when set) is the
    /// file chemfiles reads in place of `path`, in the chemfiles format `chemfiles`; `temp` keeps
    /// it alive. Errors name `path`.
    pub(crate) fn open_prepared(
        path: &Path,
        base: &'static str,
        copy: Option<PathBuf>,
        chemfiles: &str,
        temp: Option<tempfile::TempDir>,
    ) -> Result<Self, IoError> {
        warnings::install();
        let open_path = copy.clone().unwrap_or_else(|| path.to_path_buf());
        let opened =
            quiet::silenced(|| chemfiles::Trajectory::open_with_format(&open_path, 'r', chemfiles))
                .map_err(|()| IoError::unreadable(path, "the reader failed on this file"))?;
        let inner = opened.map_err(|e| {
            IoError::unreadable(path, tidy_tng(unmask(&e.message, &open_path, path)))
        })?;
        let mut reader = ChemReader {
            path: path.to_path_buf(),
            base,
            inner,
            scratch: chemfiles::Frame::new(),
            len: 0,
            copy,
            _temp: temp,
            truncated: None,
        };
        // `nsteps` panics (inside the Rust binding) if the C++ side fails.
        let steps = quiet::silenced(|| reader.inner.nsteps());
        reader.len = steps.map_err(|_| IoError::unreadable(path, "cannot count the frames"))?;
        if reader.len == 0 {
            return Err(IoError::Empty {
                path: path.to_path_buf(),
                what: "no frames",
            });
        }
        // chemfiles counts one PDB frame per END* record, and an ENDMDL only merges with an END
        // right after it; wwPDB files put CONECT and MASTER records between the last ENDMDL and
        // END, which made an empty last frame (a one-model NMR entry read as two frames, the
        // second with no atoms). Such a frame is not part of the trajectory.
        if reader.base == "PDB"
            && reader.len > 1
            && reader.read_raw(reader.len - 1).is_ok_and(|f| f.size() == 0)
        {
            reader.len -= 1;
        }
        Ok(reader)
    }

    /// Number of frames.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Why the file ends early, when it is a compressed file whose stream is cut, and whether
    /// the cut frame is already left out (else the last frame read is the incomplete one).
    pub(crate) fn truncated(&self) -> Option<(&str, bool)> {
        self.truncated
            .as_ref()
            .map(|(t, removed)| (t.as_str(), *removed))
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
        let (inner, scratch) = (&mut self.inner, &mut self.scratch);
        let read = quiet::silenced(|| inner.read_step(index, scratch)).map_err(|()| {
            IoError::bad_frame(&self.path, index, "the reader failed on this frame")
        })?;
        read.map_err(|e| {
            let message = match &self.copy {
                Some(copy) => unmask(&e.message, copy, &self.path),
                None => e.message.clone(),
            };
            IoError::bad_frame(&self.path, index, tidy_tng(message))
        })?;
        Ok(&self.scratch)
    }

    /// Reads frame `index` and converts it, positions not checked (a reader process sends
    /// them as they are; its parent checks them).
    pub(crate) fn read_unchecked(&mut self, index: usize) -> Result<Frame, IoError> {
        let base = self.base;
        let raw = self.read_raw(index)?;
        let positions = to_vec3(raw.positions());
        let cell = cell_rows(raw);
        // A property that is not UTF-8 (a DCD title) panics in the binding: no time then.
        let time_ps = quiet::silenced(|| frame_time_ps(raw, base)).unwrap_or(None);
        Ok(Frame {
            index,
            time_ps,
            positions,
            cell,
        })
    }

    /// Reads frame `index` and returns the topology it carries (names, residues, chains, bonds;
    /// elements only where the file states them, radii left at 0 for the caller to complete).
    pub(crate) fn read_topology(&mut self, index: usize) -> Result<Topology, IoError> {
        let path = self.path.clone();
        let raw = self.read_raw(index)?;
        // Names that are not UTF-8 (from a binary format; text files are cleaned before
        // chemfiles sees them) panic in the binding.
        let mut topology = quiet::silenced(|| convert_topology(&raw.topology())).map_err(|()| {
            IoError::unreadable(&path, "atom or residue names are not readable text")
        })?;
        if self.base == "GRO" {
            // The plain copy when there is one (decompressed, cleaned text), else the file.
            let text = self.copy.as_deref().unwrap_or(path.as_path());
            if let Some(lines) = read_gro_residues(text) {
                apply_gro_residues(&mut topology, &lines);
            }
        }
        Ok(topology)
    }
}

/// What every chemfiles read starts with, in the process that holds the user's work: the
/// checks of [`sniff`], then [`prepare`] (decompression, cleaned text, TNG salvage).
pub(crate) fn check_and_prepare(
    path: &Path,
    format: &FileFormat,
) -> Result<super::prepare::Prepared, IoError> {
    sniff(path, format.base)?;
    prepare(path, format)
}

/// Rejects files that plainly are not in `base` format, or are damaged in ways the C libraries
/// do not survive, before a C library sees them. The TNG library prints straight to stderr (past
/// chemfiles' warning callback), tries huge allocations on garbage and crashes on damaged
/// blocks, so a TNG file must start with its GENERAL INFO block and pass `tng::salvage` (called
/// by `prepare`); a DCD
/// header must announce sizes that fit the file ([`dcd::check_header`]).
fn sniff(path: &Path, base: &str) -> Result<(), IoError> {
    if base == "DCD" {
        // chemfiles allocates what the header says before reading a frame.
        return dcd::check_header(path).map_err(|reason| IoError::unreadable(path, reason));
    }
    if base != "TNG" {
        return Ok(());
    }
    let mut head = [0u8; 64];
    let read = std::fs::File::open(path).and_then(|mut f| std::io::Read::read(&mut f, &mut head));
    let n = read.map_err(|e| IoError::unreadable(path, e.to_string()))?;
    if head[..n].windows(12).any(|w| w == b"GENERAL INFO") {
        // The block chain is checked (and a damaged file salvaged) in `prepare`.
        Ok(())
    } else {
        Err(IoError::unreadable(
            path,
            "not a TNG file (it does not start with a GENERAL INFO block)",
        ))
    }
}

/// `message` with the temporary copy's path `copy` replaced by the user's `path`.
fn unmask(message: &str, copy: &Path, path: &Path) -> String {
    message.replace(
        copy.to_string_lossy().as_ref(),
        path.to_string_lossy().as_ref(),
    )
}

/// chemfiles' words for a failed TNG call (`critical error while calling
/// tng_util_trajectory_open(this->path().c_str(), mode, &handle_) in the TNG library`, C++
/// source text) made one for the user: `damaged TNG data (tng_util_trajectory_open failed)`.
/// Other messages stay as they are.
fn tidy_tng(message: String) -> String {
    if !message.contains("in the TNG library") {
        return message;
    }
    let call = message.find("tng_").map(|at| {
        let rest = &message[at..];
        let end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        &rest[..end]
    });
    match call {
        Some(call) => format!("damaged TNG data ({call} failed)"),
        None => "damaged TNG data".to_string(),
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
///
/// Residues are contiguous runs of atoms with the same (residue number, residue name, chain,
/// segment) in file order, never grouped by number alone: chemfiles puts every atom that shares
/// a residue number into one residue (a GRO file numbering protein and lipids from 1 each), so a
/// new run also starts wherever chemfiles' residue changes.
fn convert_topology(top: &chemfiles::Topology) -> Topology {
    let n = top.size();
    let mut out = super::fast::empty_topology(n);
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
        // chemfiles looks the mass up from the type; a type that is only the name (`CA` in a GRO
        // file) would give calcium's mass, so only a mass the file set explicitly is kept then.
        let mass = atom.mass();
        let mass = if kind != name || mass != chemfiles::Atom::new(kind.as_str()).mass() {
            mass as f32
        } else {
            0.0
        };
        out.masses.push(if mass.is_finite() { mass } else { 0.0 });
        out.charges.push(atom.charge() as f32);
        out.elements.push(element);
        out.types.push(kind);
        out.names.push(name);
    }
    // chemfiles' residue of each atom, to split runs where it changes.
    let mut chem_residue = vec![u32::MAX; n];
    let residues = top.residues_count() as usize;
    for r in 0..residues {
        let Some(residue) = top.residue(r) else {
            continue;
        };
        let name = residue.name();
        let id = residue.id().unwrap_or(r as i64 + 1);
        let chain = residue_chain(&residue);
        let segment = residue_string(&residue, &["segname"]);
        // chemfiles' PDB and mmCIF readers keep a residue's insertion code as a property.
        let code = residue_string(&residue, &["insertion_code"]);
        for a in residue.atoms().into_iter().filter(|&a| a < n) {
            out.residue_names.set(a, &name);
            out.residue_ids[a] = id;
            out.insertion_codes.set(a, &code);
            out.chains.set(a, &chain);
            out.segments.set(a, &segment);
            chem_residue[a] = r as u32;
        }
    }
    out.number_residue_runs(&chem_residue);
    out.bonds = top
        .bonds()
        .into_iter()
        .map(|[a, b]| [a as u32, b as u32])
        .collect();
    out
}

/// Replaces residue numbers and names with those of GRO columns 1-5 and 6-10 (`lines` are the
/// atom lines of the first frame) and renumbers the residues as runs; chemfiles' GRO reader
/// keeps one name per residue number. Does nothing when the line count is not the atom count.
fn apply_gro_residues(top: &mut Topology, lines: &[(i64, String)]) {
    if lines.len() != top.len() {
        return;
    }
    let mut group = vec![0u32; lines.len()];
    for (i, (id, name)) in lines.iter().enumerate() {
        top.residue_ids[i] = *id;
        top.residue_names.set(i, name);
        group[i] = u32::from(i > 0 && (lines[i - 1].0 != *id || lines[i - 1].1 != *name));
    }
    // Runs split where number or name change, whatever chemfiles grouped.
    let mut run = 0u32;
    for g in group.iter_mut() {
        run += *g;
        *g = run;
    }
    top.number_residue_runs(&group);
}

/// The residue number and name columns of the first frame of the GRO file `path` (plain,
/// `.gz` or `.bz2`), or `None` when it cannot be read.
fn read_gro_residues(path: &Path) -> Option<Vec<(i64, String)>> {
    use std::io::{BufRead, BufReader, Read};
    let file = std::fs::File::open(path).ok()?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let reader: Box<dyn Read> = match ext.to_ascii_lowercase().as_str() {
        "gz" => Box::new(flate2::read::MultiGzDecoder::new(file)),
        "bz2" => Box::new(bzip2::read::MultiBzDecoder::new(file)),
        _ => Box::new(file),
    };
    let mut lines = BufReader::new(reader).lines();
    lines.next()?.ok()?;
    let count: usize = lines.next()?.ok()?.trim().parse().ok()?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let line = lines.next()?.ok()?;
        let id = line.get(0..5)?.trim().parse().ok()?;
        out.push((id, line.get(5..10)?.trim().to_string()));
    }
    Some(out)
}

/// The chain id of a residue (`chainid`), else its segment name, else empty.
fn residue_chain(residue: &chemfiles::Residue) -> String {
    residue_string(residue, &["chainid", "chainname", "segname"])
}

/// The first non-empty string property of `residue` among `keys`, trimmed, else empty.
fn residue_string(residue: &chemfiles::Residue, keys: &[&str]) -> String {
    let properties: Vec<(String, Property)> = residue.properties().collect();
    for key in keys {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residues_are_runs_not_numbers() {
        // Protein residue 1, lipid residue 1, lipid residue 2, protein-numbered 1 again.
        let lines: Vec<(i64, String)> = [(1, "ALA"), (1, "ALA"), (1, "POPE"), (2, "POPE")]
            .iter()
            .map(|(i, n)| (*i, n.to_string()))
            .collect();
        let mut top = Topology::of_residues(&[(1, "ALA"); 4]);
        apply_gro_residues(&mut top, &lines);
        assert_eq!(top.residue_index, vec![0, 0, 1, 2]);
        assert_eq!(&top.residue_names[2], "POPE");
    }

    #[test]
    fn tng_library_failures_read_as_damaged_data() {
        let open = "critical error while calling tng_util_trajectory_open(this->path().c_str(), \
                    mode, &handle_) in the TNG library";
        assert_eq!(
            tidy_tng(open.into()),
            "damaged TNG data (tng_util_trajectory_open failed)"
        );
        let read = "fatal error in the TNG library while calling 'tng_util_box_shape_read_range'";
        assert_eq!(
            tidy_tng(read.into()),
            "damaged TNG data (tng_util_box_shape_read_range failed)"
        );
        let other = "XYZ format: not enough lines at step 2";
        assert_eq!(tidy_tng(other.into()), other);
    }
}
