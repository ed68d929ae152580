//! Area per residue (the sum over its atoms) and exposure (its area over the largest area a
//! residue of its name has alone).

use std::borrow::Cow;
use std::collections::BTreeMap;

use glam::Vec3;

use super::MeasureError;
use crate::model::pbc::PbcCell;
use crate::model::{Topology, chain_or_segment};
use crate::surface::{AtomSet, SurfaceEngine, SurfaceParams};

/// The area of one residue of a surface. Its names are the topology's, read on demand
/// ([`ResidueArea::names`]): a frame's residues hold no strings of their own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidueArea {
    /// Index of the residue in the topology ([`Topology::residue_index`]).
    pub residue: u32,
    /// A topology atom of the residue in the atom set, the first given (its names are read
    /// from it).
    pub atom: u32,
    /// Atoms of the residue in the atom set.
    pub atoms: usize,
    /// Area in Å² (the sum of its atoms' areas).
    pub area: f64,
}

impl ResidueArea {
    /// The residue's chain, segment, number and name in `topology` (the one it was measured
    /// on; empty names and number 0 past its end).
    pub fn names<'t>(&self, topology: &'t Topology) -> ResidueNames<'t> {
        ResidueNames::of_atom(topology, self.atom as usize)
    }
}

impl<'t> ResidueNames<'t> {
    /// The names of the residue of topology atom `atom`, and the atom's own (empty names and
    /// number 0 past the topology's end).
    pub fn of_atom(topology: &'t Topology, atom: usize) -> ResidueNames<'t> {
        let text = |l: &'t crate::model::Labels| l.get(atom).unwrap_or("");
        ResidueNames {
            chain: text(&topology.chains),
            segment: text(&topology.segments),
            resid: topology.residue_ids.get(atom).copied().unwrap_or(0),
            insertion_code: text(&topology.insertion_codes),
            resname: text(&topology.residue_names),
            atom_name: text(&topology.names),
            serial: (topology.serials.get(atom).copied()).unwrap_or(atom as i64 + 1),
            copy: (topology.residue_index.get(atom))
                .and_then(|&r| topology.residue_copies.get(r as usize).copied())
                .unwrap_or(0),
        }
    }
}

/// A residue's names as the topology holds them (untrimmed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResidueNames<'t> {
    /// Chain identifier (empty when the file has none).
    pub chain: &'t str,
    /// Segment name (empty when the file has none).
    pub segment: &'t str,
    /// Residue number as written in the file.
    pub resid: i64,
    /// Insertion code (`A` of 52A; empty when none).
    pub insertion_code: &'t str,
    /// Residue name (`LEU`).
    pub resname: &'t str,
    /// Name of the atom the names were read from (`CA`).
    pub atom_name: &'t str,
    /// That atom's serial number as written in the file (its place from 1 when the file has
    /// none).
    pub serial: i64,
    /// Which copy the residue is of those sharing its chain (else segment), number and name,
    /// from 1; 0 when it is the only one ([`Topology::residue_copies`]).
    pub copy: u32,
}

impl<'t> ResidueNames<'t> {
    /// The chain, else the segment, trimmed (empty with neither).
    pub fn chain_or_segment(&self) -> &'t str {
        chain_or_segment(self.chain, self.segment)
    }

    /// True for an atom in no residue: no chain, segment or residue name, and number 0 (every
    /// atom of a LAMMPS dump or an XYZ file, which name no residues).
    pub fn is_anonymous(&self) -> bool {
        self.chain_or_segment().is_empty() && self.resname.trim().is_empty() && self.resid == 0
    }

    /// `A:LEU12` (chain, else segment, then name, number and insertion code, `A:SER52A`;
    /// `LEU12` with neither chain nor segment), and
    /// `#2` after it for the second of residues that share all three (`PHE9#1` and `PHE9#2`:
    /// the two monomers of a dimer in a GRO file, which has no chains); for an atom in no
    /// residue ([`Self::is_anonymous`]) the atom's name and serial, `O@340`.
    pub fn label(&self) -> String {
        if self.is_anonymous() {
            format!("{}@{}", self.atom_name.trim(), self.serial)
        } else {
            let label = residue_label(self.chain, self.segment, self.resname, self.resid);
            let code = self.insertion_code.trim();
            match self.copy {
                0 => format!("{label}{code}"),
                copy => format!("{label}{code}#{copy}"),
            }
        }
    }
}

/// `A:LEU12`: the chain (else the segment) and a colon when there is one, then name and number.
pub fn residue_label(chain: &str, segment: &str, resname: &str, resid: i64) -> String {
    let chain = chain_or_segment(chain, segment);
    if chain.is_empty() {
        format!("{}{resid}", resname.trim())
    } else {
        format!("{chain}:{}{resid}", resname.trim())
    }
}

/// True when some atom of the set (the topology atoms `atom_indices`, all for `None`; indices
/// past the topology are skipped) is in a residue, that is not
/// [anonymous](ResidueNames::is_anonymous).
pub fn names_residues(topology: &Topology, atom_indices: Option<&[u32]>) -> bool {
    let named = |atom: usize| !ResidueNames::of_atom(topology, atom).is_anonymous();
    match atom_indices {
        Some(ix) => ix
            .iter()
            .any(|&a| (a as usize) < topology.len() && named(a as usize)),
        None => (0..topology.len()).any(named),
    }
}

/// The topology atoms an atom set holds: `atom_indices`, or all of them for `None`; checked
/// against the topology and against `len`, the number of per-atom values given.
pub(crate) fn topology_atoms<'a>(
    topology: &Topology,
    atom_indices: Option<&'a [u32]>,
    len: usize,
    what: &'static str,
) -> Result<Cow<'a, [u32]>, MeasureError> {
    let indices: Cow<'a, [u32]> = match atom_indices {
        Some(ix) => Cow::Borrowed(ix),
        None => Cow::Owned((0..topology.len() as u32).collect()),
    };
    if indices.len() != len {
        return Err(MeasureError::LengthMismatch {
            what,
            expected: indices.len(),
            got: len,
        });
    }
    let n = topology.len().min(topology.residue_index.len());
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(MeasureError::IndexOutOfRange {
            what: "topology atom",
            index: bad as usize,
            len: n,
        });
    }
    Ok(indices)
}

/// Area per residue in Å²: the sum of `atom_areas` (one per atom of the set, whose topology
/// atoms are `atom_indices`, or all atoms for `None`) over each residue's atoms, residues in
/// topology order, only those with atoms in the set.
///
/// Fails when `atom_areas` and the indices differ in length or an index is past the topology.
pub fn residue_areas(
    topology: &Topology,
    atom_indices: Option<&[u32]>,
    atom_areas: &[f64],
) -> Result<Vec<ResidueArea>, MeasureError> {
    let indices = topology_atoms(topology, atom_indices, atom_areas.len(), "atom areas")?;
    // Each residue's place in `found` (u32::MAX until one of its atoms is seen), then the
    // residues sorted into topology order (stable: they usually come in order already).
    let mut slot = vec![u32::MAX; topology.residue_count()];
    let mut found: Vec<ResidueArea> = Vec::new();
    for (&atom, &area) in indices.iter().zip(atom_areas) {
        let residue = topology.residue_index[atom as usize];
        let place = &mut slot[residue as usize];
        if *place == u32::MAX {
            *place = found.len() as u32;
            found.push(ResidueArea {
                residue,
                atom,
                atoms: 0,
                area: 0.0,
            });
        }
        let r = &mut found[*place as usize];
        r.atoms += 1;
        r.area += area;
    }
    if !found.is_sorted_by_key(|r| r.residue) {
        found.sort_by_key(|r| r.residue);
    }
    Ok(found)
}

/// Moves each of `positions` (Å) after the first to its image nearest the first, where that
/// image is nearer than the position itself.
fn make_whole(positions: &mut [Vec3], cell: &PbcCell) {
    let Some((first, rest)) = positions.split_first_mut() else {
        return;
    };
    let first = *first;
    for p in rest {
        let d = *p - first;
        let nearest = cell.min_image(d);
        if nearest.length_squared() < d.length_squared() {
            *p = first + nearest;
        }
    }
}

/// The largest area (Å²) a residue of each name has alone, the denominator of exposure.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExposureTable {
    max_area: BTreeMap<String, f64>,
}

impl ExposureTable {
    /// Residues of each name whose isolated surfaces are computed (the first ones in topology
    /// order); the table keeps the largest area.
    pub const SAMPLES: usize = 5;

    /// A table from given areas (Å² per residue name).
    pub fn from_areas(areas: impl IntoIterator<Item = (String, f64)>) -> ExposureTable {
        ExposureTable {
            max_area: areas.into_iter().collect(),
        }
    }

    /// The table of a structure: for each residue name among the set's atoms, the largest
    /// surface area (`SurfaceOutput::area`, Å²) of the first [`Self::SAMPLES`] residues of
    /// that name, each computed alone (its atoms in the set, their radii, made whole in `cell`
    /// when the frame has one) with `engine` and `params`. Build it once per representation
    /// (from its first frame) and reuse it.
    ///
    /// Fails on mismatched lengths, indices past the topology, or a surface that fails.
    pub fn from_isolated_residues(
        engine: &mut dyn SurfaceEngine,
        topology: &Topology,
        atom_indices: Option<&[u32]>,
        atoms: &AtomSet<'_>,
        cell: Option<&PbcCell>,
        params: &SurfaceParams,
    ) -> Result<ExposureTable, MeasureError> {
        atoms.validate()?;
        let indices = topology_atoms(topology, atom_indices, atoms.len(), "atom positions")?;
        // Set members of each residue, residues in order.
        let mut members: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (k, &atom) in indices.iter().enumerate() {
            members
                .entry(topology.residue_index[atom as usize])
                .or_default()
                .push(k);
        }
        let residues = members.into_values().map(|set| {
            let name = topology
                .residue_names
                .get(indices[set[0]] as usize)
                .unwrap_or("")
                .to_string();
            (name, set)
        });
        Self::from_residue_members(engine, residues, atoms, cell, params)
    }

    /// The table of residues given as (name, indices of their atoms in `atoms`), in the order
    /// whose first [`Self::SAMPLES`] of each name are computed alone (see
    /// [`Self::from_isolated_residues`], which gives the topology's residues in file order).
    ///
    /// With a periodic `cell`, a residue is made whole before its surface is computed: each
    /// atom is taken at its image nearest the residue's first atom (a residue split by a face
    /// of the box, as trajectories written without whole molecules have them, would otherwise
    /// count as two pieces, each with its own surface). A residue is far shorter than half a
    /// box, so the nearest image is the bonded one.
    ///
    /// Fails on an index past the set or a surface that fails.
    pub fn from_residue_members(
        engine: &mut dyn SurfaceEngine,
        residues: impl IntoIterator<Item = (String, Vec<usize>)>,
        atoms: &AtomSet<'_>,
        cell: Option<&PbcCell>,
        params: &SurfaceParams,
    ) -> Result<ExposureTable, MeasureError> {
        atoms.validate()?;
        let mut done: BTreeMap<String, usize> = BTreeMap::new();
        let mut table = ExposureTable::default();
        let (mut pos, mut radii): (Vec<Vec3>, Vec<f32>) = (Vec::new(), Vec::new());
        for (name, set) in residues {
            let name = name.trim().to_string();
            if set.is_empty() {
                continue;
            }
            if let Some(&k) = set.iter().find(|&&k| k >= atoms.len()) {
                return Err(MeasureError::IndexOutOfRange {
                    what: "residue member atom",
                    index: k,
                    len: atoms.len(),
                });
            }
            let seen = done.entry(name.clone()).or_default();
            if *seen >= Self::SAMPLES {
                continue;
            }
            *seen += 1;
            pos.clear();
            radii.clear();
            pos.extend(set.iter().map(|&k| atoms.positions[k]));
            if let Some(cell) = cell {
                make_whole(&mut pos, cell);
            }
            radii.extend(set.iter().map(|&k| atoms.radii[k]));
            let alone = AtomSet {
                positions: &pos,
                radii: &radii,
                colours: None,
            };
            let area = engine.compute(&alone, params)?.area;
            let best = table.max_area.entry(name).or_insert(0.0);
            *best = best.max(area);
        }
        Ok(table)
    }

    /// The largest isolated area (Å²) of residues named `resname`, if the table has it.
    pub fn max_area(&self, resname: &str) -> Option<f64> {
        self.max_area.get(resname.trim()).copied()
    }

    /// Exposure of a residue named `resname` with `area` (Å²): the area over
    /// [`Self::max_area`] of its name (`None` when the table lacks the name or its area is 0).
    pub fn exposure(&self, resname: &str, area: f64) -> Option<f64> {
        self.max_area(resname)
            .filter(|&m| m > 0.0)
            .map(|m| area / m)
    }

    /// Residue names and their largest isolated areas (Å²), by name.
    pub fn entries(&self) -> impl Iterator<Item = (&str, f64)> + '_ {
        self.max_area.iter().map(|(k, v)| (k.as_str(), *v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residues_that_share_their_names_are_labelled_by_copy() {
        // Two monomers of a GRO file (no chains), and a lipid numbered on its own.
        let mut top = Topology::of_residues(&[
            (9, "PHE"),
            (10, "TRP"),
            (9, "PHE"),
            (10, "TRP"),
            (297, "POPE"),
        ]);
        top.number_residue_runs(&[0, 1, 2, 3, 4]);
        let labels: Vec<String> = (0..5)
            .map(|a| ResidueNames::of_atom(&top, a).label())
            .collect();
        assert_eq!(
            labels,
            ["PHE9#1", "TRP10#1", "PHE9#2", "TRP10#2", "POPE297"]
        );
        top.chains.set(0, "A");
        top.number_residue_copies();
        assert_eq!(ResidueNames::of_atom(&top, 0).label(), "A:PHE9");
        assert_eq!(ResidueNames::of_atom(&top, 2).label(), "PHE9");
        // An insertion code follows the number, before the copy.
        top.insertion_codes = crate::model::Labels::filled("", 5);
        top.insertion_codes.set(1, "A");
        top.insertion_codes.set(3, "A");
        top.number_residue_copies();
        assert_eq!(ResidueNames::of_atom(&top, 1).label(), "TRP10A#1");
        assert_eq!(ResidueNames::of_atom(&top, 3).label(), "TRP10A#2");
    }

    #[test]
    fn atoms_in_no_residue_are_labelled_by_name_and_serial() {
        let mut top = Topology::of_residues(&[(0, ""), (0, ""), (7, "LEU")]);
        top.number_residue_runs(&[u32::MAX; 3]);
        top.serials = vec![340, 341, 342];
        let names = |atom| ResidueNames::of_atom(&top, atom);
        assert!(names(0).is_anonymous());
        assert_eq!(names(1).label(), "C@341");
        assert!(!names(2).is_anonymous());
        assert_eq!(names(2).label(), "LEU7");
        assert!(!names_residues(&top, Some(&[0, 1])));
        assert!(names_residues(&top, Some(&[0, 2])));
        assert!(names_residues(&top, None));
        assert!(
            !names_residues(&top, Some(&[0, 99])),
            "indices past the end are skipped"
        );
    }
}
