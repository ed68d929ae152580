//! The data model: a constant [`Topology`] (what the atoms are) and per-frame [`Frame`]s (where
//! they are). Everything downstream (surface engines, renderer, exporters) reads these.

use glam::Vec3;

/// Everything about the particles that does not change from frame to frame.
///
/// All per-atom vectors have the same length, [`Topology::len`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Topology {
    /// Atom names as written in the file (`CA`, `OW`, `PO4`).
    pub names: Vec<String>,
    /// Element symbols, capitalised (`C`, `Fe`); guessed from the name when the file has none.
    /// Empty string for particles with no element (coarse-grained beads, unknown types).
    pub elements: Vec<String>,
    /// Radius of each particle in Å (from the file, an override, or the element table).
    pub radii: Vec<f32>,
    /// Residue name of each atom (`ALA`, `SOL`, `DPPC`).
    pub residue_names: Vec<String>,
    /// Residue number of each atom as written in the file.
    pub residue_ids: Vec<i64>,
    /// Index of each atom's residue, counting residues in file order from 0.
    pub residue_index: Vec<u32>,
    /// Chain or segment identifier of each atom (empty when the file has none).
    pub chains: Vec<String>,
    /// Temperature factor of each atom in Å² (0 when the file has none).
    pub b_factors: Vec<f32>,
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
