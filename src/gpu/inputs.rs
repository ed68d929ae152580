//! Host-side checks of a frame's atoms before upload: matching lengths, finite coordinates,
//! positive radii, the bounding box (in parallel: it is the only pass over the atoms the host
//! makes per frame), fingerprints that tell [`super::GpuEngine`]'s blocking path what
//! changed since its previous call, and the copy of large per-atom arrays into wgpu's staging
//! memory on every core ([`write_in_parallel`]).

use glam::Vec3;
use rayon::prelude::*;

use crate::surface::{AtomSet, SurfaceError};

const CHUNK: usize = 1 << 16;

/// Writes `bytes` to the start of `buffer` as `Queue::write_buffer` does, but copies them into
/// wgpu's staging memory in 1 MiB pieces on every core. One thread copying the 274 MB of
/// positions of 22.8 M atoms took about half of a frame on an H100.
pub fn write_in_parallel(queue: &wgpu::Queue, buffer: &wgpu::Buffer, bytes: &[u8]) {
    write_in_pieces(queue, buffer, bytes, 1 << 20);
}

/// [`write_in_parallel`] with pieces of `piece` bytes (a test writes small pieces); arrays of
/// at most four pieces go through `Queue::write_buffer` in one copy.
pub fn write_in_pieces(queue: &wgpu::Queue, buffer: &wgpu::Buffer, bytes: &[u8], piece: usize) {
    let piece = piece.max(1);
    let Some(size) = wgpu::BufferSize::new(bytes.len() as u64) else {
        return;
    };
    if bytes.len() <= 4 * piece {
        return queue.write_buffer(buffer, 0, bytes);
    }
    // None only when the write is invalid: `write_buffer` then reports it to the error scope.
    let Some(mut view) = queue.write_buffer_with(buffer, 0, size) else {
        return queue.write_buffer(buffer, 0, bytes);
    };
    let mut whole = view.slice(..);
    let base = SendPtr(whole.as_raw_element_ptr().as_ptr());
    bytes.par_chunks(piece).enumerate().for_each(|(i, src)| {
        let base = &base;
        // SAFETY: `whole` is a write mapping of `bytes.len()` bytes held mutably for the whole
        // loop; piece `i` covers bytes `i * piece ..` up to `bytes.len()`, so the pieces lie
        // inside the mapping, never overlap each other, and never overlap `bytes` (host memory
        // the caller owns).
        unsafe { std::ptr::copy_nonoverlapping(src.as_ptr(), base.0.add(i * piece), src.len()) };
    });
}

/// The staging memory's start, shared by the threads that copy disjoint pieces into it.
struct SendPtr(*mut u8);
// SAFETY: each thread writes only its own piece (see `write_in_parallel`).
unsafe impl Sync for SendPtr {}

/// Fails when the radii or colours do not match the positions, or there are no atoms.
pub fn check_lengths(atoms: &AtomSet<'_>) -> Result<(), SurfaceError> {
    let n = atoms.positions.len();
    if n == 0 {
        return Err(SurfaceError::EmptySystem);
    }
    let bad = |what: &'static str, len: usize| SurfaceError::InvalidParameter {
        name: what,
        value: format!("{len} entries for {n} atoms"),
    };
    if atoms.radii.len() != n {
        return Err(bad("radii", atoms.radii.len()));
    }
    if let Some(c) = atoms.colours
        && c.len() != n
    {
        return Err(bad("colours", c.len()));
    }
    Ok(())
}

/// Bounding box of the positions (Å) and the largest radius (Å): checked and recomputed when
/// `radii_changed`, else `old_max_radius`.
pub fn bounds(
    atoms: &AtomSet<'_>,
    radii_changed: bool,
    old_max_radius: Option<f32>,
) -> Result<(Vec3, Vec3, f32), SurfaceError> {
    let (lo, hi) = atoms
        .positions
        .par_chunks(CHUNK)
        .map(|c| {
            c.iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                })
        })
        .reduce(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    if !(lo.is_finite() && hi.is_finite()) {
        let atom = atoms
            .positions
            .iter()
            .position(|p| !p.is_finite())
            .unwrap_or(0);
        return Err(SurfaceError::NonFiniteCoordinate { atom });
    }
    let max_r = match old_max_radius {
        Some(r) if !radii_changed => r,
        _ => {
            let ok = |r: f32| r.is_finite() && r > 0.0;
            let max = atoms
                .radii
                .par_chunks(CHUNK)
                .map(|c| {
                    c.iter()
                        .fold(0.0f32, |m, &r| if ok(r) { m.max(r) } else { f32::NAN })
                })
                .reduce(
                    || 0.0,
                    |a, b| {
                        if a.is_nan() || b.is_nan() {
                            f32::NAN
                        } else {
                            a.max(b)
                        }
                    },
                );
            if !ok(max) {
                let atom = atoms.radii.iter().position(|&r| !ok(r)).unwrap_or(0);
                let radius = atoms.radii.get(atom).copied().unwrap_or(f32::NAN);
                return Err(SurfaceError::InvalidRadius { atom, radius });
            }
            max
        }
    };
    Ok((lo, hi, max_r))
}

/// Hash of a byte slice (FNV-style over 8-byte words, chunks in parallel, combined in order).
pub fn fingerprint(bytes: &[u8]) -> u64 {
    let mix = |h: u64, w: u64| (h ^ w).wrapping_mul(0x100_0000_01b3).rotate_left(29);
    bytes
        .par_chunks(CHUNK * 8)
        .map(|c| {
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            let words = c.chunks_exact(8);
            let rest = words.remainder();
            for w in words {
                h = mix(
                    h,
                    u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]),
                );
            }
            for &b in rest {
                h = mix(h, b as u64);
            }
            h
        })
        .collect::<Vec<u64>>()
        .into_iter()
        .fold(bytes.len() as u64, mix)
}

/// Fingerprints of the last atoms seen.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Fingerprints {
    positions: Option<u64>,
    radii: Option<u64>,
    colours: Option<u64>,
}

impl Fingerprints {
    /// What changed since the previous call; remembers the new fingerprints.
    pub fn update(&mut self, atoms: &AtomSet<'_>) -> super::engine::Changes {
        let p = Some(fingerprint(bytemuck::cast_slice(atoms.positions)));
        let r = Some(fingerprint(bytemuck::cast_slice(atoms.radii)));
        let c = atoms.colours.map(|c| fingerprint(bytemuck::cast_slice(c)));
        let changes = super::engine::Changes {
            positions: p != self.positions,
            radii: r != self.radii,
            colours: c != self.colours,
        };
        *self = Fingerprints {
            positions: p,
            radii: r,
            colours: c,
        };
        changes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_and_errors() {
        let pos = [Vec3::new(1.0, -2.0, 3.0), Vec3::new(-1.0, 5.0, 0.0)];
        let radii = [1.5, 1.0];
        let atoms = AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        };
        let (lo, hi, r) = bounds(&atoms, true, None).unwrap();
        assert_eq!(lo, Vec3::new(-1.0, -2.0, 0.0));
        assert_eq!(hi, Vec3::new(1.0, 5.0, 3.0));
        assert_eq!(r, 1.5);
        let bad_r = [1.0, -1.0];
        let atoms = AtomSet {
            positions: &pos,
            radii: &bad_r,
            colours: None,
        };
        assert!(matches!(
            bounds(&atoms, true, None),
            Err(SurfaceError::InvalidRadius { atom: 1, .. })
        ));
        let nan = [Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0)];
        let atoms = AtomSet {
            positions: &nan,
            radii: &radii,
            colours: None,
        };
        assert!(matches!(
            bounds(&atoms, true, None),
            Err(SurfaceError::NonFiniteCoordinate { atom: 1 })
        ));
    }

    #[test]
    fn fingerprints_see_changes() {
        let mut pos = vec![Vec3::ONE; 100_000];
        let radii = vec![1.0; 100_000];
        let mut f = Fingerprints::default();
        let first = f.update(&AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        });
        assert!(first.positions && first.radii);
        let same = f.update(&AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        });
        assert_eq!(same, Default::default());
        pos[77_777].y += 1e-3;
        let moved = f.update(&AtomSet {
            positions: &pos,
            radii: &radii,
            colours: None,
        });
        assert!(moved.positions && !moved.radii && !moved.colours);
    }
}
