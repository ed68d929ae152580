//! What a file is turned into before chemfiles sees it, so that no byte of a user's file can
//! panic or hang the C++ reader.
//!
//! - Text that is not valid UTF-8 (a Latin-1 `é` in a GRO title, a PDB `TITLE`, a residue name)
//!   makes chemfiles' Rust binding panic. Such a file is read through a temporary copy: in the
//!   fixed-column formats (PDB, GRO) every non-ASCII byte becomes `?` (so columns stay where they
//!   are); in the free formats (mmCIF, XYZ, LAMMPS, MOL2) a byte that is not UTF-8 is read as
//!   Latin-1 and written as UTF-8.
//! - Lone `\r` line ends (CR-only files) become `\n` in every text format ([`super::line_ends`]).
//! - A leading UTF-8 byte order mark is dropped ([`super::text_clean`]).
//! - An XYZ file cut or damaged after its first frame keeps its whole frames ([`super::xyz_frames`]).
//! - `.gz`, `.bz2` and `.xz` files are decompressed here, by memory-safe Rust decoders
//!   (flate2, bzip2, lzma-rust2; see [`super::decoders`] for gzip's zero padding and cut `.xz`
//!   files), into a
//!   temporary plain file (chemfiles' bzip2 reader spins forever on a truncated stream). A stream
//!   that ends early keeps what decompressed: the frames before the cut stay readable and the
//!   last, cut frame is reported as damage. A copy that would outgrow the room of its folder
//!   ([`super::copy_room`]: the disk's free space, or on a tmpfs half the memory budget) stops
//!   there in the same way, its message saying so.
//! - mmCIF files (only on the reference path, [`super::open_via_chemfiles`]: [`super::open`]
//!   reads them with [`super::mmcif`]) get a residue number for every atom outside a polymer
//!   sequence ([`super::cif_residues`]): chemfiles made all the waters of a chain one residue,
//!   and refused files whose entity is `?`.
//! - A path that is not UTF-8 (chemfiles panics on it) is opened through a symbolic link with a
//!   plain name.
//!
//! Files that need none of this are opened as they are, without a copy.

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use super::copy_room::copy_room;
use super::decoders::decoder;
use super::format::FileFormat;
use super::line_ends::{CrToLf, has_lone_cr, lone_cr_to_lf};
use super::text_clean::{BOM, Cleaner, TextKind, text_kind};
use super::{IoError, cif_residues, tng, xyz_frames};

/// Bytes read at a time while scanning or copying.
const CHUNK: usize = 1 << 20;

/// The file chemfiles should open in place of the user's.
pub(crate) struct Prepared {
    /// The path chemfiles opens (the user's file, or a temporary copy or link).
    pub open_path: PathBuf,
    /// The chemfiles format string for `open_path`.
    #[cfg_attr(not(feature = "chemfiles"), allow(dead_code))]
    pub chemfiles: String,
    /// Set when the compressed stream ended early or was corrupt: why (the last frame of the
    /// copy is cut).
    pub truncated: Option<String>,
    /// True when the cut frame was removed from the copy (so the frame after the copy's last
    /// one is the damaged one), false when the copy ends with the cut frame.
    pub cut_removed: bool,
    /// Keeps the temporary copy or link alive while the reader uses it.
    pub temp: Option<tempfile::TempDir>,
}

/// Decides how chemfiles should see `path` (in `format`); see the module documentation.
pub(crate) fn prepare(path: &Path, format: &FileFormat) -> Result<Prepared, IoError> {
    let prepared = prepare_text(path, format)?;
    if format.base == "XYZ" && prepared.truncated.is_none() {
        return keep_whole_xyz_frames(path, prepared);
    }
    Ok(prepared)
}

/// An XYZ file cut or damaged in frame k > 0 as a copy of frames 0..k-1, frame k the damage
/// (chemfiles refuses the whole file; see [`xyz_frames`]); damage in frame 0 is an error naming
/// frame 0.
fn keep_whole_xyz_frames(path: &Path, prepared: Prepared) -> Result<Prepared, IoError> {
    let damage = xyz_frames::first_damage(&prepared.open_path).map_err(|e| failed(path, e))?;
    let Some(damage) = damage else {
        return Ok(prepared);
    };
    if damage.frame == 0 {
        return Err(IoError::bad_frame(path, 0, damage.reason));
    }
    let (temp, copy) = temp_file(path, "XYZ")?;
    let mut input = open(&prepared.open_path)?.take(damage.start);
    let mut output = BufWriter::new(create(path, &copy)?);
    std::io::copy(&mut input, &mut output).map_err(|e| write_failed(path, e))?;
    finish(path, output)?;
    Ok(Prepared {
        open_path: copy,
        chemfiles: prepared.chemfiles,
        truncated: Some(damage.reason),
        cut_removed: true,
        temp: Some(temp),
    })
}

/// What [`prepare`] does to any file: decompression, cleaned text, a salvaged TNG.
fn prepare_text(path: &Path, format: &FileFormat) -> Result<Prepared, IoError> {
    let compression = format
        .chemfiles
        .rsplit_once(" / ")
        .map(|(_, c)| c.to_string());
    let text = text_kind(format.base);
    match compression.as_deref() {
        Some("GZ") | Some("BZ2") | Some("XZ") => {
            decompress(path, format, compression.as_deref(), text)
        }
        _ => {
            if format.base == "TNG" && compression.is_none() {
                return prepare_tng(path, format);
            }
            if matches!(format.base, "PDB" | "mmCIF") && compression.is_none() {
                let bytes =
                    std::fs::read(path).map_err(|e| IoError::unreadable(path, e.to_string()))?;
                let cr_only = has_lone_cr(&bytes);
                let bytes = lone_cr_to_lf(bytes);
                let cleaned = match format.base {
                    "PDB" => clean_pdb(&bytes),
                    _ => {
                        refuse_short_cif_row(path, &bytes)?;
                        cif_residues::renumber(&bytes).map(latin1_as_utf8)
                    }
                };
                let cleaned = cleaned.or_else(|| cr_only.then_some(bytes));
                if let Some(cleaned) = cleaned {
                    let (temp, copy) = temp_file(path, format.base)?;
                    std::fs::write(&copy, cleaned).map_err(|e| write_failed(path, e))?;
                    return Ok(Prepared {
                        open_path: copy,
                        chemfiles: format.chemfiles.clone(),
                        truncated: None,
                        cut_removed: false,
                        temp: Some(temp),
                    });
                }
            }
            let needs_copy = match text {
                Some(_) if format.base == "PDB" => false,
                Some(kind) if compression.is_none() => !scan(path, kind)?,
                _ => false,
            };
            if needs_copy {
                let kind = text.unwrap_or(TextKind::Free);
                let (temp, copy) = temp_file(path, format.base)?;
                let mut input = open(path)?;
                let mut output = BufWriter::new(create(path, &copy)?);
                let mut cleaner = Cleaner::new(kind);
                copy_cleaned(path, &mut input, &mut output, &mut cleaner)?;
                finish(path, output)?;
                return Ok(Prepared {
                    open_path: copy,
                    chemfiles: format.chemfiles.clone(),
                    truncated: None,
                    cut_removed: false,
                    temp: Some(temp),
                });
            }
            if path.to_str().is_none() {
                let (temp, link) = temp_file(path, format.base)?;
                let target = std::path::absolute(path).map_err(|e| failed(path, e))?;
                std::os::unix::fs::symlink(&target, &link).map_err(|e| failed(path, e))?;
                return Ok(Prepared {
                    open_path: link,
                    chemfiles: format.chemfiles.clone(),
                    truncated: None,
                    cut_removed: false,
                    temp: Some(temp),
                });
            }
            Ok(Prepared {
                open_path: path.to_path_buf(),
                chemfiles: format.chemfiles.clone(),
                truncated: None,
                cut_removed: false,
                temp: None,
            })
        }
    }
}

/// A PDB file made safe for chemfiles, or `None` when it already is: non-ASCII bytes become `?`,
/// and `CONECT` records before the first atom of a model are dropped (chemfiles indexes an empty
/// list with them and crashes; a chunk of a file duplicated ahead of its atoms does this, and so
/// do the CONECT records after the last ENDMDL of a wwPDB file whose models differ in size, as
/// 1lcd's). mdsurf reads CONECT records itself from the original file (`super::conect`).
fn clean_pdb(bytes: &[u8]) -> Option<Vec<u8>> {
    let orphan = |bytes: &[u8]| {
        let mut atoms = false;
        bytes.split(|&b| b == b'\n').any(|line| {
            if line.starts_with(b"ATOM") || line.starts_with(b"HETATM") {
                atoms = true;
            } else if line.starts_with(b"END") {
                atoms = false;
            }
            line.starts_with(b"CONECT") && !atoms
        })
    };
    if bytes.is_ascii() && !orphan(bytes) {
        return None;
    }
    let mut out = Vec::with_capacity(bytes.len());
    let mut atoms = false;
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        if line.starts_with(b"ATOM") || line.starts_with(b"HETATM") {
            atoms = true;
        } else if line.starts_with(b"END") {
            atoms = false;
        }
        if line.starts_with(b"CONECT") && !atoms {
            continue;
        }
        out.extend(line.iter().map(|&b| if b.is_ascii() { b } else { b'?' }));
    }
    Some(out)
}

/// An error naming `path` and the line when an mmCIF `_atom_site` row of `bytes` has fewer
/// values than its columns ([`cif_residues::short_row`]: chemfiles would crash on it).
fn refuse_short_cif_row(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    match cif_residues::short_row(bytes) {
        Some((line, values, columns)) => Err(IoError::unreadable(
            path,
            format!(
                "line {line}: an _atom_site row with {values} of its {columns} values (is the file cut short?)"
            ),
        )),
        None => Ok(()),
    }
}

/// `bytes` with every byte that is not valid UTF-8 read as Latin-1 (as a free-format copy
/// gets; chemfiles' binding panics on invalid UTF-8).
fn latin1_as_utf8(bytes: Vec<u8>) -> Vec<u8> {
    if std::str::from_utf8(&bytes).is_ok() {
        return bytes;
    }
    let mut out = Vec::with_capacity(bytes.len() + bytes.len() / 8);
    Cleaner::new(TextKind::Free).push(&bytes, true, &mut out);
    out
}

/// True when `path` can go to chemfiles as it is: all ASCII for fixed columns, valid UTF-8 for
/// free text, no byte order mark.
fn scan(path: &Path, kind: TextKind) -> Result<bool, IoError> {
    let mut input = open(path)?;
    let mut buffer = vec![0u8; CHUNK];
    let mut carry = 0usize;
    let mut first = true;
    loop {
        let n = read_some(path, &mut input, &mut buffer[carry..])?;
        if n == 0 {
            return Ok(carry == 0);
        }
        let filled = carry + n;
        // A byte order mark goes (the copy drops it).
        if std::mem::take(&mut first) && buffer[..filled].starts_with(BOM) {
            return Ok(false);
        }
        if has_lone_cr(&buffer[..filled]) {
            return Ok(false);
        }
        match kind {
            TextKind::Columns => {
                if !buffer[..filled].is_ascii() {
                    return Ok(false);
                }
            }
            TextKind::Free => match std::str::from_utf8(&buffer[..filled]) {
                Ok(_) => carry = 0,
                Err(e) if e.error_len().is_none() => {
                    // A character cut by the chunk boundary: keep its bytes for the next read.
                    let valid = e.valid_up_to();
                    buffer.copy_within(valid..filled, 0);
                    carry = filled - valid;
                }
                Err(_) => return Ok(false),
            },
        }
    }
}

/// Decompresses a `.gz` or `.bz2` file into a temporary plain file (cleaning its text).
/// A TNG file as it is when its block chain is sound, or a copy of its whole frame sets before
/// the damage (see [`tng::salvage`]); an error when none is sound.
fn prepare_tng(path: &Path, format: &FileFormat) -> Result<Prepared, IoError> {
    let as_is = || Prepared {
        open_path: path.to_path_buf(),
        chemfiles: format.chemfiles.clone(),
        truncated: None,
        cut_removed: false,
        temp: None,
    };
    match tng::salvage(path).map_err(|reason| IoError::unreadable(path, reason))? {
        tng::Salvage::Sound => Ok(as_is()),
        tng::Salvage::Kept { bytes, reason } => {
            let (temp, copy) = temp_file(path, format.base)?;
            std::fs::write(&copy, bytes).map_err(|e| write_failed(path, e))?;
            Ok(Prepared {
                open_path: copy,
                chemfiles: format.chemfiles.clone(),
                truncated: Some(reason),
                cut_removed: true,
                temp: Some(temp),
            })
        }
    }
}

fn decompress(
    path: &Path,
    format: &FileFormat,
    compression: Option<&str>,
    text: Option<TextKind>,
) -> Result<Prepared, IoError> {
    let mut input = decoder(open(path)?, compression);
    let (temp, copy) = temp_file(path, format.base)?;
    let room = copy_room(temp.path().parent().unwrap_or(temp.path()));
    let mut written = 0u64;
    let mut output = BufWriter::new(create(path, &copy)?);
    let mut cleaner = text.map(Cleaner::new);
    let mut buffer = vec![0u8; CHUNK];
    let mut cleaned = Vec::with_capacity(CHUNK + 16);
    // Text only: a binary stream's 0x0d bytes are data.
    let mut line_ends = CrToLf::default();
    let mut fixed = Vec::with_capacity(CHUNK + 16);
    let mut total = 0u64;
    let mut truncated = None;
    loop {
        let n = match input.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                truncated = Some(format!(
                    "the compressed data is cut or corrupt after {total} bytes ({e})"
                ));
                break;
            }
        };
        total += n as u64;
        let bytes = match cleaner.as_mut() {
            Some(c) => {
                cleaned.clear();
                c.push(&buffer[..n], false, &mut cleaned);
                fixed.clear();
                line_ends.push(&cleaned, false, &mut fixed);
                &fixed[..]
            }
            None => &buffer[..n],
        };
        // A copy stops at its room, as a cut stream does (the frame it cuts is reported).
        let fits = room.bytes.saturating_sub(written).min(bytes.len() as u64) as usize;
        output
            .write_all(&bytes[..fits])
            .map_err(|e| write_failed(path, e))?;
        written += fits as u64;
        if fits < bytes.len() {
            truncated = Some(room.reason(written));
            break;
        }
    }
    if let Some(c) = cleaner.as_mut() {
        cleaned.clear();
        c.push(&[], true, &mut cleaned);
        fixed.clear();
        line_ends.push(&cleaned, true, &mut fixed);
        output
            .write_all(&fixed)
            .map_err(|e| write_failed(path, e))?;
    }
    finish(path, output)?;
    if matches!(format.base, "PDB" | "mmCIF") {
        // The same cleaning as an uncompressed file gets (a wwPDB multi-model file's CONECT
        // records after its last ENDMDL crashed chemfiles when that model has fewer atoms; an
        // mmCIF file's waters were one residue).
        let bytes = std::fs::read(&copy).map_err(|e| write_failed(path, e))?;
        let cleaned = match format.base {
            "PDB" => clean_pdb(&bytes),
            _ => {
                refuse_short_cif_row(path, &bytes)?;
                cif_residues::renumber(&bytes)
            }
        };
        if let Some(cleaned) = cleaned {
            std::fs::write(&copy, cleaned).map_err(|e| write_failed(path, e))?;
        }
    }
    let mut cut_removed = false;
    if truncated.is_some() && format.base == "LAMMPS" {
        // chemfiles refuses a LAMMPS file whose last frame is incomplete: keep whole frames.
        let bytes = std::fs::read(&copy).map_err(|e| write_failed(path, e))?;
        let marker = b"ITEM: TIMESTEP";
        let last = bytes.windows(marker.len()).rposition(|w| w == marker);
        let keep = last.unwrap_or(0) as u64;
        if keep == 0 {
            let reason = truncated.unwrap_or_default();
            return Err(IoError::bad_frame(path, 0, reason));
        }
        File::options()
            .write(true)
            .open(&copy)
            .and_then(|f| f.set_len(keep))
            .map_err(|e| write_failed(path, e))?;
        cut_removed = true;
    }
    if total == 0 {
        let message = truncated.unwrap_or_else(|| "the compressed data is empty".to_string());
        return Err(IoError::unreadable(path, message));
    }
    Ok(Prepared {
        open_path: copy,
        chemfiles: format.base.to_string(),
        truncated,
        cut_removed,
        temp: Some(temp),
    })
}

/// The whole content of `path` in memory, decompressed (in Rust) when `format` is compressed,
/// with lone `\r` line ends made `\n` (`read_all` serves text formats only), and why the
/// compressed stream ends early when it does (what decompressed before is kept).
/// For the readers that parse a file themselves ([`super::mmcif`]); no temporary copy.
pub(crate) fn read_all(
    path: &Path,
    format: &FileFormat,
) -> Result<(Vec<u8>, Option<String>), IoError> {
    let compression = format.chemfiles.rsplit_once(" / ").map(|(_, c)| c);
    let mut file = open(path)?;
    let Some(compression) = compression else {
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes)
            .map_err(|e| IoError::unreadable(path, e.to_string()))?;
        return Ok((lone_cr_to_lf(bytes), None));
    };
    let mut input = decoder(file, Some(compression));
    let mut bytes = Vec::new();
    let mut buffer = vec![0u8; CHUNK];
    loop {
        match input.read(&mut buffer) {
            Ok(0) => break,
            Ok(n) => bytes.extend_from_slice(&buffer[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                let total = bytes.len();
                let reason =
                    format!("the compressed data is cut or corrupt after {total} bytes ({e})");
                if bytes.is_empty() {
                    return Err(IoError::unreadable(path, reason));
                }
                return Ok((lone_cr_to_lf(bytes), Some(reason)));
            }
        }
    }
    if bytes.is_empty() {
        return Err(IoError::unreadable(path, "the compressed data is empty"));
    }
    Ok((lone_cr_to_lf(bytes), None))
}

/// Copies `input` to `output` through `cleaner`.
fn copy_cleaned(
    path: &Path,
    input: &mut File,
    output: &mut impl Write,
    cleaner: &mut Cleaner,
) -> Result<(), IoError> {
    let mut buffer = vec![0u8; CHUNK];
    let mut cleaned = Vec::with_capacity(2 * CHUNK);
    let mut line_ends = CrToLf::default();
    let mut fixed = Vec::with_capacity(2 * CHUNK);
    loop {
        let n = read_some(path, input, &mut buffer)?;
        cleaned.clear();
        cleaner.push(&buffer[..n], n == 0, &mut cleaned);
        fixed.clear();
        line_ends.push(&cleaned, n == 0, &mut fixed);
        output
            .write_all(&fixed)
            .map_err(|e| write_failed(path, e))?;
        if n == 0 {
            return Ok(());
        }
    }
}

/// A new temporary folder and the path of a file in it with a plain name for `base`.
fn temp_file(path: &Path, base: &str) -> Result<(tempfile::TempDir, PathBuf), IoError> {
    let dir = tempfile::Builder::new()
        .prefix("mdsurf-read-")
        .tempdir()
        .map_err(|e| write_failed(path, e))?;
    let ext = match base {
        "PDB" => "pdb",
        "GRO" => "gro",
        "mmCIF" => "cif",
        "XYZ" => "xyz",
        "LAMMPS" => "lammpstrj",
        "MOL2" => "mol2",
        "XTC" => "xtc",
        "TRR" => "trr",
        "DCD" => "dcd",
        "TNG" => "tng",
        _ => "dat",
    };
    let file = dir.path().join(format!("input.{ext}"));
    Ok((dir, file))
}

fn open(path: &Path) -> Result<File, IoError> {
    File::open(path).map_err(|e| IoError::NotFound {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

fn create(path: &Path, copy: &Path) -> Result<File, IoError> {
    File::create(copy).map_err(|e| write_failed(path, e))
}

fn finish(path: &Path, output: BufWriter<File>) -> Result<(), IoError> {
    output
        .into_inner()
        .map_err(|e| write_failed(path, e.into_error()))?;
    Ok(())
}

fn read_some(path: &Path, input: &mut File, buffer: &mut [u8]) -> Result<usize, IoError> {
    loop {
        match input.read(buffer) {
            Ok(n) => return Ok(n),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(IoError::unreadable(path, e.to_string())),
        }
    }
}

fn failed(path: &Path, e: std::io::Error) -> IoError {
    IoError::unreadable(path, format!("cannot prepare the file for reading: {e}"))
}

fn write_failed(path: &Path, e: std::io::Error) -> IoError {
    IoError::unreadable(
        path,
        format!("cannot write a temporary copy for reading: {e}"),
    )
}
