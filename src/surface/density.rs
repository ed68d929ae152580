//! Stage 2 of the CPU engine (the paper's `t_d`): the Gaussian density volume and, when the atoms
//! carry colours, the colour volume, sampled on a [`GridSpec`] (DESIGN section 2).
//!
//! Data flow: [`AtomBins`] (from [`super::bin`]) -> [`DensityVolume`] -> Marching Cubes
//! ([`super::marching_cubes`]).
//!
//! Definitions: `rho(x) = sum_i exp(-|x - p_i|^2 / (2 alpha_i^2))` over the atoms with
//! `|x - p_i|^2 < (q alpha_i)^2` (the per-pair cutoff, tested before the exponential), and
//! `c(x) = sum_i w_i(x) colour_i / I` with the same weights. The exponential is evaluated per
//! axis (`exp(-k d^2) = exp(-k dx^2) exp(-k dy^2) exp(-k dz^2)`), which matches the direct formula
//! to a few f32 ulps; the cutoff test uses the full `d^2 = (dx^2 + dy^2) + dz^2`.
//!
//! Parallelism: rayon over z-slabs of the grid; each slab sums the atoms that reach it in
//! canonical order (see [`super::bin`]), so every voxel's sum is the same for any permutation of
//! the input, any slab size and any thread count.

use rayon::prelude::*;

use super::bin::{AtomBins, bin_atoms, sample_range};
use super::{AtomSet, GridSpec, SurfaceError, SurfaceParams};

/// The sampled density and (optionally) colour volume of one surface.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DensityVolume {
    /// Density per grid sample (dimensionless), x fastest (see [`GridSpec::index`]).
    pub values: Vec<f32>,
    /// Colour per grid sample, `sum_i w_i colour_i / I` (linear RGB; about 0..1 on the surface),
    /// present only when the atoms carry colours.
    pub colours: Option<Vec<[f32; 3]>>,
}

/// Density (and colour volume when `atoms.colours` is set) of `atoms` on `grid` under `params`.
///
/// `grid` is normally [`GridSpec::for_atoms`] of the same atoms, but any grid works (atoms
/// outside it simply contribute where they reach). Fails on bad parameters or atoms
/// (see [`AtomSet::validate`]).
pub fn compute(
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    grid: &GridSpec,
) -> Result<DensityVolume, SurfaceError> {
    params.validate()?;
    atoms.validate()?;
    let planes = slab_planes(grid);
    let bins = bin_atoms(atoms, params, grid, planes);
    Ok(compute_binned(&bins, params, grid, atoms.colours.is_some()))
}

/// Grid planes per density slab: about eight slabs per thread for load balance, at least two
/// planes each.
pub fn slab_planes(grid: &GridSpec) -> u32 {
    let threads = rayon::current_num_threads().max(1) as u32;
    (grid.dims[2] / (8 * threads)).clamp(2, 64)
}

/// Density (and colour volume when `with_colour`) from atoms already binned for `grid`.
/// Colours come from [`super::bin::PreparedAtom::colour`].
pub fn compute_binned(
    bins: &AtomBins,
    params: &SurfaceParams,
    grid: &GridSpec,
    with_colour: bool,
) -> DensityVolume {
    let mut out = DensityVolume::default();
    compute_binned_into(bins, params, grid, with_colour, &mut out);
    out
}

/// [`compute_binned`] into `out`, reusing its buffers when they already have the grid's size
/// (one frame after another), which saves allocating and page-faulting them again.
pub fn compute_binned_into(
    bins: &AtomBins,
    params: &SurfaceParams,
    grid: &GridSpec,
    with_colour: bool,
    out: &mut DensityVolume,
) {
    let lattice = SampleLattice::of_grid(grid);
    fill_binned_into(bins, &lattice, params.isovalue, with_colour, out);
}

/// The samples a density kernel adds to: sample `(i, j, k)` (each from 0 to `dims - 1`) at
/// `origin + (i h_x, j h_y, k h_z)`. The dense engine's grid has one spacing; the periodic
/// engine's box has one per axis and local coordinates (origin 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SampleLattice {
    /// Position of sample (0, 0, 0) in Å, in the atoms' coordinates.
    pub origin: [f32; 3],
    /// Spacing per axis in Å.
    pub spacing: [f32; 3],
    /// Samples per axis.
    pub dims: [u32; 3],
}

impl SampleLattice {
    /// The samples of a dense grid.
    pub fn of_grid(grid: &GridSpec) -> SampleLattice {
        SampleLattice {
            origin: grid.origin.to_array(),
            spacing: [grid.spacing; 3],
            dims: grid.dims,
        }
    }
}

/// Density (and colour volume, `sum w colour / iso`, when `with_colour`) of the binned atoms
/// on `lattice` into `out`, slab by slab in parallel, reusing `out`'s buffers when they
/// already have the lattice's size. The dense and the periodic engine both fill through it.
pub(crate) fn fill_binned_into(
    bins: &AtomBins,
    lattice: &SampleLattice,
    iso: f32,
    with_colour: bool,
    out: &mut DensityVolume,
) {
    let [nx, ny, nz] = lattice.dims.map(|d| d as usize);
    let plane = nx * ny;
    let slab_len = (plane * bins.slab_planes as usize).max(1);
    let total = plane * nz;
    // Every sample is written below (each slab is zeroed first, colours assigned).
    fit_len(&mut out.values, total, 0.0);
    match (with_colour, &mut out.colours) {
        (false, colours) => *colours = None,
        (true, Some(colours)) => fit_len(colours, total, [0.0; 3]),
        (true, colours) => *colours = Some(vec![[0.0f32; 3]; total]),
    }
    let inv_iso = 1.0 / iso;
    let values = &mut out.values;
    match out.colours.as_mut() {
        None => values
            .par_chunks_mut(slab_len)
            .enumerate()
            .for_each(|(s, vals)| {
                vals.fill(0.0);
                fill_slab(bins, lattice, s, vals, None);
            }),
        Some(cols) => values
            .par_chunks_mut(slab_len)
            .zip(cols.par_chunks_mut(slab_len))
            .enumerate()
            .for_each(|(s, (vals, cols))| {
                vals.fill(0.0);
                // The kernel sums each channel in its own plane (vectorised), then the
                // channels are interleaved and scaled by 1/I. The planes are the thread's
                // own, kept from slab to slab and frame to frame.
                COLOUR_PLANES.with_borrow_mut(|planes| {
                    for plane in planes.iter_mut() {
                        plane.clear();
                        plane.resize(vals.len(), 0.0);
                    }
                    let [r, g, b] = planes;
                    fill_slab(bins, lattice, s, vals, Some([&mut *r, &mut *g, &mut *b]));
                    // Zipped, so the interleaving runs without bounds checks.
                    for (c, ((r, g), b)) in
                        cols.iter_mut().zip(r.iter().zip(g.iter()).zip(b.iter()))
                    {
                        *c = [*r * inv_iso, *g * inv_iso, *b * inv_iso];
                    }
                })
            }),
    }
}

/// Makes `buffer` `len` long, keeping its memory when it holds that many and is not more than
/// twice too large. On a trajectory the grid changes size from frame to frame: a new buffer
/// would fault its pages in again (about 0.3 ms of a 1.5 ms frame for 200,000 samples).
/// Contents are left to the caller to overwrite.
fn fit_len<T: Copy>(buffer: &mut Vec<T>, len: usize, zero: T) {
    if buffer.capacity() >= len && buffer.capacity() <= 2 * len {
        buffer.truncate(len);
        buffer.resize(len, zero);
    } else {
        *buffer = Vec::new();
        *buffer = vec![zero; len];
    }
}

thread_local! {
    /// One thread's colour sums of a dense slab, one plane per channel (see
    /// [`compute_binned_into`]).
    static COLOUR_PLANES: std::cell::RefCell<[Vec<f32>; 3]> = std::cell::RefCell::default();
}

/// Per-axis samples an atom reaches: first index, squared distances (Å²) and exponentials.
#[derive(Default)]
struct AxisTerms {
    first: usize,
    d2: Vec<f32>,
    e: Vec<f32>,
}

impl AxisTerms {
    /// Fills the terms for samples `lo..=hi` of an axis with origin `o` (Å), spacing `h` (Å),
    /// atom coordinate `p` (Å) and exponent factor `k` (Å⁻²).
    /// Samples with `d^2 >= cut2` along this axis alone are dropped from both ends: f32
    /// addition of non-negative terms never decreases, so they fail the full cutoff test too,
    /// and `d^2` is monotonic in `|i - p|`, so the samples kept are contiguous.
    /// Returns false when no sample is kept.
    #[allow(clippy::too_many_arguments)]
    fn fill(&mut self, lo: u32, hi: u32, o: f32, h: f32, p: f32, k: f32, cut2: f32) -> bool {
        self.d2.clear();
        self.e.clear();
        let mut first = None;
        for i in lo..=hi {
            let d = (o + h * i as f32) - p;
            let d2 = d * d;
            if d2 < cut2 {
                first.get_or_insert(i);
                self.d2.push(d2);
            } else if first.is_some() {
                break;
            }
        }
        self.first = first.unwrap_or(lo) as usize;
        self.e.extend(self.d2.iter().map(|&d2| (-k * d2).exp()));
        !self.d2.is_empty()
    }
}

/// Width of the fixed-size row kernel (samples along x).
const LANES: usize = 16;

/// The x terms of one atom padded to [`LANES`]: `d2 = +inf` and `e = 0` past its reach.
struct Lanes {
    d2: [f32; LANES],
    e: [f32; LANES],
}

impl Lanes {
    fn new(t: &AxisTerms) -> Lanes {
        let mut l = Lanes {
            d2: [f32::INFINITY; LANES],
            e: [0.0; LANES],
        };
        l.d2[..t.d2.len()].copy_from_slice(&t.d2);
        l.e[..t.e.len()].copy_from_slice(&t.e);
        l
    }
}

/// Adds every atom of slab `s` to that slab's samples (`vals`, and `cols` when colouring).
fn fill_slab(
    bins: &AtomBins,
    lattice: &SampleLattice,
    s: usize,
    vals: &mut [f32],
    cols: Option<ColourPlanes<'_>>,
) {
    let z0 = s as u32 * bins.slab_planes;
    let z1 = (z0 + bins.slab_planes).min(lattice.dims[2]) - 1;
    fill_planes(&bins.atoms, bins.slab(s), lattice, z0, z1, vals, cols);
}

/// Colour sums of a run of samples, one plane per channel (red, green, blue; laid out as the
/// density samples), so that the row kernel adds each channel with vector instructions.
pub(crate) type ColourPlanes<'a> = [&'a mut [f32]; 3];

/// Adds the atoms `list` (indices into `atoms`, ascending) to the samples of grid planes
/// `z0..=z1`: `vals` (and `cols` when colouring, each channel `w_i colour_i` summed in its own
/// plane) hold those planes, plane `z0` first, x fastest.
/// Every sample's terms are added in list order, so any list holding the atoms that reach a
/// sample, in canonical order, gives that sample the same bits. Only samples inside an atom's
/// [`sample_range`] box get a non-zero term (others may get `+0.0` added, which changes nothing).
pub(crate) fn fill_planes(
    atoms: &[super::bin::PreparedAtom],
    list: &[u32],
    lattice: &SampleLattice,
    z0: u32,
    z1: u32,
    vals: &mut [f32],
    cols: Option<ColourPlanes<'_>>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { fill_planes_avx2(atoms, list, lattice, z0, z1, vals, cols) };
        return;
    }
    fill_planes_body(atoms, list, lattice, z0, z1, vals, cols);
}

/// [`fill_planes`] compiled for AVX2, whose 8-wide registers halve the instructions of the
/// [`LANES`]-wide row kernel. The same arithmetic in the same order (Rust never fuses a
/// multiply and an add), so the same bits as the portable build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fill_planes_avx2(
    atoms: &[super::bin::PreparedAtom],
    list: &[u32],
    lattice: &SampleLattice,
    z0: u32,
    z1: u32,
    vals: &mut [f32],
    cols: Option<ColourPlanes<'_>>,
) {
    fill_planes_body(atoms, list, lattice, z0, z1, vals, cols);
}

/// The body of [`fill_planes`], inlined into each instruction-set variant.
#[inline(always)]
fn fill_planes_body(
    atoms: &[super::bin::PreparedAtom],
    list: &[u32],
    lattice: &SampleLattice,
    z0: u32,
    z1: u32,
    vals: &mut [f32],
    mut cols: Option<ColourPlanes<'_>>,
) {
    let [nx, ny, nz] = lattice.dims;
    let (o, h) = (lattice.origin, lattice.spacing);
    let plane = nx as usize * ny as usize;
    let (mut tx, mut ty, mut tz) = (
        AxisTerms::default(),
        AxisTerms::default(),
        AxisTerms::default(),
    );
    for &a in list {
        let atom = &atoms[a as usize];
        let [px, py, pz] = atom.pos;
        let (Some(rx), Some(ry), Some(rz)) = (
            sample_range(px, atom.cut, o[0], h[0], nx),
            sample_range(py, atom.cut, o[1], h[1], ny),
            sample_range(pz, atom.cut, o[2], h[2], nz),
        ) else {
            continue;
        };
        let (k0, k1) = (rz.0.max(z0), rz.1.min(z1));
        if k0 > k1 {
            continue;
        }
        let cut2 = atom.cut2;
        if !(tx.fill(rx.0, rx.1, o[0], h[0], px, atom.k, cut2)
            && ty.fill(ry.0, ry.1, o[1], h[1], py, atom.k, cut2)
            && tz.fill(k0, k1, o[2], h[2], pz, atom.k, cut2))
        {
            continue;
        }
        let wide = (tx.d2.len() <= LANES).then(|| Lanes::new(&tx));
        for (kz, (&dz2, &ez)) in tz.d2.iter().zip(&tz.e).enumerate() {
            let zoff = (tz.first + kz - z0 as usize) * plane;
            for (jy, (&dy2, &ey)) in ty.d2.iter().zip(&ty.e).enumerate() {
                if dy2 + dz2 >= cut2 {
                    continue;
                }
                let eyz = ey * ez;
                let row0 = zoff + (ty.first + jy) * nx as usize + tx.first;
                if let Some(lanes) = wide.as_ref()
                    && row0 + LANES <= vals.len()
                    && let Ok(out) = <&mut [f32; LANES]>::try_from(&mut vals[row0..row0 + LANES])
                {
                    // Fixed-width path: lanes past the atom's reach (or failing the cutoff)
                    // get weight exactly 0.0, which changes no sample.
                    let mut w = [0.0f32; LANES];
                    for l in 0..LANES {
                        let pass = (lanes.d2[l] + dy2) + dz2 < cut2;
                        w[l] = if pass { lanes.e[l] * eyz } else { 0.0 };
                        out[l] += w[l];
                    }
                    if let Some(planes) = cols.as_mut() {
                        for (plane, &c) in planes.iter_mut().zip(&atom.colour) {
                            if let Ok(out) =
                                <&mut [f32; LANES]>::try_from(&mut plane[row0..row0 + LANES])
                            {
                                for l in 0..LANES {
                                    out[l] += w[l] * c;
                                }
                            }
                        }
                    }
                    continue;
                }
                // The samples of this row that pass the exact cutoff test are contiguous
                // (the test is monotonic in dx^2): trim the failing ones from both ends, then
                // add without a mask.
                let pass = |d: f32| (d + dy2) + dz2 < cut2;
                let mut a = 0;
                let mut b = tx.d2.len();
                while a < b && !pass(tx.d2[a]) {
                    a += 1;
                }
                while b > a && !pass(tx.d2[b - 1]) {
                    b -= 1;
                }
                let exs = &tx.e[a..b];
                let row = row0 + a;
                let out = &mut vals[row..row + exs.len()];
                for (v, &ex) in out.iter_mut().zip(exs) {
                    *v += ex * eyz;
                }
                if let Some(planes) = cols.as_mut() {
                    for (plane, &c) in planes.iter_mut().zip(&atom.colour) {
                        let out = &mut plane[row..row + exs.len()];
                        for (v, &ex) in out.iter_mut().zip(exs) {
                            *v += ex * eyz * c;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The instruction-set variant `fill_planes` picks on this CPU gives the portable build's
    /// bits, with and without colours, on rows both narrower and wider than [`LANES`].
    #[test]
    fn dispatched_kernel_matches_portable_bits() {
        let mut seed = 0x5eed_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let positions: Vec<Vec3> = (0..300)
            .map(|_| Vec3::new(next() * 30.0, next() * 25.0, next() * 20.0))
            .collect();
        // Radii up to 4 Å reach more than LANES samples at H = 0.4 Å.
        let radii: Vec<f32> = (0..300).map(|_| 1.0 + 3.0 * next()).collect();
        let colours: Vec<[f32; 3]> = (0..300).map(|_| [next(), next(), next()]).collect();
        let atoms = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: Some(&colours),
        };
        for spacing in [0.4, 1.0] {
            let params = SurfaceParams {
                spacing,
                ..SurfaceParams::default()
            };
            let grid = GridSpec::for_atoms(&positions, &radii, &params).unwrap();
            let bins = bin_atoms(&atoms, &params, &grid, grid.dims[2]);
            let n = grid.voxel_count() as usize;
            let list: Vec<u32> = (0..bins.atoms.len() as u32).collect();
            let z1 = grid.dims[2] - 1;
            let lattice = SampleLattice::of_grid(&grid);
            let (mut v1, mut c1) = (vec![0.0f32; n], [(); 3].map(|_| vec![0.0f32; n]));
            let (mut v2, mut c2) = (vec![0.0f32; n], [(); 3].map(|_| vec![0.0f32; n]));
            let [r1, g1, b1] = &mut c1;
            fill_planes(
                &bins.atoms,
                &list,
                &lattice,
                0,
                z1,
                &mut v1,
                Some([r1, g1, b1]),
            );
            let [r2, g2, b2] = &mut c2;
            fill_planes_body(
                &bins.atoms,
                &list,
                &lattice,
                0,
                z1,
                &mut v2,
                Some([r2, g2, b2]),
            );
            assert!(v1.iter().any(|&v| v > 1.0), "no overlap at H = {spacing}");
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&v1), bits(&v2), "density at H = {spacing}");
            for (a, b) in c1.iter().zip(&c2) {
                assert_eq!(bits(a), bits(b), "colour at H = {spacing}");
            }
        }
    }
}
