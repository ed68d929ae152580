//! Making molecules whole: atoms a molecule lost across a box face are moved back next to the
//! atom they are bonded to (by whole lattice vectors only), as `gmx trjconv -pbc mol` does.
//!
//! The molecules ([`Molecules`]) are found once per topology: connected components of the
//! bonds the file lists and of bonds guessed from distances (periodic images counted), and
//! atoms of one residue are always kept together (so coarse-grained beads, which no distance
//! rule bonds, stay in one piece per residue). Each molecule is walked breadth-first once; per
//! frame every atom follows its parent along that walk to the nearest image.

use std::collections::VecDeque;

use glam::Vec3;

use crate::model::bonds::guess_bonds_periodic;
use crate::model::pbc::PbcCell;
use crate::model::{Frame, Topology};

/// A residue larger than this many atoms is not used to join atoms (files without residues
/// may put every atom in one).
const MAX_RESIDUE_UNIT: usize = 5000;

/// Where the connectivity of [`Molecules`] comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Connectivity {
    /// The bonds the file lists and bonds guessed from distances (plus residues).
    FileBonds,
    /// Bonds guessed from distances in the reference frame (plus residues).
    GuessedBonds,
    /// Residues only.
    Residues,
    /// Nothing joins any two atoms.
    None,
}

/// The molecules of a topology and a breadth-first walk through each.
#[derive(Debug, Clone)]
pub struct Molecules {
    /// `[child, parent]` pairs in walk order: each parent comes before its children.
    edges: Vec<[u32; 2]>,
    /// Atoms of every molecule, molecule after molecule.
    atoms: Vec<u32>,
    /// Start of each molecule in `atoms`, plus the end.
    offsets: Vec<u32>,
    connectivity: Connectivity,
}

impl Molecules {
    /// The molecules of `topology`: its bonds and bonds guessed from `frame` (periodic images
    /// counted when it has a box), with residues joined.
    pub fn new(topology: &Topology, frame: &Frame) -> Molecules {
        let n = topology.len();
        // Files often list only some bonds (chemfiles' PDB templates stop at the residue),
        // so guessed bonds are always added.
        let mut bonds = guess_bonds_periodic(&frame.positions, &topology.radii, PbcCell::of(frame));
        let mut connectivity = Connectivity::GuessedBonds;
        if !topology.bonds.is_empty() {
            bonds.extend_from_slice(&topology.bonds);
            connectivity = Connectivity::FileBonds;
        }
        if bonds.is_empty() {
            connectivity = Connectivity::Residues;
        }
        let mut molecules = Molecules::from_bonds(n, &bonds, &topology.residue_index);
        if molecules.edges.is_empty() {
            connectivity = Connectivity::None;
        }
        molecules.connectivity = connectivity;
        molecules
    }

    /// The molecules of `n` atoms joined by `bonds` (pairs of atom indices; out-of-range ones
    /// are ignored) and by shared residues (`residue_index`, one per atom, may be empty).
    pub fn from_bonds(n: usize, bonds: &[[u32; 2]], residue_index: &[u32]) -> Molecules {
        let mut links: Vec<[u32; 2]> = bonds
            .iter()
            .copied()
            .filter(|&[a, b]| a != b && (a as usize) < n && (b as usize) < n)
            .collect();
        // Residues join what the bonds left apart: one link per piece, to the residue's first
        // atom.
        if residue_index.len() == n && n > 0 {
            let mut sets = UnionFind::new(n);
            for &[a, b] in &links {
                sets.union(a, b);
            }
            let residues = residue_index.iter().max().map_or(0, |&m| m as usize + 1);
            let mut sizes = vec![0usize; residues];
            for &r in residue_index {
                sizes[r as usize] += 1;
            }
            let mut anchor = vec![u32::MAX; residues];
            if residues > 1 {
                for (i, &r) in residue_index.iter().enumerate() {
                    let r = r as usize;
                    if sizes[r] > MAX_RESIDUE_UNIT {
                        continue;
                    }
                    if anchor[r] == u32::MAX {
                        anchor[r] = i as u32;
                    } else if sets.union(anchor[r], i as u32) {
                        links.push([anchor[r], i as u32]);
                    }
                }
            }
        }
        // Adjacency in compressed rows.
        let mut start = vec![0u32; n + 1];
        for &[a, b] in &links {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut next = vec![0u32; start[n] as usize];
        for &[a, b] in &links {
            next[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
            next[fill[b as usize] as usize] = a;
            fill[b as usize] += 1;
        }
        // Breadth-first walk from the lowest atom of each molecule.
        let mut seen = vec![false; n];
        let mut edges = Vec::new();
        let mut atoms = Vec::with_capacity(n);
        let mut offsets = vec![0u32];
        let mut queue = VecDeque::new();
        for root in 0..n {
            if seen[root] {
                continue;
            }
            seen[root] = true;
            queue.push_back(root as u32);
            while let Some(a) = queue.pop_front() {
                atoms.push(a);
                for &b in &next[start[a as usize] as usize..start[a as usize + 1] as usize] {
                    if !seen[b as usize] {
                        seen[b as usize] = true;
                        edges.push([b, a]);
                        queue.push_back(b);
                    }
                }
            }
            offsets.push(atoms.len() as u32);
        }
        Molecules {
            edges,
            atoms,
            offsets,
            connectivity: if links.is_empty() {
                Connectivity::None
            } else {
                Connectivity::FileBonds
            },
        }
    }

    /// Where the connectivity came from.
    pub fn connectivity(&self) -> Connectivity {
        self.connectivity
    }

    /// True when some atoms are joined (otherwise making whole changes nothing).
    pub fn has_links(&self) -> bool {
        !self.edges.is_empty()
    }

    /// Number of molecules (single atoms count as one each).
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when there are no atoms.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The atoms of molecule `m`.
    pub fn molecule(&self, m: usize) -> &[u32] {
        &self.atoms[self.offsets[m] as usize..self.offsets[m + 1] as usize]
    }

    /// Iterates over the molecules' atom lists.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> {
        self.offsets
            .windows(2)
            .map(|w| &self.atoms[w[0] as usize..w[1] as usize])
    }

    /// Makes every molecule whole in `positions` (Å): each atom is moved by whole lattice
    /// vectors of `cell` to the image nearest its parent in the walk. Atoms already next to
    /// their parent are not touched.
    pub fn make_whole(&self, positions: &mut [Vec3], cell: &PbcCell) {
        for &[child, parent] in &self.edges {
            let (c, p) = (child as usize, parent as usize);
            let n = cell.nearest_lattice(positions[c] - positions[p]);
            if n != Vec3::ZERO {
                positions[c] -= cell.cartesian(n);
            }
        }
    }
}

/// Disjoint sets of atoms.
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut a: u32) -> u32 {
        while self.parent[a as usize] != a {
            let up = self.parent[self.parent[a as usize] as usize];
            self.parent[a as usize] = up;
            a = up;
        }
        a
    }

    /// Joins the sets of `a` and `b`; false when they were one already.
    fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.parent[ra.max(rb) as usize] = ra.min(rb);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bonds::{BOND_RADIUS_FRACTION, MAX_BOND_LENGTH};

    fn cubic(l: f32) -> PbcCell {
        PbcCell::new(&[Vec3::X * l, Vec3::Y * l, Vec3::Z * l]).expect("cell")
    }

    #[test]
    fn a_chain_split_across_a_face_is_joined() {
        let cell = cubic(20.0);
        let whole: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(17.0 + 1.5 * i as f32, 5.0, 5.0))
            .collect();
        let mut wrapped: Vec<Vec3> = whole
            .iter()
            .map(|&p| if p.x >= 20.0 { p - Vec3::X * 20.0 } else { p })
            .collect();
        let bonds: Vec<[u32; 2]> = (0..5).map(|i| [i, i + 1]).collect();
        let mols = Molecules::from_bonds(6, &bonds, &[]);
        assert_eq!(mols.len(), 1);
        mols.make_whole(&mut wrapped, &cell);
        for (a, b) in wrapped.iter().zip(&whole) {
            assert!((*a - *b).length() < 1e-5, "{a} {b}");
        }
    }

    /// Every pair of `positions` closer than the bond limit (minimum image in `cell`), tested
    /// one by one.
    fn close_pairs(positions: &[Vec3], radii: &[f32], cell: &PbcCell) -> Vec<[u32; 2]> {
        let wrap = |p: Vec3| {
            let f = cell.fractional(p);
            cell.cartesian(f - f.floor())
        };
        let mut pairs = Vec::new();
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                let limit = (BOND_RADIUS_FRACTION * (radii[i] + radii[j])).min(MAX_BOND_LENGTH);
                let d = cell.min_image(wrap(positions[j]) - wrap(positions[i]));
                if d.length_squared() < limit * limit {
                    pairs.push([i as u32, j as u32]);
                }
            }
        }
        pairs
    }

    /// `n` atoms spread over a cube of `side` Å from `low` Å, with radii 1, 1.5 and 1.9 Å.
    fn random_atoms(n: usize, low: f32, side: f32) -> (Vec<Vec3>, Vec<f32>) {
        let mut x: u64 = 7;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            low + side * (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let positions = (0..n).map(|_| Vec3::new(next(), next(), next())).collect();
        let radii = (0..n).map(|i| [1.0, 1.5, 1.9][i % 3]).collect();
        (positions, radii)
    }

    #[test]
    fn guessed_bonds_are_every_close_pair_in_a_sparse_box() {
        // A cluster of atoms in a corner of a large triclinic box, some across the faces: the
        // bonds are exactly the pairs closer than the bond limit.
        let rows = [
            Vec3::new(300.0, 0.0, 0.0),
            Vec3::new(40.0, 280.0, 0.0),
            Vec3::new(20.0, 30.0, 260.0),
        ];
        let cell = PbcCell::new(&rows).expect("cell");
        let (positions, radii) = random_atoms(600, -4.0, 14.0);
        let want = close_pairs(&positions, &radii, &cell);
        assert!(want.len() > 100, "{} bonds", want.len());
        assert_eq!(guess_bonds_periodic(&positions, &radii, Some(cell)), want);
    }

    #[test]
    fn guessed_bonds_are_every_close_pair_in_small_boxes() {
        // Boxes two and three grid cells wide (neighbouring cells repeat, or only just not).
        for side in [5.0, 6.5, 9.0] {
            let cell = cubic(side);
            let (positions, radii) = random_atoms(40, -1.0, side + 2.0);
            let want = close_pairs(&positions, &radii, &cell);
            assert!(want.len() > 10, "{side}: {} bonds", want.len());
            assert_eq!(
                guess_bonds_periodic(&positions, &radii, Some(cell)),
                want,
                "{side}"
            );
        }
    }

    #[test]
    fn guessed_bonds_cross_the_box_and_residues_join_beads() {
        let cell = cubic(10.0);
        let positions = vec![
            Vec3::new(0.2, 5.0, 5.0),
            Vec3::new(9.5, 5.0, 5.0),
            Vec3::new(5.0, 5.0, 5.0),
        ];
        let bonds = guess_bonds_periodic(&positions, &[1.5, 1.5, 1.5], Some(cell));
        assert_eq!(bonds, vec![[0, 1]]);
        // Beads 4.7 Å apart: no bond guessed, the residue keeps them together.
        let mols = Molecules::from_bonds(3, &[], &[0, 0, 1]);
        assert_eq!(mols.len(), 2);
        assert_eq!(mols.molecule(0), &[0, 1]);
    }
}
