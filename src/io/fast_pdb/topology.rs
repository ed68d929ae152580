//! Building the topology from the parsed pieces in file order: CRYST1 boxes, models, TER
//! segments, residues grouped as chemfiles groups them, template bonds and links, CONECT bonds.

use super::*;

impl Reader {
    pub(super) fn cryst1(&mut self, line: &[u8]) -> Option<()> {
        if line.len() < 54 {
            return None;
        }
        let v = |a: usize, b: usize| parse_f64(cols(line, a, b));
        let lengths = [v(6, 15)?, v(15, 24)?, v(24, 33)?];
        let angles = [v(33, 40)?, v(40, 47)?, v(47, 54)?];
        self.cell = Some((lengths, angles));
        Some(())
    }

    /// An atom joins: its name and element column are `names` and `kinds` ids.
    pub(super) fn atom(&mut self, atom: &ParsedAtom, (name, kind): (u32, u32)) {
        let line = atom.line;
        if self.offsets.is_empty() {
            let first = decode_hybrid36(5, cols(line, 6, 11)).unwrap_or(1);
            self.offsets.push(if first <= 0 { 0 } else { first - 1 });
        }
        let index = self.names.len() as u32;
        self.names.push_id(name);
        self.kinds.push_id(kind);
        self.kind_given.push(atom.kind_given);
        self.positions.push(atom.position);
        let code = usize::from(atom.chain_code);
        let chain = match self.chain_ids[code] {
            Some(id) => id,
            None => {
                let text = match u8::try_from(code) {
                    Ok(b) => char::from(b).to_string(),
                    Err(_) => String::new(),
                };
                let id = self.column_chains.intern(&text);
                self.chain_ids[code] = Some(id);
                id
            }
        };
        self.columns.push(Columns {
            chain,
            ..atom.columns
        });
        self.residue_of.push(u32::MAX);
        let Some(key) = atom.residue else {
            return; // no residue
        };
        let slot = match self.last_residue {
            Some((last, slot)) if last == key => slot,
            _ => match self.segment_index.get(&key) {
                Some(&slot) => slot,
                None => {
                    let (chain, _, _, _) = key;
                    let chain_text = columns_text(&[chain]);
                    let segment = if line.len() > 72 {
                        columns_text(trim(cols(line, 72, 76)))
                    } else {
                        String::new()
                    };
                    let chain = match chain_text.trim() {
                        "" => segment.trim().to_string(),
                        c => c.to_string(),
                    };
                    self.segment.push(Residue {
                        key,
                        name: columns_text(trim(cols(line, 17, 20))),
                        chain,
                        segment: segment.trim().to_string(),
                        atoms: Vec::new(),
                    });
                    self.segment_index.insert(key, self.segment.len() - 1);
                    self.segment.len() - 1
                }
            },
        };
        self.last_residue = Some((key, slot));
        self.segment[slot].atoms.push(index);
    }

    /// chemfiles' `read_CONECT`: serials map to atoms through the first serial and the TER
    /// serials seen so far; bonds to atoms not (yet) read are dropped.
    pub(super) fn conect(&mut self, line: &[u8]) -> Option<()> {
        if line.len() < 11 {
            return None;
        }
        let length = trim(line).len();
        let n = self.names.len() as i64;
        // No first serial yet (no atom parsed, though one was seen): not a file this reader
        // reproduces (found by fuzzing: it indexed an empty list).
        let first = *self.offsets.first()?;
        let index = |at: usize| -> Option<i64> {
            let id = decode_hybrid36(5, cols(line, at, at + 5))?;
            let below = self.offsets.partition_point(|&o| o < id) as i64;
            Some(id - below - first)
        };
        let i = index(6)?;
        for at in [11, 16, 21, 26] {
            if length <= at {
                break;
            }
            let j = index(at)?;
            if (0..n).contains(&i) && (0..n).contains(&j) {
                if i == j {
                    return None; // chemfiles refuses the file
                }
                self.bonds.push([i as u32, j as u32]);
            }
        }
        Some(())
    }

    /// chemfiles' `chain_ended`: the segment's residues join the topology in key order.
    pub(super) fn chain_ended(&mut self) {
        let mut segment = std::mem::take(&mut self.segment);
        self.segment_index.clear();
        self.last_residue = None;
        segment.sort_by_key(|r| r.key);
        for residue in segment {
            let index = self.residues.len() as u32;
            for &a in &residue.atoms {
                self.residue_of[a as usize] = index;
            }
            self.residues.push(residue);
        }
    }

    /// chemfiles' `link_standard_residue_bonds`; `None` where chemfiles would fail. Atom names
    /// are compared as ids: those of [`Reader::names`], and ids past them for template names
    /// no atom has.
    pub(super) fn link_standard_residues(&mut self) -> Option<()> {
        const SPECIAL: [&str; 6] = ["N", "C", "O3'", "P", "HO5'", "O5'"];
        let absent = self.names.distinct().0.len() as u32;
        let id_of = |name: &str| -> u32 {
            self.names
                .find(name)
                .unwrap_or_else(|| match NAMES.iter().position(|n| *n == name) {
                    Some(k) => absent + k as u32,
                    None => {
                        let k = SPECIAL.iter().position(|n| *n == name).unwrap_or(0);
                        absent + (NAMES.len() + k) as u32
                    }
                })
        };
        let template: Vec<u32> = NAMES.iter().map(|n| id_of(n)).collect();
        let [n_id, c_id, o3_id, p_id, ho5_id, o5_id] = SPECIAL.map(id_of);
        let mut link_peptide = false;
        let mut link_nucleic = false;
        let mut previous_id = 0i64;
        let mut previous_link = 0u32;
        let mut bonds = Vec::new();
        let mut by_name: Vec<(u32, u32)> = Vec::new();
        for residue in &self.residues {
            let Ok(t) = RESIDUES.binary_search_by(|(n, _)| n.cmp(&residue.name.as_str())) else {
                continue;
            };
            by_name.clear();
            for &a in &residue.atoms {
                let name = self.names.id(a as usize);
                match by_name.iter_mut().find(|(n, _)| *n == name) {
                    Some(slot) => slot.1 = a,
                    None => by_name.push((name, a)),
                }
            }
            let find = |by_name: &[(u32, u32)], name: u32| {
                by_name.iter().find(|(n, _)| *n == name).map(|&(_, a)| a)
            };
            let id = residue.key.1;
            let nitrogen = find(&by_name, n_id);
            if link_peptide
                && let Some(n) = nitrogen
                && id == previous_id + 1
            {
                link_peptide = false;
                bonds.push([previous_link, n]);
            }
            if let Some(c) = find(&by_name, c_id) {
                link_peptide = true;
                previous_link = c;
                previous_id = id;
            }
            let o3 = find(&by_name, o3_id);
            if link_nucleic && find(&by_name, p_id).is_some() && id == previous_id + 1 {
                link_nucleic = false;
                // chemfiles links the previous O3' to this residue's O3' (and reads past its
                // map when there is none).
                bonds.push([previous_link, o3?]);
            }
            if let Some(o) = o3 {
                link_nucleic = true;
                previous_link = o;
                previous_id = id;
            }
            if let Some(h) = find(&by_name, ho5_id) {
                // `map["O5'"]` inserts atom 0 when the residue has no O5'.
                let o5 = match find(&by_name, o5_id) {
                    Some(o) => o,
                    None => {
                        by_name.push((o5_id, 0));
                        0
                    }
                };
                bonds.push([h, o5]);
            }
            for &(a, b) in RESIDUES[t].1 {
                let (Some(a), Some(b)) = (
                    find(&by_name, template[a as usize]),
                    find(&by_name, template[b as usize]),
                ) else {
                    continue;
                };
                bonds.push([a, b]);
            }
        }
        if bonds.iter().any(|[a, b]| a == b) {
            return None;
        }
        self.bonds.extend(bonds);
        Some(())
    }

    /// The topology and frame as the chemfiles path leaves them after enrichment and CONECT.
    pub(super) fn finish(self, pieces: &[Piece]) -> Option<FastRead> {
        let n = self.names.len();
        let mut top = empty_topology(n);
        let mut table = TypeTable::default();
        // Name, type, element, mass and charge follow from the (name, type) pair: worked out
        // once per distinct pair.
        type Derived = (u32, u32, u32, f32, f32);
        let mut derived: QuickMap<(u32, u32), Derived> = QuickMap::default();
        for i in 0..n {
            let given = self.kind_given[i];
            let key = (
                self.names.id(i),
                if given { self.kinds.id(i) } else { u32::MAX },
            );
            let (name, kind, element, mass, charge) = match derived.get(&key) {
                Some(&d) => d,
                None => {
                    let raw_name = &self.names[i];
                    let kind = if given { &self.kinds[i] } else { raw_name };
                    let name = if raw_name.trim().is_empty() {
                        kind
                    } else {
                        raw_name
                    };
                    let (mass, charge) = table.get(kind);
                    let (element, mass) = if kind != name {
                        (canonical_symbol(kind).unwrap_or_default(), mass)
                    } else {
                        ("", 0.0)
                    };
                    let d = (
                        top.names.intern(name),
                        top.types.intern(kind),
                        top.elements.intern(element),
                        if mass.is_finite() { mass } else { 0.0 },
                        charge,
                    );
                    derived.insert(key, d);
                    d
                }
            };
            top.masses.push(mass);
            top.charges.push(charge);
            top.elements.push_id(element);
            top.types.push_id(kind);
            top.names.push_id(name);
        }
        for residue in &self.residues {
            let name = top.residue_names.intern(&residue.name);
            let chain = top.chains.intern(&residue.chain);
            let segment = top.segments.intern(&residue.segment);
            let code = match residue.key.2 {
                b' ' | 0 => String::new(),
                c => char::from(c).to_string(),
            };
            let code = top.insertion_codes.intern(&code);
            for &a in &residue.atoms {
                let a = a as usize;
                top.residue_names.set_id(a, name);
                top.residue_ids[a] = residue.key.1;
                top.insertion_codes.set_id(a, code);
                top.chains.set_id(a, chain);
                top.segments.set_id(a, segment);
            }
        }
        top.number_residue_runs(&self.residue_of);
        let mut bonds: Vec<[u32; 2]> = self
            .bonds
            .into_iter()
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        bonds.sort_unstable();
        bonds.dedup();
        top.bonds = bonds;
        apply_enrichment(&mut top, &self.columns, &self.column_chains);
        crate::io::conect::resolve(
            pieces.iter().flat_map(|p| p.conect.iter().copied()),
            &mut top,
        );
        let cell = match self.cell {
            // A box chemfiles refused: the file goes the chemfiles way (and its error).
            Some((lengths, angles)) => crate::io::unit_cell::from_record(lengths, angles).ok()?,
            None => None,
        };
        let frame = Frame {
            index: 0,
            time_ps: None,
            positions: self.positions.into_iter().map(to_vec3).collect(),
            cell,
        };
        Some(FastRead {
            topology: top,
            frame,
        })
    }
}
