//! `within D of SEL`: which atoms lie within D Å of any source atom, with a cell grid.
//!
//! With a periodic box (orthorhombic or triclinic), every position is first wrapped into the
//! box (through fractional coordinates), and the atoms of the set that gets binned are copied
//! with each periodic image that lies within D of the box (a slab test per box axis, in
//! fractional coordinates; any box shape, and boxes narrower than D get several images). A
//! wrapped atom then finds every partner within D among those copies, so the search itself is a
//! plain Cartesian one: no minimum-image convention is needed.
//!
//! The smaller of the two sets (sources, targets) is binned into Cartesian cells D wide: a
//! [`CutoffCells`], the crate's one cell list ([`crate::model::cells`], shared with bond
//! guessing, exposure counts and radius fitting) with the cells within D of a binned atom
//! marked. Each atom of the larger set (in parallel) is rejected by one look-up when its cell
//! is unmarked, and otherwise visits the 3 × 3 × 3 cells around its own, row by row, skipping
//! cells whose nearest point is farther than D. With few sources (`within 5 of protein` in
//! water) each target looks for any source around it, its own cell first; with few targets
//! (`ion and within 5 of water`) each source marks the targets around it.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Mat3, Mat3A, Vec3, Vec3A};
use rayon::prelude::*;

use crate::model::cells::CutoffCells;

/// Atoms per parallel task.
const CHUNK: usize = 1024;

/// Atoms `i` with `targets[i]` that lie within `distance` Å (inclusive) of some atom in
/// `sources` in `positions`, counting periodic images when `cell` (box edge vectors a, b, c in
/// Å) is given. Indices past the end of `positions` are never selected.
pub(crate) fn within(
    positions: &[Vec3],
    cell: Option<&[Vec3; 3]>,
    sources: &[u32],
    targets: &[bool],
    distance: f32,
) -> Vec<bool> {
    let mut out = vec![false; targets.len()];
    let n = targets.len().min(positions.len());
    let sources: Vec<u32> = sources
        .iter()
        .copied()
        .filter(|&s| (s as usize) < n)
        .collect();
    let target_count = targets[..n].iter().filter(|t| **t).count();
    if sources.is_empty() || target_count == 0 || !distance.is_finite() || distance < 0.0 {
        return out;
    }
    let space = cell.and_then(Periodic::new);
    // Wrapped position of atom `i`, or `None` when it is not finite.
    let place = |i: usize| {
        let p = Vec3A::from(positions[i]);
        p.is_finite()
            .then(|| space.as_ref().map_or(p, |s| s.wrap(p)))
    };
    let binned = |atoms: &mut dyn Iterator<Item = usize>| {
        let points: Vec<(u32, Vec3)> = match &space {
            Some(s) => {
                let wrapped: Vec<(u32, Vec3A)> = atoms
                    .filter_map(|i| place(i).map(|p| (i as u32, p)))
                    .collect();
                s.with_images(&wrapped, distance)
            }
            None => atoms
                .filter(|&i| positions[i].is_finite())
                .map(|i| (i as u32, positions[i]))
                .collect(),
        };
        CutoffCells::new(&points, distance)
    };
    if target_count < sources.len() {
        // Few targets: bin them, and let each source near one mark the targets around it.
        let near = binned(&mut (0..n).filter(|&i| targets[i]));
        let marks: Vec<AtomicBool> = (0..targets.len()).map(|_| AtomicBool::new(false)).collect();
        sources.par_chunks(CHUNK).for_each(|chunk| {
            for p in chunk.iter().filter_map(|&s| place(s as usize)) {
                near.for_each_within(p, |i| marks[i as usize].store(true, Ordering::Relaxed));
            }
        });
        out.iter_mut()
            .zip(marks)
            .for_each(|(o, m)| *o = m.into_inner());
    } else {
        // Few sources: bin them, and let each target near one look for one. A target that is
        // itself a source (at a finite position) is at distance 0: no search.
        let near = binned(&mut sources.iter().map(|&s| s as usize));
        let mut is_source = vec![false; n];
        for &s in &sources {
            is_source[s as usize] = positions[s as usize].is_finite();
        }
        out[..n]
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (j, o) in chunk.iter_mut().enumerate() {
                    let i = k * CHUNK + j;
                    *o = targets[i]
                        && (is_source[i] || place(i).is_some_and(|p| near.any_within(p)));
                }
            });
    }
    out
}

/// A periodic box: edge vectors, the map to fractional coordinates, and face-to-face widths.
struct Periodic {
    /// Box edge vectors a, b, c in Å.
    edges: [Vec3A; 3],
    /// Cartesian to fractional coordinates.
    to_fraction: Mat3A,
    /// Width of the box between the faces opposite each edge, in Å.
    widths: Vec3,
}

impl Periodic {
    /// The box with edges `e`, or `None` when it is degenerate.
    fn new(e: &[Vec3; 3]) -> Option<Periodic> {
        let volume = e[0].dot(e[1].cross(e[2])).abs();
        if !volume.is_finite() || volume < 1e-6 {
            return None;
        }
        let widths = Vec3::new(
            volume / e[1].cross(e[2]).length(),
            volume / e[2].cross(e[0]).length(),
            volume / e[0].cross(e[1]).length(),
        );
        // A placeholder box (`CRYST1 1 1 1`) is not periodic.
        if widths.min_element() < crate::model::MIN_BOX_WIDTH {
            return None;
        }
        Some(Periodic {
            edges: e.map(Vec3A::from),
            to_fraction: Mat3A::from(Mat3::from_cols(e[0], e[1], e[2]).inverse()),
            widths,
        })
    }

    /// The box translation `t.x a + t.y b + t.z c`.
    #[inline]
    fn shift(&self, t: Vec3A) -> Vec3A {
        t.x * self.edges[0] + t.y * self.edges[1] + t.z * self.edges[2]
    }

    /// `p` moved into the box (fractional coordinates in [0, 1)).
    #[inline]
    fn wrap(&self, p: Vec3A) -> Vec3A {
        p - self.shift((self.to_fraction * p).floor())
    }

    /// Wrapped `points` with every periodic image that lies within `distance` Å of the box.
    fn with_images(&self, points: &[(u32, Vec3A)], distance: f32) -> Vec<(u32, Vec3)> {
        let margin = Vec3::splat(distance) / self.widths;
        let reach = margin.ceil().as_ivec3();
        let mut out = Vec::with_capacity(points.len() * 3 / 2);
        for &(i, p) in points {
            let f = self.to_fraction * p;
            // Image offsets along axis k whose slab stays within the margin of the box.
            let range = |k: usize| {
                let (m, r) = (margin[k], reach[k]);
                (-r..=r).filter(move |&t| {
                    let g = f[k] + t as f32;
                    t == 0 || (g >= -m && g <= 1.0 + m)
                })
            };
            for tz in range(2) {
                for ty in range(1) {
                    for tx in range(0) {
                        let t = Vec3A::new(tx as f32, ty as f32, tz as f32);
                        out.push((i, Vec3::from(p + self.shift(t))));
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over the 729 nearest images (enough for the points and boxes below).
    fn brute(positions: &[Vec3], cell: Option<&[Vec3; 3]>, sources: &[u32], d: f32) -> Vec<bool> {
        let shifts: Vec<Vec3> = match cell {
            Some(e) => {
                let mut v = Vec::new();
                for i in -4..=4 {
                    for j in -4..=4 {
                        for k in -4..=4 {
                            v.push(i as f32 * e[0] + j as f32 * e[1] + k as f32 * e[2]);
                        }
                    }
                }
                v
            }
            None => vec![Vec3::ZERO],
        };
        positions
            .iter()
            .map(|p| {
                sources.iter().any(|&s| {
                    shifts
                        .iter()
                        .any(|t| (positions[s as usize] + *t).distance_squared(*p) <= d * d)
                })
            })
            .collect()
    }

    fn points(n: usize, scale: f32) -> Vec<Vec3> {
        // A deterministic scatter (golden-ratio sequences), partly outside the box.
        (0..n)
            .map(|i| {
                let f = |a: f32| ((i as f32 * a).fract() * 1.4 - 0.2) * scale;
                Vec3::new(f(0.618_034), f(0.754_878), f(0.569_840))
            })
            .collect()
    }

    #[test]
    fn grid_matches_brute_force() {
        let boxes = [
            None,
            Some([Vec3::X * 20.0, Vec3::Y * 20.0, Vec3::Z * 20.0]),
            Some([
                Vec3::new(20.0, 0.0, 0.0),
                Vec3::new(8.0, 18.0, 0.0),
                Vec3::new(-6.0, 7.0, 16.0),
            ]),
            // Narrower than three cutoffs: images of the same cell are searched.
            Some([Vec3::X * 9.0, Vec3::new(3.0, 8.0, 0.0), Vec3::Z * 30.0]),
        ];
        let positions = points(600, 20.0);
        let all = vec![true; positions.len()];
        let few: Vec<bool> = (0..600).map(|i| i % 29 == 0).collect();
        let many: Vec<u32> = (0..600).filter(|i| i % 5 != 0).collect();
        let sparse: Vec<u32> = (0..600).step_by(37).collect();
        for cell in &boxes {
            for d in [0.0, 1.5, 4.0, 7.5] {
                // Few sources (targets binned), then few targets (sources binned).
                for (sources, targets) in [(&sparse, &all), (&many, &few)] {
                    let got = within(&positions, cell.as_ref(), sources, targets, d);
                    let want: Vec<bool> = brute(&positions, cell.as_ref(), sources, d)
                        .into_iter()
                        .zip(targets.iter())
                        .map(|(w, t)| w && *t)
                        .collect();
                    assert_eq!(got, want, "box {cell:?} d {d}");
                }
            }
        }
    }
}
