//! Stage 2 of the periodic engine in a triclinic cell: the density (and colour) of the atoms'
//! images at the cell's samples (see [`super::triclinic`] for the definitions).
//!
//! Data flow: the images in canonical order ([`super::triclinic::images`]) -> per slab of
//! planes along c, the images that reach it -> per image and plane, the rows its cutoff sphere
//! reaches (a quadratic in the row index across the rows, [`rows_reached`]) -> per row, the
//! samples within the cutoff (a quadratic along the row) -> their terms [`ROW_LANES`] at a time
//! ([`add_run`]).
//!
//! Each sample adds its images' terms in the images' order, whatever the slab size or thread
//! count, so the volume does not depend on either. The exponential is a polynomial
//! ([`exp_fast`], relative error below 1e-6) so that the row kernel vectorises; the cutoff
//! test is on the squared distance in Å², as the other engines'.

use glam::Vec3;
use rayon::prelude::*;

use super::triclinic::{Geometry, Image};
use crate::surface::DensityVolume;
use crate::surface::analytic::exp_fast;

/// Inclusive index range `0..n` within `half` samples of `g`, `None` when empty.
fn span(g: f32, half: f64, n: u32) -> Option<(u32, u32)> {
    let lo = (g as f64 - half).floor() as i64;
    let hi = (g as f64 + half).ceil() as i64;
    let (lo, hi) = (lo.max(0), hi.min(n as i64 - 1));
    (lo <= hi).then_some((lo as u32, hi as u32))
}

/// The most bytes of samples (density and colour) one slab of the fill holds, about a core's
/// share of a second-level cache.
const SLAB_BYTES: usize = 512 * 1024;

/// Fills `vol` with the density (and colour divided by `iso` when `with_colour`) of `images`
/// at the samples of `geo`, reusing the buffers when the grid keeps its size.
pub fn fill(
    vol: &mut DensityVolume,
    images: &[Image],
    geo: &Geometry,
    iso: f32,
    with_colour: bool,
) {
    let [nx, ny, nz] = geo.dims;
    let total = nx as usize * ny as usize * nz as usize;
    let plane = nx as usize * ny as usize;
    if vol.values.len() != total {
        vol.values = vec![0.0; total];
    }
    if !with_colour {
        vol.colours = None;
    } else if vol.colours.as_ref().is_none_or(|c| c.len() != total) {
        vol.colours = Some(vec![[0.0; 3]; total]);
    }
    // Slabs of planes along c, each with the images that reach it (ascending, so canonical):
    // about eight per thread, and small enough that a slab's samples stay in a core's cache
    // while its images visit them (at H = 0.5 Å on adk in water, one plane a slab instead of
    // ten took the fill from about 630 to 430 ms).
    let threads = rayon::current_num_threads().max(1) as u32;
    let sample_bytes = if with_colour { 16 } else { 4 };
    let cached_planes = (SLAB_BYTES / (plane * sample_bytes)).max(1) as u32;
    let slab_planes = (nz / (8 * threads)).clamp(1, 64).min(cached_planes);
    let slab_count = nz.div_ceil(slab_planes) as usize;
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); slab_count];
    for (i, img) in images.iter().enumerate() {
        let half = img.cut as f64 * geo.reach[2] + 1.0;
        if let Some((k0, k1)) = span(img.index[2], half, nz) {
            for s in k0 / slab_planes..=k1 / slab_planes {
                lists[s as usize].push(i as u32);
            }
        }
    }
    let slab_len = plane * slab_planes as usize;
    let inv_iso = 1.0 / iso;
    let run = |s: usize, vals: &mut [f32], cols: Option<&mut [[f32; 3]]>| {
        let z0 = s as u32 * slab_planes;
        let z1 = (z0 + slab_planes).min(nz) - 1;
        let slab = Slab {
            images,
            list: &lists[s],
            geo,
            planes: (z0, z1),
        };
        fill_slab(&slab, vals, cols);
    };
    match vol.colours.as_mut() {
        None => vol
            .values
            .par_chunks_mut(slab_len)
            .enumerate()
            .for_each(|(s, vals)| {
                vals.fill(0.0);
                run(s, vals, None);
            }),
        Some(cols) => vol
            .values
            .par_chunks_mut(slab_len)
            .zip(cols.par_chunks_mut(slab_len))
            .enumerate()
            .for_each(|(s, (vals, cols))| {
                vals.fill(0.0);
                cols.fill([0.0; 3]);
                run(s, vals, Some(&mut *cols));
                for c in cols.iter_mut() {
                    *c = c.map(|v| v * inv_iso);
                }
            }),
    }
}

/// One slab's work: the images `list` (indices into `images`) that reach its planes
/// `planes.0..=planes.1` of the samples of `geo`.
struct Slab<'a> {
    images: &'a [Image],
    list: &'a [u32],
    geo: &'a Geometry,
    planes: (u32, u32),
}

/// Adds the slab's images to its planes (`vals`, `cols` hold those planes).
fn fill_slab(slab: &Slab<'_>, vals: &mut [f32], cols: Option<&mut [[f32; 3]]>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { fill_slab_avx2(slab, vals, cols) };
        return;
    }
    fill_slab_body(slab, vals, cols);
}

/// [`fill_slab`] compiled for AVX2 (8-wide rows); the same operations in the same order (Rust
/// never fuses a multiply and an add), so the same bits as the portable build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fill_slab_avx2(slab: &Slab<'_>, vals: &mut [f32], cols: Option<&mut [[f32; 3]]>) {
    fill_slab_body(slab, vals, cols);
}

/// The body of [`fill_slab`], inlined into each instruction-set variant: per image and row,
/// the samples its cutoff sphere reaches (a quadratic in the row's index), their terms
/// computed [`ROW_LANES`] at a time ([`add_run`]).
#[inline(always)]
fn fill_slab_body(slab: &Slab<'_>, vals: &mut [f32], mut cols: Option<&mut [[f32; 3]]>) {
    let Slab {
        images,
        list,
        geo,
        planes: (z0, z1),
    } = *slab;
    let [nx, ny, _] = geo.dims;
    let plane = nx as usize * ny as usize;
    let [u, v, w] = [geo.jac.x_axis, geo.jac.y_axis, geo.jac.z_axis].map(|c| c.as_vec3());
    let uu = u.dot(u);
    // The parts of v and of a row's start across the rows (orthogonal to u): a row is
    // reached when that part of its start lies within the cutoff.
    let across = |x: Vec3| x - u * (u.dot(x) / uu);
    let v_across = across(v);
    let vv_across = v_across.dot(v_across);
    for &a in list {
        let img = &images[a as usize];
        let cut2 = img.cut * img.cut;
        let half = |axis: usize| img.cut as f64 * geo.reach[axis] + 1.0;
        let Some((k0, k1)) = span(img.index[2], half(2), z1 + 1) else {
            continue;
        };
        let Some((j0, j1)) = span(img.index[1], half(1), ny) else {
            continue;
        };
        for k in k0.max(z0)..=k1 {
            let zoff = (k - z0) as usize * plane;
            let ek = k as f32 * w - img.pos;
            let Some((j0, j1)) = rows_reached(across(ek), v_across, vv_across, cut2, (j0, j1))
            else {
                continue;
            };
            for j in j0..=j1 {
                // Samples of this row: |i u + e|^2 < cut^2, a quadratic in i.
                let e = ek + j as f32 * v;
                let ue = u.dot(e);
                let disc = ue * ue - uu * (e.dot(e) - cut2);
                if disc <= 0.0 {
                    continue;
                }
                let root = disc.sqrt();
                let lo = ((-ue - root) / uu).floor() as i64;
                let hi = ((-ue + root) / uu).ceil() as i64;
                let (lo, hi) = (lo.max(0) as usize, hi.min(nx as i64 - 1));
                if hi < lo as i64 {
                    continue;
                }
                let row = zoff + j as usize * nx as usize;
                let run = Run {
                    e,
                    u,
                    k: img.k,
                    cut2,
                    first: lo,
                    last: hi as usize,
                };
                let row_cols = cols
                    .as_deref_mut()
                    .map(|c| (&mut c[row..row + nx as usize], img.colour));
                add_run(&mut vals[row..row + nx as usize], row_cols, &run);
            }
        }
    }
}

/// The rows `j` of a plane whose start's part across the rows, `e + j v` (Å), lies within
/// `cut2` (Å²) of the image, a quadratic in `j`, widened by one row each way against rounding
/// (each row is tested again) and kept within `rows`.
#[inline(always)]
fn rows_reached(e: Vec3, v: Vec3, vv: f32, cut2: f32, rows: (u32, u32)) -> Option<(u32, u32)> {
    let b = v.dot(e);
    let disc = b * b - vv * (e.dot(e) - cut2);
    if disc <= 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let lo = ((-b - root) / vv).floor() as i64 - 1;
    let hi = ((-b + root) / vv).ceil() as i64 + 1;
    let (lo, hi) = (lo.max(rows.0 as i64), hi.min(rows.1 as i64));
    (lo <= hi).then_some((lo as u32, hi as u32))
}

/// Samples per step of [`add_run`] (one AVX2 register of f32).
const ROW_LANES: usize = 8;

/// The samples `first..=last` of one row that one image may reach: sample `i` lies at
/// `d = e + i u` (Å) from the image, whose exponent factor is `k` (Å⁻²) and squared cutoff
/// `cut2` (Å²).
struct Run {
    e: Vec3,
    u: Vec3,
    k: f32,
    cut2: f32,
    first: usize,
    last: usize,
}

/// Adds the image's term `exp(-k d^2)` to each sample of `run` in `row` (and `g colour` to the
/// colour sums) where `d^2 < cut2`. [`ROW_LANES`] samples at a time with no branch per sample
/// and a polynomial exponential ([`exp_fast`], relative error below 1e-6), so each step is a
/// few vector instructions; lanes outside the run or the cutoff add `+0.0`, which changes
/// nothing. A row shorter than [`ROW_LANES`] takes its samples one by one.
#[inline(always)]
fn add_run(row: &mut [f32], mut cols: Option<(&mut [[f32; 3]], [f32; 3])>, run: &Run) {
    let term = |i: usize| {
        let fi = i as f32;
        let (dx, dy, dz) = (
            run.e.x + fi * run.u.x,
            run.e.y + fi * run.u.y,
            run.e.z + fi * run.u.z,
        );
        let d2 = dx * dx + dy * dy + dz * dz;
        let g = exp_fast(-run.k * d2);
        if d2 < run.cut2 { g } else { 0.0 }
    };
    if row.len() < ROW_LANES {
        for i in run.first..=run.last {
            let g = term(i);
            row[i] += g;
            if let Some((cols, colour)) = cols.as_mut() {
                for (y, &z) in cols[i].iter_mut().zip(colour.iter()) {
                    *y += g * z;
                }
            }
        }
        return;
    }
    let mut at = run.first;
    while at <= run.last {
        let base = at.min(row.len() - ROW_LANES);
        let mut terms = [0.0f32; ROW_LANES];
        for (l, t) in terms.iter_mut().enumerate() {
            let i = base + l;
            let g = term(i);
            *t = if i >= at && i <= run.last { g } else { 0.0 };
        }
        let out: &mut [f32; ROW_LANES] = (&mut row[base..base + ROW_LANES])
            .try_into()
            .expect("ROW_LANES samples");
        for (x, &t) in out.iter_mut().zip(&terms) {
            *x += t;
        }
        if let Some((cols, colour)) = cols.as_mut() {
            let out: &mut [[f32; 3]; ROW_LANES] = (&mut cols[base..base + ROW_LANES])
                .try_into()
                .expect("ROW_LANES samples");
            for (c, &t) in out.iter_mut().zip(&terms) {
                for (y, &z) in c.iter_mut().zip(colour.iter()) {
                    *y += t * z;
                }
            }
        }
        at = base + ROW_LANES;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::periodic::TriclinicCell;

    /// A skewed cell (no edge along an axis, so every row and plane is sheared).
    fn cell() -> TriclinicCell {
        TriclinicCell::new([
            Vec3::new(14.0, 1.5, -0.8),
            Vec3::new(4.0, 12.5, 1.0),
            Vec3::new(-3.0, 5.0, 11.0),
        ])
        .expect("cell")
    }

    /// Images spread over and beyond the cell (some outside it, as images are), with the
    /// cutoffs and colours of different atoms.
    fn some_images(geo: &Geometry) -> Vec<Image> {
        let m = geo.cell.matrix();
        let dims = geo.dims.map(f64::from);
        (0..40)
            .map(|n| {
                let t = n as f64;
                let f = glam::DVec3::new(
                    (t * 0.618).fract() * 1.2 - 0.1,
                    (t * 0.414).fract() * 1.2 - 0.1,
                    (t * 0.732).fract() * 1.2 - 0.1,
                );
                let alpha = 1.1 + 0.05 * (n % 9) as f32;
                Image {
                    index: (f * glam::DVec3::from(dims)).as_vec3().to_array(),
                    pos: (m * f).as_vec3(),
                    k: 0.5 / (alpha * alpha),
                    cut: 2.5 * alpha,
                    colour: [0.1 * (n % 7) as f32, 0.5, 1.0 - 0.05 * (n % 5) as f32],
                }
            })
            .collect()
    }

    /// Every image at every sample with the C library's exponential, the offsets formed as
    /// the engine forms them (so that the cutoff test decides the same pairs).
    fn brute_force(images: &[Image], geo: &Geometry) -> (Vec<f32>, Vec<[f32; 3]>) {
        let [nx, ny, nz] = geo.dims;
        let [u, v, w] = [geo.jac.x_axis, geo.jac.y_axis, geo.jac.z_axis].map(|c| c.as_vec3());
        let total = (nx * ny * nz) as usize;
        let (mut vals, mut cols) = (vec![0.0f32; total], vec![[0.0f32; 3]; total]);
        for img in images {
            for k in 0..nz {
                for j in 0..ny {
                    let e = (k as f32 * w - img.pos) + j as f32 * v;
                    for i in 0..nx {
                        let d = e + i as f32 * u;
                        let d2 = d.dot(d);
                        if d2 < img.cut * img.cut {
                            let g = (-img.k * d2).exp();
                            let at = ((k * ny + j) * nx + i) as usize;
                            vals[at] += g;
                            for (y, &z) in cols[at].iter_mut().zip(&img.colour) {
                                *y += g * z;
                            }
                        }
                    }
                }
            }
        }
        (vals, cols)
    }

    #[test]
    fn fill_adds_every_image_within_its_cutoff_and_no_other() {
        // 6 samples along a: rows shorter than ROW_LANES; 23: runs against the row's end.
        for dims in [[6, 11, 9], [23, 19, 17]] {
            let geo = Geometry::new(cell(), dims);
            let images = some_images(&geo);
            let (want, want_cols) = brute_force(&images, &geo);
            let mut vol = DensityVolume::default();
            let iso = 0.5;
            fill(&mut vol, &images, &geo, iso, true);
            let cols = vol.colours.as_ref().expect("colours");
            let mut reached = 0;
            for (n, (&got, &exp)) in vol.values.iter().zip(&want).enumerate() {
                assert!(
                    (got - exp).abs() <= 4e-6 * exp.max(1e-3),
                    "{dims:?} sample {n}: {got} against {exp}"
                );
                reached += usize::from(exp > 0.0);
                for c in 0..3 {
                    let exp_c = want_cols[n][c] / iso;
                    assert!(
                        (cols[n][c] - exp_c).abs() <= 4e-6 * exp_c.max(1e-3),
                        "{dims:?} sample {n} channel {c}: {} against {exp_c}",
                        cols[n][c]
                    );
                }
            }
            assert!(
                reached > vol.values.len() / 4,
                "{dims:?}: {reached} reached"
            );
            // Without colours, the same density to the bit.
            let mut plain = DensityVolume::default();
            fill(&mut plain, &images, &geo, iso, false);
            assert!(plain.colours.is_none());
            assert_eq!(plain.values, vol.values);
        }
    }
}
