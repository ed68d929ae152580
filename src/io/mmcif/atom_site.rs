//! The `_atom_site` loop: its column positions, and the atoms, residues, bonds and models read
//! from its rows.

use super::*;

/// Column positions in the `_atom_site` loop.
#[derive(Default)]
pub(super) struct Columns {
    pub(super) id: Option<usize>,
    pub(super) type_symbol: Option<usize>,
    pub(super) name: Option<usize>,
    pub(super) comp: Option<usize>,
    pub(super) asym: Option<usize>,
    pub(super) auth_asym: Option<usize>,
    pub(super) entity: Option<usize>,
    pub(super) label_seq: Option<usize>,
    pub(super) auth_seq: Option<usize>,
    pub(super) x: usize,
    pub(super) y: usize,
    pub(super) z: usize,
    pub(super) occupancy: Option<usize>,
    pub(super) b_factor: Option<usize>,
    pub(super) formal_charge: Option<usize>,
    pub(super) model: Option<usize>,
}

/// Derived once per distinct (name, type): ids in the topology's labels, mass, charge.
pub(super) type Derived = (u32, u32, u32, f32, f32);

/// The `_atom_site` loop being read, row by row.
pub(super) struct AtomSite<'a> {
    pub(super) path: &'a Path,
    pub(super) bytes: &'a [u8],
    pub(super) columns: Columns,
    pub(super) width: usize,
    /// The values of the row being read.
    pub(super) row: Vec<Token>,
    /// Whether the first row started its line (then every row must).
    pub(super) rows_start_lines: Option<bool>,
    /// The model number of the last row, and how many models have started.
    pub(super) model: Option<u64>,
    pub(super) models: usize,
    pub(super) top: Topology,
    pub(super) derived: QuickMap<(&'a [u8], &'a [u8]), Derived>,
    pub(super) types: TypeTable,
    pub(super) residues: Vec<Residue<'a>>,
    pub(super) residue_of_key: QuickMap<(&'a [u8], i64), u32>,
    /// Each atom's residue (`u32::MAX`: none).
    pub(super) group: Vec<u32>,
    pub(super) positions: Vec<Vec<Vec3>>,
}

impl<'a> AtomSite<'a> {
    /// A reader for the loop whose tags are `tags`; fails without coordinate columns.
    pub(super) fn new(path: &'a Path, bytes: &'a [u8], tags: &[Token]) -> Result<Self, IoError> {
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
    pub(super) fn push(&mut self, value: Token) -> Result<(), IoError> {
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
    pub(super) fn bad_row(&self, first: &Token, note: &str) -> IoError {
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
    pub(super) fn take_row(&mut self) -> Result<(), IoError> {
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
    pub(super) fn not_a_number(&self, t: &Token, column: &str, what: &str) -> IoError {
        let value = free_text(text(self.bytes, t));
        at_line(
            self.path,
            t.line,
            format!("_atom_site.{column} is '{value}', not {what}"),
        )
    }

    /// A value of column `column` (`name`) as a number; `None` for `?` and `.`, an error for
    /// anything else that is not a number.
    pub(super) fn optional_number(
        &self,
        column: Option<usize>,
        name: &str,
    ) -> Result<Option<f64>, IoError> {
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
    pub(super) fn take_atom(&mut self) -> Result<(), IoError> {
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
    pub(super) fn finish(mut self, at_end: bool) -> Result<CifRead, IoError> {
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
        top.number_residue_runs(&self.group);
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
