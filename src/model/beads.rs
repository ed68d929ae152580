//! The coarse bead model (DESIGN section 2): one bead per residue (so one per molecule for
//! water, ions and other small molecules), centred at the mean of its atoms.

use glam::{Mat3, Vec3};

use super::{Frame, ModelError, Topology};

/// Extra radius in Å added to a bead's largest centre-to-atom distance.
pub const BEAD_PADDING: f32 = 1.0;

/// Which atoms form each bead, and each bead's radius.
///
/// Bead radii are computed once, from the frame given to [`BeadModel::new`] (normally the first
/// frame), and then kept: radii are part of what the surface engines treat as constant (the GPU
/// uploads them only when they change), and a residue's extent changes by a fraction of an Å
/// as it moves, far less than the 1 Å padding.
#[derive(Debug, Clone, PartialEq)]
pub struct BeadModel {
    /// Atoms in the topology (and in every frame) the model was built for.
    atom_count: usize,
    /// Bead `b` holds `atoms[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<usize>,
    /// Atom indices grouped by bead, in file order within a bead.
    atoms: Vec<u32>,
    /// Radius of each bead in Å.
    radii: Vec<f32>,
}

impl BeadModel {
    /// Groups `topology`'s atoms by residue and sizes the beads from `frame`'s positions.
    /// Atoms without residue information each become their own bead. Fails when the frame's
    /// atom count differs from the topology's.
    pub fn new(topology: &Topology, frame: &Frame) -> Result<Self, ModelError> {
        Self::new_subset(topology, frame, None)
    }

    /// Like [`BeadModel::new`] for the atoms `subset` only (sorted 0-based indices; `None`: all
    /// atoms): one bead per residue that has at least one selected atom, made of those atoms.
    pub fn new_subset(
        topology: &Topology,
        frame: &Frame,
        subset: Option<&[u32]>,
    ) -> Result<Self, ModelError> {
        let n = topology.len();
        check_count(frame, n)?;
        let all: Vec<u32>;
        let members = match subset {
            Some(s) => s,
            None => {
                all = (0..n as u32).collect();
                &all
            }
        };
        let key = |i: u32| -> usize {
            if topology.residue_index.len() == n {
                topology.residue_index[i as usize] as usize
            } else {
                i as usize
            }
        };
        let groups = members.iter().map(|&i| key(i)).max().map_or(0, |m| m + 1);
        let mut offsets = vec![0usize; groups + 1];
        for &i in members {
            offsets[key(i) + 1] += 1;
        }
        for g in 0..groups {
            offsets[g + 1] += offsets[g];
        }
        let mut fill = offsets.clone();
        let mut atoms = vec![0u32; members.len()];
        for &i in members {
            let k = key(i);
            atoms[fill[k]] = i;
            fill[k] += 1;
        }
        // Drop residue indices that hold no atom.
        offsets.dedup();
        let mut model = BeadModel {
            atom_count: n,
            offsets,
            atoms,
            radii: Vec::new(),
        };
        model.radii = model.measure_radii(frame);
        Ok(model)
    }

    /// Number of beads.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no beads.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Radius of each bead in Å.
    pub fn radii(&self) -> &[f32] {
        &self.radii
    }

    /// Atom indices of bead `b`.
    pub fn atoms_of(&self, b: usize) -> &[u32] {
        &self.atoms[self.offsets[b]..self.offsets[b + 1]]
    }

    /// Bead centres in Å for `frame`, written into `out` (cleared first). Molecules split by the
    /// periodic box are made whole around their first atom before averaging. Fails when the
    /// frame has a different atom count than the topology the model was built from.
    pub fn centres_into(&self, frame: &Frame, out: &mut Vec<Vec3>) -> Result<(), ModelError> {
        check_count(frame, self.atom_count)?;
        out.clear();
        let image = MinimumImage::new(frame.cell);
        for b in 0..self.len() {
            out.push(self.centre(b, frame, &image));
        }
        Ok(())
    }

    /// The mean colour of each bead's atoms (for residue-based schemes: the residue's colour).
    pub fn colours(&self, atom_colours: &[[f32; 3]]) -> Vec<[f32; 3]> {
        (0..self.len())
            .map(|b| {
                let group = self.atoms_of(b);
                let sum = group.iter().fold(Vec3::ZERO, |s, &i| {
                    s + Vec3::from(atom_colours.get(i as usize).copied().unwrap_or([1.0; 3]))
                });
                (sum / group.len().max(1) as f32).to_array()
            })
            .collect()
    }

    fn centre(&self, b: usize, frame: &Frame, image: &MinimumImage) -> Vec3 {
        let group = self.atoms_of(b);
        let reference = frame.positions[group[0] as usize];
        let sum: Vec3 = group
            .iter()
            .map(|&i| image.apply(frame.positions[i as usize] - reference))
            .sum();
        reference + sum / group.len() as f32
    }

    fn measure_radii(&self, frame: &Frame) -> Vec<f32> {
        let image = MinimumImage::new(frame.cell);
        (0..self.len())
            .map(|b| {
                let centre = self.centre(b, frame, &image);
                let reach = self
                    .atoms_of(b)
                    .iter()
                    .map(|&i| image.apply(frame.positions[i as usize] - centre).length())
                    .fold(0.0f32, f32::max);
                reach + BEAD_PADDING
            })
            .collect()
    }
}

/// Fails unless `frame` holds exactly `atoms` positions.
pub(crate) fn check_count(frame: &Frame, atoms: usize) -> Result<(), ModelError> {
    if frame.positions.len() == atoms {
        Ok(())
    } else {
        Err(ModelError::AtomCountMismatch {
            frame: frame.index,
            frame_atoms: frame.positions.len(),
            topology_atoms: atoms,
        })
    }
}

/// Wraps difference vectors to their shortest periodic image (exact for orthorhombic boxes,
/// close for triclinic ones); does nothing without a box.
struct MinimumImage {
    cell: Option<(Mat3, Mat3)>,
}

impl MinimumImage {
    fn new(cell: Option<[Vec3; 3]>) -> Self {
        let cell = cell.and_then(|[a, b, c]| {
            let m = Mat3::from_cols(a, b, c);
            (m.determinant().abs() > 1e-6).then(|| (m, m.inverse()))
        });
        MinimumImage { cell }
    }

    fn apply(&self, d: Vec3) -> Vec3 {
        match &self.cell {
            Some((m, inv)) => {
                let f = *inv * d;
                *m * (f - f.round())
            }
            None => d,
        }
    }
}
