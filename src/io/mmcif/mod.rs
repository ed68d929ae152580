//! Our mmCIF reader (`.cif`, `.mmcif`, also compressed): the `_atom_site` loop and the `_cell`
//! lengths and angles, read in Rust from the file's tokens ([`super::cif_lexer`]), so no C++
//! parser sees an mmCIF file's bytes. chemfiles 0.10's reader split rows at spaces and lines: a
//! tab in a row or a row cut short crashed it (a segmentation fault), a blank line inside the
//! loop ended the atoms there (1gbt read as 100 of its 1761 atoms), quoted values kept their
//! quotes (`"O5'"`) and a quoted value with a space broke the row.
//!
//! What it gives is what the chemfiles path gave (`tests/it/io_mmcif.rs` compares both on every
//! mmCIF file in `tests/data`), with the B-factors, occupancies and serials that path took from
//! pdbtbx for plain files (and lost for compressed ones):
//!
//! - One atom per row, in file order. Name `label_atom_id` (else `label`, else `auth_atom_id`;
//!   the type when empty), type `type_symbol` (the name when absent), element the type's
//!   symbol, mass the type's when it differs from the name (0 otherwise, completed later from
//!   the element), charge `formal_charge` when the loop has that column, B-factor
//!   `B_iso_or_equiv`, occupancy, serial `id`. Numbers may carry an uncertainty, `12.34(5)`.
//! - Residues group atoms by (`label_asym_id`, number) over the model, named by the first atom's
//!   `label_comp_id`; the number is `label_seq_id`, or where that is not a number (waters,
//!   ligands) `auth_seq_id`, else `label_entity_id`, else 0 (see [`super::cif_residues`]). The
//!   chain is `label_asym_id` (`auth_` columns stand in for absent `label_` ones). Residue runs
//!   are numbered as everywhere else ([`crate::model::Topology::number_residue_runs`]).
//! - Bonds: with a `pdbx_PDB_model_num` column, the standard residues get their template bonds
//!   and peptide links as chemfiles' PDB reader makes them ([`super::mmcif_bonds`]);
//!   consecutive nucleotides are linked O3'-P (chemfiles linked O3' to O3', and never matched
//!   the quoted primed names anyway).
//! - Frames: a new model starts wherever `pdbx_PDB_model_num` changes; the first model is the
//!   topology. Every model's positions are kept (models of another size fail when read, as
//!   before); the box comes from `_cell.length_a` ... `_cell.angle_gamma` (or `_cell_length_a`
//!   ...), none when the lengths are absent.
//!
//! A damaged loop is an error naming the file and the line, never a smaller atom count: a row
//! with a value too few or too many (the next row no longer starts its own line), a loop that
//! ends inside a row, a coordinate or model number that is not a number, an unclosed quote or
//! text field. Bytes that are not UTF-8 are read as Latin-1.

use std::path::Path;

use glam::Vec3;

use super::IoError;
use super::cif_lexer::{Kind, LexError, Lexer, Token, starts_with_ignore_case};
use super::fast::{QuickMap, TypeTable, empty_topology, free_text, parse_f64};
use super::mmcif_bonds::{Residue, link_standard_residues};
use crate::model::elements::canonical_symbol;
use crate::model::{Frame, Topology};

mod atom_site;
#[cfg(test)]
mod tests;

use atom_site::*;

/// An mmCIF file read: the first model's topology (radii still 0, as the chemfiles path leaves
/// it before [`Topology::complete_elements_and_radii`]) and every model as a frame.
pub(crate) struct CifRead {
    pub topology: Topology,
    pub frames: Vec<Frame>,
}

/// Reads the mmCIF text `bytes` of `path` (already decompressed); see the module notes.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<CifRead, IoError> {
    let mut lexer = Lexer::new(bytes);
    let mut cell = [None::<f64>; 6];
    let mut atoms = None;
    let mut token = next(path, &mut lexer)?;
    while let Some(t) = token {
        token = match t.kind {
            Kind::Tag => match next(path, &mut lexer)? {
                Some(v) if v.kind.is_value() => {
                    if let Some(k) = cell_slot(text(bytes, &t)) {
                        cell[k] = cell[k].or_else(|| number(bytes, &v));
                    }
                    next(path, &mut lexer)?
                }
                other => other,
            },
            Kind::Loop => {
                let mut tags = Vec::new();
                let mut n = next(path, &mut lexer)?;
                while let Some(tag) = n.filter(|n| n.kind == Kind::Tag) {
                    tags.push(tag);
                    n = next(path, &mut lexer)?;
                }
                let atom_site = tags
                    .first()
                    .is_some_and(|t| starts_with_ignore_case(text(bytes, t), b"_atom_site."));
                if atom_site && atoms.is_none() {
                    let mut loop_reader = AtomSite::new(path, bytes, &tags)?;
                    while let Some(v) = n.filter(|n| n.kind.is_value()) {
                        loop_reader.push(v)?;
                        n = next(path, &mut lexer)?;
                    }
                    atoms = Some(loop_reader.finish(n.is_none())?);
                } else {
                    while n.is_some_and(|n| n.kind.is_value()) {
                        n = next(path, &mut lexer)?;
                    }
                }
                n
            }
            _ => next(path, &mut lexer)?,
        };
    }
    let Some(mut read) = atoms else {
        return Err(IoError::unreadable(
            path,
            "no _atom_site loop (is this an mmCIF file?)",
        ));
    };
    let box_rows = cell_rows(&cell);
    for frame in &mut read.frames {
        frame.cell = box_rows;
    }
    Ok(read)
}

/// The next token, or the lexer's error naming the file and line.
fn next(path: &Path, lexer: &mut Lexer) -> Result<Option<Token>, IoError> {
    lexer
        .next_token()
        .map_err(|LexError { line, reason }| at_line(path, line, reason))
}

/// An error naming `path` and `line`.
fn at_line(path: &Path, line: usize, message: impl std::fmt::Display) -> IoError {
    IoError::unreadable(path, format!("line {line}: {message}"))
}

/// The bytes of a token.
fn text<'a>(bytes: &'a [u8], t: &Token) -> &'a [u8] {
    &bytes[t.start..t.end]
}

/// A token as a number, without an uncertainty in parentheses (`1.234(5)`); `None` for `?`,
/// `.` and anything that is not a number.
fn number(bytes: &[u8], t: &Token) -> Option<f64> {
    if !matches!(t.kind, Kind::Value | Kind::Quoted) {
        return None;
    }
    let raw = text(bytes, t);
    match memchr::memchr(b'(', raw) {
        // The uncertainty is dropped (chemfiles dropped only the parentheses: 10.0(2) was 10.02).
        Some(k) if raw.ends_with(b")") => parse_f64(&raw[..k]),
        _ => parse_f64(raw),
    }
}

/// A token as an integer (`None` for anything else).
fn integer(bytes: &[u8], t: &Token) -> Option<i64> {
    std::str::from_utf8(text(bytes, t)).ok()?.parse().ok()
}

/// Which of the six cell parameters (a, b, c in Å, then alpha, beta, gamma in degrees) `tag`
/// sets, if any.
fn cell_slot(tag: &[u8]) -> Option<usize> {
    const NAMES: [&[u8]; 6] = [
        b"length_a",
        b"length_b",
        b"length_c",
        b"angle_alpha",
        b"angle_beta",
        b"angle_gamma",
    ];
    let item = if starts_with_ignore_case(tag, b"_cell.") || starts_with_ignore_case(tag, b"_cell_")
    {
        &tag[6..]
    } else {
        return None;
    };
    NAMES.iter().position(|n| item.eq_ignore_ascii_case(n))
}

/// The box rows (Å) of the cell parameters, as chemfiles builds a cell from lengths and angles
/// (angles 90° where absent); `None` when no length is given or the cell is not a cell.
fn cell_rows(cell: &[Option<f64>; 6]) -> Option<[Vec3; 3]> {
    let lengths = [0, 1, 2].map(|k| cell[k].unwrap_or(0.0));
    let angles = [3, 4, 5].map(|k| cell[k].unwrap_or(90.0));
    if lengths == [0.0; 3] || !lengths.iter().chain(&angles).all(|v| v.is_finite()) {
        return None;
    }
    // The cell matrix exactly as the chemfiles path had it.
    super::unit_cell::from_record(lengths, angles)
        .ok()
        .flatten()
}
