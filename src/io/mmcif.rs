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
//!   are numbered as everywhere else ([`super::chem::number_residue_runs`]).
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
    // Numbers only (no byte of the file): the cell matrix exactly as the chemfiles path had it.
    super::quiet::silenced(|| {
        super::chem::cell_rows_of(&chemfiles::UnitCell::triclinic(lengths, angles))
    })
    .ok()
    .flatten()
}

/// Column positions in the `_atom_site` loop.
#[derive(Default)]
struct Columns {
    id: Option<usize>,
    type_symbol: Option<usize>,
    name: Option<usize>,
    comp: Option<usize>,
    asym: Option<usize>,
    auth_asym: Option<usize>,
    entity: Option<usize>,
    label_seq: Option<usize>,
    auth_seq: Option<usize>,
    x: usize,
    y: usize,
    z: usize,
    occupancy: Option<usize>,
    b_factor: Option<usize>,
    formal_charge: Option<usize>,
    model: Option<usize>,
}

/// Derived once per distinct (name, type): ids in the topology's labels, mass, charge.
type Derived = (u32, u32, u32, f32, f32);

/// The `_atom_site` loop being read, row by row.
struct AtomSite<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    columns: Columns,
    width: usize,
    /// The values of the row being read.
    row: Vec<Token>,
    /// Whether the first row started its line (then every row must).
    rows_start_lines: Option<bool>,
    /// The model number of the last row, and how many models have started.
    model: Option<u64>,
    models: usize,
    top: Topology,
    derived: QuickMap<(&'a [u8], &'a [u8]), Derived>,
    types: TypeTable,
    residues: Vec<Residue<'a>>,
    residue_of_key: QuickMap<(&'a [u8], i64), u32>,
    /// Each atom's residue (`u32::MAX`: none).
    group: Vec<u32>,
    positions: Vec<Vec<Vec3>>,
}

impl<'a> AtomSite<'a> {
    /// A reader for the loop whose tags are `tags`; fails without coordinate columns.
    fn new(path: &'a Path, bytes: &'a [u8], tags: &[Token]) -> Result<Self, IoError> {
        let names: Vec<&[u8]> = tags
            .iter()
            .map(|t| {
                text(bytes, t)
                    .get(b"_atom_site.".len()..)
                    .unwrap_or_default()
            })
            .collect();
        let at = |name: &str| {
            names
                .iter()
                .position(|n| n.eq_ignore_ascii_case(name.as_bytes()))
        };
        let coordinate = |name: &str| {
            at(name).ok_or_else(|| {
                at_line(
                    path,
                    tags[0].line,
                    format!("the _atom_site loop has no {name} column"),
                )
            })
        };
        let columns = Columns {
            id: at("id"),
            type_symbol: at("type_symbol"),
            name: at("label_atom_id")
                .or_else(|| at("label"))
                .or_else(|| at("auth_atom_id")),
            comp: at("label_comp_id").or_else(|| at("auth_comp_id")),
            asym: at("label_asym_id").or_else(|| at("auth_asym_id")),
            auth_asym: at("auth_asym_id"),
            entity: at("label_entity_id"),
            label_seq: at("label_seq_id"),
            auth_seq: at("auth_seq_id"),
            x: coordinate("Cartn_x")?,
            y: coordinate("Cartn_y")?,
            z: coordinate("Cartn_z")?,
            occupancy: at("occupancy"),
            b_factor: at("B_iso_or_equiv"),
            formal_charge: at("formal_charge"),
            model: at("pdbx_PDB_model_num"),
        };
        Ok(AtomSite {
            path,
            bytes,
            columns,
            width: tags.len(),
            row: Vec::with_capacity(tags.len()),
            rows_start_lines: None,
            model: None,
            models: 0,
            top: empty_topology(0),
            derived: QuickMap::default(),
            types: TypeTable::default(),
            residues: Vec::new(),
            residue_of_key: QuickMap::default(),
            group: Vec::new(),
            positions: Vec::new(),
        })
    }

    /// Takes the next value of the loop. A complete row is read once the value after it
    /// arrives: when rows start their lines, a row that does not shows that the row before it
    /// has a value too few or too many, and that row is the one reported.
    fn push(&mut self, value: Token) -> Result<(), IoError> {
        if self.row.len() == self.width {
            let starts_line = *self
                .rows_start_lines
                .get_or_insert(self.row[0].first_on_line);
            if starts_line && !value.first_on_line {
                return Err(self.bad_row(&self.row[0], ""));
            }
            self.take_row()?;
            self.row.clear();
        }
        self.row.push(value);
        Ok(())
    }

    /// The error for the row starting with `first`, which has a value too few or too many:
    /// counts the values on its first line.
    fn bad_row(&self, first: &Token, note: &str) -> IoError {
        let line_start = memchr::memrchr(b'\n', &self.bytes[..first.start]).map_or(0, |k| k + 1);
        let values = Lexer::new(&self.bytes[line_start..])
            .map_while(Result::ok)
            .take_while(|t| t.line == 1 && t.kind.is_value())
            .count();
        let width = self.width;
        let message = if values < width {
            format!("an _atom_site row with {values} of its {width} values{note}")
        } else {
            format!("an _atom_site row with {values} values where the loop has {width} columns")
        };
        at_line(self.path, first.line, message)
    }

    /// Reads the complete row in `self.row`.
    fn take_row(&mut self) -> Result<(), IoError> {
        let bytes = self.bytes;
        let row = &self.row;
        let c = &self.columns;
        if let Some(m) = c.model {
            let t = &row[m];
            let model = match t.kind {
                Kind::Unknown | Kind::Inapplicable => self.model.unwrap_or(0),
                _ => std::str::from_utf8(text(bytes, t))
                    .ok()
                    .and_then(|s| s.parse::<u64>().ok())
                    .ok_or_else(|| self.not_a_number(t, "pdbx_PDB_model_num", "a model number"))?,
            };
            if self.model != Some(model) {
                self.model = Some(model);
                self.models += 1;
                self.positions.push(Vec::new());
            }
        } else if self.models == 0 {
            self.models = 1;
            self.positions.push(Vec::new());
        }
        let mut xyz = [0f32; 3];
        for (k, (column, name)) in [(c.x, "Cartn_x"), (c.y, "Cartn_y"), (c.z, "Cartn_z")]
            .into_iter()
            .enumerate()
        {
            let t = &row[column];
            xyz[k] = number(bytes, t).ok_or_else(|| self.not_a_number(t, name, "a number"))? as f32;
        }
        let frame = self.positions.last_mut().expect("a model was started");
        frame.push(Vec3::from_array(xyz));
        if self.models == 1 {
            self.take_atom()?;
        }
        Ok(())
    }

    /// The error for a value of column `column` that is not `what`.
    fn not_a_number(&self, t: &Token, column: &str, what: &str) -> IoError {
        let value = free_text(text(self.bytes, t));
        at_line(
            self.path,
            t.line,
            format!("_atom_site.{column} is '{value}', not {what}"),
        )
    }

    /// A value of column `column` (`name`) as a number; `None` for `?` and `.`, an error for
    /// anything else that is not a number.
    fn optional_number(&self, column: Option<usize>, name: &str) -> Result<Option<f64>, IoError> {
        let Some(t) = column.map(|k| &self.row[k]) else {
            return Ok(None);
        };
        if matches!(t.kind, Kind::Unknown | Kind::Inapplicable) {
            return Ok(None);
        }
        number(self.bytes, t)
            .map(Some)
            .ok_or_else(|| self.not_a_number(t, name, "a number"))
    }

    /// Adds the atom of the row in `self.row` (of the first model) to the topology.
    fn take_atom(&mut self) -> Result<(), IoError> {
        let b_factor = self.optional_number(self.columns.b_factor, "B_iso_or_equiv")?;
        let occupancy = self.optional_number(self.columns.occupancy, "occupancy")?;
        let bytes = self.bytes;
        let row = &self.row;
        let c = &self.columns;
        let index = self.group.len();
        let get = |column: Option<usize>| column.map(|k| &row[k]);
        let value = |column: Option<usize>| get(column).map_or(&b""[..], |t| text(bytes, t));
        // Name, type, element, mass and charge, once per distinct (name, type).
        let raw_name = value(c.name);
        let kind = match c.type_symbol {
            Some(k) => text(bytes, &row[k]),
            None => raw_name,
        };
        let (top, types) = (&mut self.top, &mut self.types);
        let &mut (name, kind, element, mass, charge) =
            self.derived.entry((raw_name, kind)).or_insert_with(|| {
                let kind = free_text(kind);
                let name = match free_text(raw_name) {
                    n if n.trim().is_empty() => kind.clone(),
                    n => n,
                };
                // chemfiles' mass and charge of the type (a table lookup, for the types it
                // can know: element symbols).
                let (mass, charge) = if kind.len() <= 3 && !kind.contains('\0') {
                    types.get(&kind)
                } else {
                    (0.0, 0.0)
                };
                let mass = if kind != name && mass.is_finite() {
                    mass
                } else {
                    0.0
                };
                let element = canonical_symbol(&kind).unwrap_or_default();
                (
                    top.names.intern(&name),
                    top.types.intern(&kind),
                    top.elements.intern(element),
                    mass,
                    charge,
                )
            });
        top.names.push_id(name);
        top.types.push_id(kind);
        top.elements.push_id(element);
        top.masses.push(mass);
        let formal = get(c.formal_charge).and_then(|t| number(bytes, t));
        top.charges.push(formal.map_or(charge, |q| q as f32));
        top.b_factors.push(b_factor.map_or(0.0, |b| b as f32));
        top.occupancies.push(occupancy.map_or(1.0, |o| o as f32));
        let serial = get(c.id).and_then(|t| integer(bytes, t));
        top.serials.push(serial.unwrap_or(index as i64 + 1));
        // The residue: (asym id, number), the number falling back as cif_residues says.
        let (Some(comp), Some(asym)) = (get(c.comp), get(c.asym)) else {
            self.group.push(u32::MAX);
            return Ok(());
        };
        let number = |column: Option<usize>| get(column).and_then(|t| integer(bytes, t));
        let id = number(c.label_seq)
            .or_else(|| number(c.auth_seq))
            .or_else(|| number(c.entity))
            .unwrap_or(0);
        let asym = text(bytes, asym);
        let chain = match asym.trim_ascii() {
            [] => value(c.auth_asym).trim_ascii(),
            chain => chain,
        };
        let next = self.residues.len() as u32;
        let r = *self.residue_of_key.entry((asym, id)).or_insert(next);
        if r == next {
            self.residues.push(Residue {
                name: text(bytes, comp),
                id,
                chain,
                atoms: Vec::new(),
            });
        }
        self.residues[r as usize].atoms.push(index as u32);
        self.group.push(r);
        Ok(())
    }

    /// The topology and frames once the loop has ended (`at_end`: with the file).
    fn finish(mut self, at_end: bool) -> Result<CifRead, IoError> {
        if self.row.len() == self.width {
            self.take_row()?;
            self.row.clear();
        }
        if let Some(first) = self.row.first() {
            let note = if at_end {
                " (is the file cut short?)"
            } else {
                ""
            };
            return Err(self.bad_row(first, note));
        }
        let Some(first) = self.positions.first() else {
            return Err(IoError::Empty {
                path: self.path.to_path_buf(),
                what: "no atoms",
            });
        };
        let n = first.len();
        let mut top = std::mem::replace(&mut self.top, empty_topology(0));
        let defaults = empty_topology(n);
        (top.residue_names, top.residue_ids, top.residue_index) = (
            defaults.residue_names,
            defaults.residue_ids,
            defaults.residue_index,
        );
        (top.chains, top.segments, top.radii) =
            (defaults.chains, defaults.segments, defaults.radii);
        for residue in &self.residues {
            let name = top.residue_names.intern(&free_text(residue.name));
            let chain = top.chains.intern(&free_text(residue.chain));
            for &a in &residue.atoms {
                top.residue_names.set_id(a as usize, name);
                top.residue_ids[a as usize] = residue.id;
                top.chains.set_id(a as usize, chain);
            }
        }
        super::chem::number_residue_runs(&mut top, &self.group);
        if self.columns.model.is_some() {
            let mut bonds = link_standard_residues(&self.residues, &top.names);
            bonds.sort_unstable();
            bonds.dedup();
            top.bonds = bonds;
        }
        let frames = self
            .positions
            .into_iter()
            .enumerate()
            .map(|(index, positions)| Frame {
                index,
                time_ps: None,
                positions,
                cell: None,
            })
            .collect();
        Ok(CifRead {
            topology: top,
            frames,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "data_x\n_cell.length_a 10.0(2)\n_cell.length_b 20\n\
        _cell.length_c 30\n#\nloop_\n_atom_site.group_PDB\n_atom_site.id\n\
        _atom_site.type_symbol\n_atom_site.label_atom_id\n_atom_site.label_comp_id\n\
        _atom_site.label_asym_id\n_atom_site.label_entity_id\n_atom_site.label_seq_id\n\
        _atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n\
        _atom_site.B_iso_or_equiv\n_atom_site.auth_seq_id\n_atom_site.pdbx_PDB_model_num\n";

    fn read_text(text: &str) -> Result<CifRead, IoError> {
        read(Path::new("t.cif"), text.as_bytes())
    }

    fn glycines(model: u32, dx: f32) -> String {
        let mut out = String::new();
        for (k, name) in ["N", "CA", "C", "O"].iter().enumerate() {
            for res in 1..=2 {
                let serial = res * 10 + k;
                let x = k as f32 + 5.0 * res as f32 + dx;
                out += &format!(
                    "ATOM {serial} {} {name} GLY A 1 {res} {x:.3} 0.5 -1.25 {}.5 {res} {model}\n",
                    &name[..1],
                    k
                );
            }
        }
        out
    }

    #[test]
    fn atoms_residues_bonds_models_and_cell() {
        let text = format!(
            "{HEADER}{}{}HETATM 99 O O HOH B 2 . 1 2 3 ? 301 1\n#\n",
            glycines(1, 0.0),
            glycines(2, 0.25)
        );
        // Model 2 has no water: the model numbers are 1, 1, ..., 2, 2, ..., 1.
        let read = read_text(&text).expect("reads");
        assert_eq!(read.frames.len(), 3);
        let top = &read.topology;
        assert_eq!(top.len(), 8);
        assert_eq!(top.names.to_strings()[..4], ["N", "N", "CA", "CA"]);
        assert_eq!(top.elements.to_strings()[..3], ["N", "N", "C"]);
        assert_eq!(top.residue_ids, [1, 2, 1, 2, 1, 2, 1, 2]);
        // Two residues, interleaved in the file: runs of one atom each.
        assert_eq!(top.residue_index, [0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(&top.chains[0], "A");
        assert_eq!(top.b_factors[2], 1.5);
        assert_eq!(top.serials[..2], [10, 20]);
        // GLY N-CA, CA-C, C-O in each residue and the peptide link C(1)-N(2).
        let bonds: Vec<[u32; 2]> = vec![[0, 2], [1, 3], [1, 4], [2, 4], [3, 5], [4, 6], [5, 7]];
        assert_eq!(top.bonds, bonds);
        assert_eq!(read.frames[0].positions[0], Vec3::new(5.0, 0.5, -1.25));
        assert_eq!(read.frames[1].positions[0], Vec3::new(5.25, 0.5, -1.25));
        assert_eq!(read.frames[2].positions, [Vec3::new(1.0, 2.0, 3.0)]);
        let cell = read.frames[0].cell.expect("a box");
        assert!(
            cell[0].abs_diff_eq(Vec3::new(10.0, 0.0, 0.0), 1e-5),
            "{cell:?}"
        );
        assert!(
            cell[2].abs_diff_eq(Vec3::new(0.0, 0.0, 30.0), 1e-5),
            "{cell:?}"
        );
    }

    #[test]
    fn quoted_primed_names_link_nucleotides_o3_to_p() {
        let mut text = HEADER.to_string();
        let names = ["P", "\"O5'\"", "\"C5'\"", "\"C4'\"", "\"C3'\"", "'O3''"];
        for res in 1..=2 {
            for (k, name) in names.iter().enumerate() {
                let serial = res * 10 + k;
                let x = (res * 10 + k) as f32;
                text += &format!("ATOM {serial} X {name} DA B 1 {res} {x} 0 0 1 {res} 1\n");
            }
        }
        let read = read_text(&text).expect("reads");
        let top = &read.topology;
        assert_eq!(&top.names[1], "O5'");
        assert_eq!(&top.names[5], "O3'");
        let chain = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5]];
        let mut want: Vec<[u32; 2]> = chain.to_vec();
        want.extend(chain.iter().map(|[a, b]| [a + 6, b + 6]));
        // O3' of the first nucleotide to P of the second.
        want.push([5, 6]);
        want.sort_unstable();
        assert_eq!(top.bonds, want);
    }

    #[test]
    fn damaged_rows_name_their_line() {
        let good = glycines(1, 0.0);
        let lines: Vec<&str> = good.lines().collect();
        let first_row = HEADER.lines().count() + 1;
        // A value missing from the third row.
        let short = lines[2].replacen(" GLY", "", 1);
        let text = format!(
            "{HEADER}{}\n{}\n{short}\n{}\n",
            lines[0], lines[1], lines[3]
        );
        let e = read_text(&text).err().expect("a short row").to_string();
        assert!(
            e.contains(&format!(
                "line {}: an _atom_site row with 13 of its 14 values",
                first_row + 2
            )),
            "{e}"
        );
        // A value too many.
        let long = format!("{} 7", lines[1]);
        let text = format!("{HEADER}{}\n{long}\n{}\n", lines[0], lines[2]);
        let e = read_text(&text).err().expect("a long row").to_string();
        assert!(
            e.contains("row with 15 values where the loop has 14"),
            "{e}"
        );
        // Cut inside the last row.
        let text = format!("{HEADER}{}\nATOM 3 C", lines[0]);
        let e = read_text(&text).err().expect("a cut row").to_string();
        assert!(
            e.contains("of its 14 values (is the file cut short?)"),
            "{e}"
        );
        // A coordinate that is not a number.
        let text = format!("{HEADER}{}\n", lines[0].replace("0.5", "0.5x"));
        let e = read_text(&text).err().expect("a bad number").to_string();
        assert!(
            e.contains(&format!(
                "line {first_row}: _atom_site.Cartn_y is '0.5x', not a number"
            )),
            "{e}"
        );
        let e = read_text("data_x\n_cell.length_a 3\n")
            .err()
            .expect("no loop");
        assert!(e.to_string().contains("no _atom_site loop"), "{e}");
        let e = read_text(&format!("{HEADER}#\n")).err().expect("no atoms");
        assert!(matches!(e, IoError::Empty { .. }), "{e}");
    }
}
