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

/// Grid cell index along one axis: `floor((p - origin) / h)` clamped to `0..n`. Truncation
/// equals `floor` for the non-negative values kept (negative ones clamp to 0 either way), and
/// needs no libm call on the baseline x86-64 target.
fn cell(p: f32, origin: f32, h: f32, n: u32) -> u64 {
    (((p - origin) / h).max(0.0) as u64).min(n.saturating_sub(1) as u64)
}

/// Grid rows (y, z) at most for which [`canonical_order`] buckets atoms per row; above it,
/// per y plane (4 bytes of count per bucket).
const MAX_ROW_BUCKETS: u64 = 1 << 24;

/// `(cell key, input index)` of every atom in canonical order (module docs).
///
/// A counting sort by bucket (the key's row `cy * nz + cz`, or its y plane on grids with very
/// many rows), then each bucket sorted by the full key and the tie-break; the buckets hold a
/// few atoms each and are sorted in parallel, which is several times faster than one
/// comparison sort of all atoms, with the same order.
fn canonical_order(atoms: &AtomSet<'_>, grid: &GridSpec) -> Vec<(u64, u32)> {
    canonical_order_bucketed(atoms, grid, MAX_ROW_BUCKETS)
}

/// [`canonical_order`], bucketing per row when the grid has at most `max_row_buckets` rows.
fn canonical_order_bucketed(
    atoms: &AtomSet<'_>,
    grid: &GridSpec,
    max_row_buckets: u64,
) -> Vec<(u64, u32)> {
    let [nx, ny, nz] = grid.dims;
    let (o, h) = (grid.origin, grid.spacing);
    let keyed: Vec<(u64, u32)> = atoms
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
    let rows = ny as u64 * nz as u64;
    let per_bucket = if rows <= max_row_buckets {
        nx as u64
    } else {
        nx as u64 * nz as u64
    };
    let buckets = (nx as u64 * rows).div_ceil(per_bucket.max(1)) as usize;
    let mut start = vec![0usize; buckets + 1];
    for &(key, _) in &keyed {
        start[(key / per_bucket) as usize + 1] += 1;
    }
    for b in 0..buckets {
        start[b + 1] += start[b];
    }
    let mut fill = start.clone();
    let mut order = vec![(0u64, 0u32); keyed.len()];
    for &(key, i) in &keyed {
        let b = (key / per_bucket) as usize;
        order[fill[b]] = (key, i);
        fill[b] += 1;
    }
    drop(keyed);
    drop(fill);

    let tie = |a: usize, b: usize| -> Ordering {
        let (pa, pb) = (atoms.positions[a], atoms.positions[b]);
        let (ca, cb) = (atoms.colour(a), atoms.colour(b));
        pa.x.total_cmp(&pb.x)
            .then(pa.y.total_cmp(&pb.y))
            .then(pa.z.total_cmp(&pb.z))
            .then(atoms.radii[a].total_cmp(&atoms.radii[b]))
            .then(ca[0].total_cmp(&cb[0]))
            .then(ca[1].total_cmp(&cb[1]))
            .then(ca[2].total_cmp(&cb[2]))
    };
    let by_key = |a: &(u64, u32), b: &(u64, u32)| {
        a.0.cmp(&b.0).then_with(|| tie(a.1 as usize, b.1 as usize))
    };
    // Split `order` at bucket boundaries into chunks of about 4096 atoms; each chunk sorts its
    // buckets one by one (in parallel over chunks).
    let mut chunks: Vec<(usize, &mut [(u64, u32)])> = Vec::new();
    let mut rest = &mut order[..];
    let mut b = 0usize;
    while b < buckets {
        let mut e = b + 1;
        while e < buckets && start[e + 1] - start[b] <= 4096 {
            e += 1;
        }
        let (head, tail) = rest.split_at_mut(start[e] - start[b]);
        chunks.push((b, head));
        rest = tail;
        b = e;
    }
    chunks.into_par_iter().for_each(|(first, chunk)| {
        let mut bucket = first;
        let mut done = 0;
        while done < chunk.len() {
            let end = start[bucket + 1] - start[first];
            chunk[done..end].sort_unstable_by(by_key);
            done = end;
            bucket += 1;
        }
    });
    order
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
    let nz = grid.dims[2];
    let (o, h) = (grid.origin, grid.spacing);
    let q = params.cutoff();

    let order = canonical_order(atoms, grid);

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
                colour: atoms.colour(i),
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

    /// Both bucketings give the order of one comparison sort by (key, tie-break), also with
    /// many atoms per cell (ties) and buckets larger than a parallel chunk.
    #[test]
    fn bucketed_order_is_the_full_sort() {
        let positions: Vec<Vec3> = (0..9000u32)
            .map(|i| {
                // Every third atom repeats another's position (with another radius or colour).
                let j = if i % 3 == 0 { i / 3 } else { i };
                let f = |m: u32, d: f32| (j.wrapping_mul(m) % 1009) as f32 / d;
                Vec3::new(f(7919, 50.0), f(104_729, 3000.0), f(1299, 80.0))
            })
            .collect();
        let radii: Vec<f32> = (0..positions.len())
            .map(|i| 1.2 + (i % 4) as f32 * 0.2)
            .collect();
        let colours: Vec<[f32; 3]> = (0..positions.len())
            .map(|i| [(i % 5) as f32 / 4.0, 0.5, (i % 2) as f32])
            .collect();
        let set = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: Some(&colours),
        };
        let params = SurfaceParams::default();
        let grid = GridSpec::for_atoms(&positions, &radii, &params).unwrap();
        let rows_mode = canonical_order_bucketed(&set, &grid, u64::MAX);
        let planes_mode = canonical_order_bucketed(&set, &grid, 0);
        let attrs = |i: u32| {
            let (p, c) = (positions[i as usize], colours[i as usize]);
            [p.x, p.y, p.z, radii[i as usize], c[0], c[1], c[2]]
        };
        let mut reference = rows_mode.clone();
        reference.sort_by(|a, b| {
            let (x, y) = (attrs(a.1), attrs(b.1));
            let tie = x.iter().zip(&y).map(|(u, v)| u.total_cmp(v));
            a.0.cmp(&b.0)
                .then(tie.fold(Ordering::Equal, Ordering::then))
        });
        let bits = |o: &[(u64, u32)]| {
            o.iter()
                .map(|&(k, i)| (k, attrs(i).map(f32::to_bits)))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&rows_mode), bits(&reference));
        assert_eq!(bits(&planes_mode), bits(&reference));
        assert!(
            reference.windows(2).any(|w| w[0].0 == w[1].0),
            "the case has ties"
        );
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
