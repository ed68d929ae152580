//! Smoothing over frames: each atom's position is averaged over a window of ±k frames (VMD's
//! trajectory smoothing window), after the other transforms. At the ends of the trajectory the
//! window holds the frames that exist. The result depends only on the frame's index, so
//! scrubbing to a frame gives what playing to it gives.
//!
//! Frames are averaged as displacements from the middle frame, each taken as its minimum image
//! in that frame's box, so an atom that crossed a box face between frames is not averaged
//! across the box.

use std::borrow::Borrow;
use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;

use crate::model::Frame;
use crate::model::pbc::PbcCell;

/// Atoms per parallel chunk when averaging.
const CHUNK: usize = 8192;

/// The frames averaged for frame `index` of `len` with half-width `k`: `index - k ..= index + k`
/// clipped to `0..len`.
pub fn window(index: usize, len: usize, k: usize) -> Range<usize> {
    index.saturating_sub(k)..(index + k + 1).min(len)
}

/// Frame `index` smoothed over ±`k` frames of a trajectory of `len` frames; `read(i)` gives
/// frame `i` (already transformed). The result keeps the middle frame's index, time and box.
/// With `k == 0` it is the frame itself.
pub fn smooth_frame<F, E>(
    index: usize,
    len: usize,
    k: usize,
    mut read: impl FnMut(usize) -> Result<F, E>,
) -> Result<Frame, E>
where
    F: Borrow<Frame>,
{
    let middle = read(index)?;
    let middle: &Frame = middle.borrow();
    let range = window(index, len.max(index + 1), k);
    if range.len() <= 1 {
        return Ok(middle.clone());
    }
    let n = middle.positions.len();
    let mut sum = vec![Vec3::ZERO; n];
    let mut count = 1.0f32;
    for j in range {
        if j == index {
            continue;
        }
        let other = read(j)?;
        let other: &Frame = other.borrow();
        if other.positions.len() != n {
            continue;
        }
        let cell = PbcCell::of(other);
        // Displacements shorter than half the narrowest box width are their own minimum image.
        let near = cell.map_or(f32::INFINITY, |c| (0.5 * c.widths().min_element()).powi(2));
        sum.par_chunks_mut(CHUNK)
            .zip(middle.positions.par_chunks(CHUNK))
            .zip(other.positions.par_chunks(CHUNK))
            .for_each(|((s, m), o)| {
                for ((s, &m), &o) in s.iter_mut().zip(m).zip(o) {
                    let d = o - m;
                    *s += match &cell {
                        Some(c) if d.length_squared() >= near => c.min_image(d),
                        _ => d,
                    };
                }
            });
        count += 1.0;
    }
    let mut out = middle.clone();
    out.positions
        .par_chunks_mut(CHUNK)
        .zip(sum.par_chunks(CHUNK))
        .for_each(|(p, s)| {
            for (p, s) in p.iter_mut().zip(s) {
                *p += *s / count;
            }
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_clip_at_the_ends() {
        assert_eq!(window(0, 10, 2), 0..3);
        assert_eq!(window(5, 10, 2), 3..8);
        assert_eq!(window(9, 10, 2), 7..10);
        assert_eq!(window(3, 10, 0), 3..4);
    }

    #[test]
    fn an_atom_crossing_the_box_is_averaged_as_unwrapped() {
        let cell = Some([Vec3::X * 10.0, Vec3::Y * 10.0, Vec3::Z * 10.0]);
        let xs = [9.0f32, 9.8, 0.6];
        let frames: Vec<Frame> = xs
            .iter()
            .enumerate()
            .map(|(i, &x)| Frame {
                index: i,
                positions: vec![Vec3::new(x, 1.0, 1.0)],
                cell,
                ..Frame::default()
            })
            .collect();
        let f = smooth_frame(1, 3, 1, |i| Ok::<_, ()>(&frames[i])).expect("smooth");
        assert!((f.positions[0].x - (9.0 + 9.8 + 10.6) / 3.0).abs() < 1e-4);
    }
}
