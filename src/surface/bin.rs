//! Stage 1 of the CPU engine (the paper's `t_sort`): put the atoms in a canonical order and
//! list, for every z-slab of the grid, the atoms whose cutoff sphere can reach it.
//!
//! Data flow: [`AtomSet`] + [`SurfaceParams`] + [`GridSpec`] -> [`AtomBins`] -> the density stage
//! ([`super::density`]).
//!
//! Canonical order: atoms are sorted by the grid cell that holds them, y-major
//! (`key = (cy * nz + cz) * nx + cx`, `c = floor((p - origin) / H)`), ties broken by the bits of
//! x, y, z, radius and colour (`f32::total_cmp`). The density stage adds every voxel's terms in
//! this order, so the result does not depend on the order of the input atoms (a permutation
//! gives a bitwise identical map), nor on how the grid is cut into slabs or how many threads run.
//! The y-major key also makes consecutive atoms of a slab touch neighbouring rows of memory.

use std::cmp::Ordering;

use rayon::prelude::*;

use super::{AtomSet, GridSpec, SurfaceParams};

/// One atom ready for the density stage (in canonical order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedAtom {
    /// Position in Å.
    pub pos: [f32; 3],
    /// Exponent factor `k = 0.5 / (alpha * alpha)` in Å⁻², with `alpha = r * R` (f32).
    pub k: f32,
    /// Cutoff radius `c = q * alpha` in Å (f32).
    pub cut: f32,
    /// Squared cutoff `c * c` in Å² (f32): a sample counts when `d2 < cut2`.
    pub cut2: f32,
    /// Linear RGB colour (white when the atom set has no colours).
    pub colour: [f32; 3],
}

/// Atoms in canonical order plus the list of atoms that reach each z-slab.
#[derive(Debug, Clone)]
pub struct AtomBins {
    /// Atoms in canonical order.
    pub atoms: Vec<PreparedAtom>,
    /// Grid planes (z samples) per slab; the last slab may be thinner.
    pub slab_planes: u32,
    /// `slab_start[s]..slab_start[s + 1]` indexes [`AtomBins::slab_atoms`] for slab `s`.
    pub slab_start: Vec<usize>,
    /// Indices into [`AtomBins::atoms`], ascending within each slab.
    pub slab_atoms: Vec<u32>,
}

impl AtomBins {
    /// Number of slabs.
    pub fn slab_count(&self) -> usize {
        self.slab_start.len() - 1
    }

    /// Indices (into [`AtomBins::atoms`]) of the atoms that may reach slab `s`, ascending.
    pub fn slab(&self, s: usize) -> &[u32] {
        &self.slab_atoms[self.slab_start[s]..self.slab_start[s + 1]]
    }
}

/// Inclusive range of sample indices along one axis that a cutoff sphere of radius `cut` around
/// coordinate `p` may reach: one sample of margin on each side, clamped to `0..n`. `None` when it
/// misses the grid. The exact per-sample test is made later; this only has to be conservative.
pub fn sample_range(p: f32, cut: f32, origin: f32, h: f32, n: u32) -> Option<(u32, u32)> {
    let lo = ((p - cut - origin) / h).floor() as i64 - 1;
    let hi = ((p + cut - origin) / h).ceil() as i64 + 1;
    let lo = lo.max(0);
    let hi = hi.min(n as i64 - 1);
    (lo <= hi).then_some((lo as u32, hi as u32))
}

fn cell(p: f32, origin: f32, h: f32, n: u32) -> u64 {
    (((p - origin) / h).floor().max(0.0) as u64).min(n.saturating_sub(1) as u64)
}

/// Sorts the atoms canonically and lists the atoms of every slab of `slab_planes` z-planes.
///
/// `atoms` must already be validated (finite, same lengths, positive radii) and `grid` must be
/// the grid of these atoms.
pub fn bin_atoms(
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    grid: &GridSpec,
    slab_planes: u32,
) -> AtomBins {
    bin_atoms_overlapping(atoms, params, grid, slab_planes, 0)
}

/// [`bin_atoms`] where slab `s` also lists the atoms that reach the `overlap` planes above it
/// (planes `s * slab_planes + slab_planes ..` `+ overlap`), for stages that need a slab plus
/// the first planes of the next one (the sparse engine's bricks, [`super::bricks`]).
pub fn bin_atoms_overlapping(
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    grid: &GridSpec,
    slab_planes: u32,
    overlap: u32,
) -> AtomBins {
    let slab_planes = slab_planes.max(1);
    let [nx, ny, nz] = grid.dims;
    let (o, h) = (grid.origin, grid.spacing);
    let q = params.cutoff();
    let colour_of = |i: usize| atoms.colours.map_or([1.0; 3], |c| c[i]);

    let mut order: Vec<(u64, u32)> = atoms
        .positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let cx = cell(p.x, o.x, h, nx);
            let cy = cell(p.y, o.y, h, ny);
            let cz = cell(p.z, o.z, h, nz);
            ((cy * nz as u64 + cz) * nx as u64 + cx, i as u32)
        })
        .collect();
    let tie = |a: usize, b: usize| -> Ordering {
        let (pa, pb) = (atoms.positions[a], atoms.positions[b]);
        let (ca, cb) = (colour_of(a), colour_of(b));
        pa.x.total_cmp(&pb.x)
            .then(pa.y.total_cmp(&pb.y))
            .then(pa.z.total_cmp(&pb.z))
            .then(atoms.radii[a].total_cmp(&atoms.radii[b]))
            .then(ca[0].total_cmp(&cb[0]))
            .then(ca[1].total_cmp(&cb[1]))
            .then(ca[2].total_cmp(&cb[2]))
    };
    order.par_sort_unstable_by(|a, b| a.0.cmp(&b.0).then_with(|| tie(a.1 as usize, b.1 as usize)));

    let prepared: Vec<PreparedAtom> = order
        .par_iter()
        .map(|&(_, i)| {
            let i = i as usize;
            let p = atoms.positions[i];
            let alpha = atoms.radii[i] * params.radius_scale;
            let cut = q * alpha;
            PreparedAtom {
                pos: [p.x, p.y, p.z],
                k: 0.5 / (alpha * alpha),
                cut,
                cut2: cut * cut,
                colour: colour_of(i),
            }
        })
        .collect();
    drop(order);

    // Slabs each atom reaches (inclusive), then a counting fill that keeps canonical order.
    let slab_count = nz.div_ceil(slab_planes) as usize;
    let reach: Vec<Option<(u32, u32)>> = prepared
        .par_iter()
        .map(|a| {
            sample_range(a.pos[2], a.cut, o.z, h, nz)
                .map(|(k0, k1)| (k0.saturating_sub(overlap) / slab_planes, k1 / slab_planes))
        })
        .collect();
    let mut slab_start = vec![0usize; slab_count + 1];
    for &(s0, s1) in reach.iter().flatten() {
        for s in s0..=s1 {
            slab_start[s as usize + 1] += 1;
        }
    }
    for s in 0..slab_count {
        slab_start[s + 1] += slab_start[s];
    }
    let mut fill = slab_start.clone();
    let mut slab_atoms = vec![0u32; slab_start[slab_count]];
    for (i, r) in reach.iter().enumerate() {
        if let Some((s0, s1)) = *r {
            for s in s0..=s1 {
                slab_atoms[fill[s as usize]] = i as u32;
                fill[s as usize] += 1;
            }
        }
    }
    AtomBins {
        atoms: prepared,
        slab_planes,
        slab_start,
        slab_atoms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn sample_range_is_conservative_and_clamped() {
        // Sphere of radius 2 around x = 5 on a grid with origin 0, H = 1, 20 samples.
        assert_eq!(sample_range(5.0, 2.0, 0.0, 1.0, 20), Some((2, 8)));
        assert_eq!(sample_range(0.5, 2.0, 0.0, 1.0, 20), Some((0, 4)));
        assert_eq!(sample_range(50.0, 2.0, 0.0, 1.0, 20), None);
    }

    #[test]
    fn order_is_canonical_and_slabs_cover_reach() {
        let positions: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new((i * 7 % 11) as f32, (i * 3 % 5) as f32, (i % 13) as f32))
            .collect();
        let radii = vec![1.5; positions.len()];
        let params = SurfaceParams::default();
        let set = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: None,
        };
        let grid = GridSpec::for_atoms(&positions, &radii, &params).unwrap();
        let a = bin_atoms(&set, &params, &grid, 3);
        let mut rev_p = positions.clone();
        rev_p.reverse();
        let rev = AtomSet {
            positions: &rev_p,
            ..set
        };
        let b = bin_atoms(&rev, &params, &grid, 3);
        assert_eq!(a.atoms, b.atoms);
        assert_eq!(a.slab_atoms, b.slab_atoms);
        // Every atom is listed in each slab its z-range touches, in ascending order.
        for s in 0..a.slab_count() {
            let list = a.slab(s);
            assert!(list.windows(2).all(|w| w[0] < w[1]));
            for (i, at) in a.atoms.iter().enumerate() {
                let r = sample_range(at.pos[2], at.cut, grid.origin.z, 1.0, grid.dims[2]).unwrap();
                let touches = (r.0 / 3..=r.1 / 3).contains(&(s as u32));
                assert_eq!(list.contains(&(i as u32)), touches);
            }
        }
    }
}
