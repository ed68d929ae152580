//! The data model: a constant [`Topology`] (what the atoms are) and per-frame [`Frame`]s (where
//! they are). Everything downstream (surface engines, renderer, exporters) reads these.

use glam::Vec3;

/// Boxes narrower than this (Å) in any direction are placeholders, not periodic boxes (PDB's
/// `CRYST1 1 1 1`): neither the transforms nor `within` selections wrap across them.
pub const MIN_BOX_WIDTH: f32 = 4.0;

pub(crate) mod beads;
pub(crate) mod bonds;
pub(crate) mod cells;
pub(crate) mod colour;
pub mod colour_data;
pub mod colour_map;
pub mod elements;
pub mod exposure;
pub(crate) mod labels;
pub(crate) mod lipid_like;
pub(crate) mod particles;
pub mod pbc;
pub(crate) mod radii;
mod residue_runs;
pub(crate) mod residues;
pub mod sizing;

pub use beads::BeadModel;
pub use colour::{ColorScheme, DataColours};
pub use colour_map::ColourMap;
pub use labels::Labels;
pub use particles::{ParticleOptions, Particles};
pub use radii::{RadiusOverride, RadiusOverrides};
pub use residue_runs::chain_or_segment;
pub use residues::ResidueClass;

/// Why particles could not be built from a topology and frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A radius override or colour scheme string could not be parsed.
    #[error("{0}")]
    Parse(String),
    /// The frame does not match the topology.
    #[error("frame {frame} has {frame_atoms} atoms but the topology has {topology_atoms}")]
    AtomCountMismatch {
        /// Index of the frame.
        frame: usize,
        /// Atoms in the frame.
        frame_atoms: usize,
        /// Atoms in the topology.
        topology_atoms: usize,
    },
}

/// Everything about the particles that does not change from frame to frame.
///
/// All per-atom vectors have the same length, [`Topology::len`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Topology {
    /// Atom names as written in the file (`CA`, `OW`, `PO4`).
    pub names: Labels,
    /// Element symbols, capitalised (`C`, `Fe`); guessed from the name when the file has none.
    /// Empty string for particles with no element (coarse-grained beads, unknown types).
    pub elements: Labels,
    /// Radius of each particle in Å (from the file, an override, or the element table).
    pub radii: Vec<f32>,
    /// Residue name of each atom (`ALA`, `SOL`, `DPPC`).
    pub residue_names: Labels,
    /// Residue number of each atom as written in the file.
    pub residue_ids: Vec<i64>,
    /// PDB insertion code of each atom's residue (`A` of residue 52A, as antibodies' Kabat
    /// numbering has them; empty when none or the file has no such column).
    pub insertion_codes: Labels,
    /// Index of each atom's residue, counting residues in file order from 0.
    pub residue_index: Vec<u32>,
    /// Which copy each residue (by [`Topology::residue_index`]) is of the residues that share
    /// its chain (else segment), number and name, from 1 in file order; 0 when no other
    /// residue shares them (and for atoms in no residue). A GRO file, which has no chains,
    /// numbers both monomers of a dimer alike: their residues are copies 1 and 2. Set by
    /// [`Topology::number_residue_copies`].
    pub residue_copies: Vec<u32>,
    /// Chain or segment identifier of each atom (empty when the file has none).
    pub chains: Labels,
    /// Segment name of each atom (PDB columns 73-76, PSF segid; empty when the file has none).
    pub segments: Labels,
    /// Temperature factor of each atom in Å² (0 when the file has none).
    pub b_factors: Vec<f32>,
    /// Occupancy of each atom, 0 to 1 (1 when the file has none).
    pub occupancies: Vec<f32>,
    /// Atom type as the file gives it (force-field type, LAMMPS numeric type, or the PDB
    /// element column); equal to the name when the file has no type.
    pub types: Labels,
    /// Mass of each atom in amu (from the file, else from the element; 0 when neither is known).
    pub masses: Vec<f32>,
    /// Partial charge of each atom in units of the elementary charge e (0 when the file has none).
    pub charges: Vec<f32>,
    /// Serial number of each atom as written in the file (1-based; index + 1 when the file has
    /// none).
    pub serials: Vec<i64>,
    /// Bonds as pairs of atom indices, when the file lists them.
    pub bonds: Vec<[u32; 2]>,
}

impl Topology {
    /// Number of atoms.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// True when there are no atoms.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Fills what the file left open, per DESIGN section 2: in a coarse-grained system every
    /// particle gets no element and the bead radius (2.35 Å); otherwise empty elements are
    /// guessed from atom and residue names, radii that are not positive (not given by the
    /// file) come from the element table, and so do masses that are not positive.
    /// Per-atom vectors shorter than [`Topology::len`] are padded with their defaults (see
    /// [`Topology::complete_defaults`]).
    pub fn complete_elements_and_radii(&mut self) {
        let n = self.len();
        self.complete_defaults();
        self.radii.resize(n, 0.0);
        if elements::looks_coarse_grained(self.names.iter()) {
            self.elements.fill("");
            for r in self.radii.iter_mut().filter(|r| r.is_nan() || **r <= 0.0) {
                *r = elements::BEAD_RADIUS;
            }
            return;
        }
        // Guesses and table lookups are made once per distinct name, residue or element,
        // found through tables indexed by the labels' ids (no hashing per atom).
        let mut guesses = PairTable::new(
            self.names.distinct().0.len(),
            self.residue_names.distinct().0.len() + 1,
        );
        let mut radius_of: Vec<Option<(f32, f32)>> = Vec::new();
        let empty = self.elements.find("");
        for i in 0..n {
            if Some(self.elements.id(i)) == empty {
                let residue_id = if i < self.residue_names.len() {
                    self.residue_names.id(i)
                } else {
                    u32::MAX
                };
                let key = (self.names.id(i), residue_id);
                let element = match guesses.get(key) {
                    Some(id) => id,
                    None => {
                        let residue = self.residue_names.get(i).unwrap_or("");
                        let guess = elements::guess_element(&self.names[i], residue);
                        let id = self.elements.intern(guess.unwrap_or_default());
                        guesses.insert(key, id);
                        id
                    }
                };
                self.elements.set_id(i, element);
            }
            let e = self.elements.id(i) as usize;
            if radius_of.len() <= e {
                radius_of.resize(e + 1, None);
            }
            let (radius, mass) = *radius_of[e].get_or_insert_with(|| {
                let e = &self.elements[i];
                (elements::element_radius(e), elements::element_mass(e))
            });
            if self.radii[i].is_nan() || self.radii[i] <= 0.0 {
                self.radii[i] = radius;
            }
            if self.masses[i].is_nan() || self.masses[i] <= 0.0 {
                self.masses[i] = mass;
            }
        }
    }

    /// Pads every per-atom vector shorter than [`Topology::len`] with its default: empty
    /// strings, 0 (B-factor, mass, charge), occupancy 1, serial index + 1, and a type equal to
    /// the atom's name. Residue numbers and indices are left as they are.
    pub fn complete_defaults(&mut self) {
        let n = self.len();
        for v in [
            &mut self.elements,
            &mut self.residue_names,
            &mut self.insertion_codes,
            &mut self.chains,
            &mut self.segments,
        ] {
            v.resize(n, "");
        }
        for v in [&mut self.b_factors, &mut self.masses, &mut self.charges] {
            v.resize(n, 0.0);
        }
        self.occupancies.resize(n, 1.0);
        let first = self.serials.len();
        self.serials.extend((first..n).map(|i| i as i64 + 1));
        let first = self.types.len();
        self.types.extend_from(&self.names, first.min(n)..n);
    }

    /// Number of residues (one more than the largest [`Topology::residue_index`]).
    pub fn residue_count(&self) -> usize {
        self.residue_index
            .iter()
            .max()
            .map_or(0, |&m| m as usize + 1)
    }
}

/// One frame of a trajectory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Frame {
    /// Index of this frame in its trajectory, from 0.
    pub index: usize,
    /// Simulation time in ps, when the file records it.
    pub time_ps: Option<f64>,
    /// Atom positions in Å, one per topology atom.
    pub positions: Vec<Vec3>,
    /// Periodic box edge vectors in Å (rows a, b, c), when the file has a box.
    pub cell: Option<[Vec3; 3]>,
}

/// A map from pairs of label ids (`first < rows`; `second < columns`, or `u32::MAX` for the
/// last column) to an id: a dense table when it is small, else a hash map.
enum PairTable {
    Dense { columns: usize, cells: Vec<u32> },
    Sparse(std::collections::HashMap<(u32, u32), u32>),
}

impl PairTable {
    /// Cells above which the table is a hash map (16 MB of `u32`).
    const MAX_DENSE: usize = 1 << 22;

    fn new(rows: usize, columns: usize) -> PairTable {
        match rows.checked_mul(columns) {
            Some(cells) if cells <= Self::MAX_DENSE => PairTable::Dense {
                columns,
                cells: vec![u32::MAX; cells],
            },
            _ => PairTable::Sparse(Default::default()),
        }
    }

    /// The cell of `(row, column)` in the dense table (`u32::MAX` is the last column).
    fn cell(columns: usize, (row, column): (u32, u32)) -> usize {
        let column = if column == u32::MAX {
            columns - 1
        } else {
            column as usize
        };
        row as usize * columns + column
    }

    fn get(&self, key: (u32, u32)) -> Option<u32> {
        match self {
            PairTable::Dense { columns, cells } => {
                let v = cells[Self::cell(*columns, key)];
                (v != u32::MAX).then_some(v)
            }
            PairTable::Sparse(map) => map.get(&key).copied(),
        }
    }

    fn insert(&mut self, key: (u32, u32), value: u32) {
        match self {
            PairTable::Dense { columns, cells } => cells[Self::cell(*columns, key)] = value,
            PairTable::Sparse(map) => {
                map.insert(key, value);
            }
        }
    }
}
