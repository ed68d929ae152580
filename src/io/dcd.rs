//! A structural check of DCD files, done once when one opens. chemfiles counts DCD frames from
//! the file size and silently drops a partial last frame; this reads the header to find the frame
//! size, so a truncated file is reported as damaged at the frame it cuts, not quietly shortened.
//!
//! Layout (CHARMM/NAMD, Fortran records with 4-byte length markers before and after each):
//! header record (84 bytes: `CORD` + 20 control integers), title record, atom-count record, a
//! free-atom index record when atoms are fixed; then per frame an optional unit-cell record
//! (6 doubles), x, y and z records (one f32 per atom), and an optional fourth-dimension record.
//! Sizes that cannot fit the file are a [`DcdError`](super::reader_errors::DcdError).

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

#[cfg(feature = "chemfiles")]
use super::reader_errors::DcdError;

/// What the file size says about the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct DcdTail {
    /// Complete frames in the file.
    pub complete: usize,
    /// Bytes after the last complete frame (a partial frame when not 0).
    pub trailing: u64,
    /// Bytes of one (non-first) frame.
    pub frame_bytes: u64,
}

/// Reads the header of the DCD file at `path` and measures its frames. `None` when the header is
/// not one this check understands (64-bit record markers, damaged header): the caller then
/// trusts chemfiles.
pub(crate) fn measure(path: &Path) -> Option<DcdTail> {
    let mut file = std::fs::File::open(path).ok()?;
    let total = file.metadata().ok()?.len();
    let mut head = [0u8; 92];
    file.read_exact(&mut head).ok()?;
    let little = match (
        head[0..4].try_into().ok().map(u32::from_le_bytes),
        &head[4..8],
    ) {
        (Some(84), b"CORD") => true,
        (_, b"CORD") if u32::from_be_bytes(head[0..4].try_into().ok()?) == 84 => false,
        _ => return None,
    };
    let int = |b: &[u8]| -> Option<i64> {
        let bytes: [u8; 4] = b.try_into().ok()?;
        Some(i64::from(if little {
            i32::from_le_bytes(bytes)
        } else {
            i32::from_be_bytes(bytes)
        }))
    };
    let control = |k: usize| int(&head[8 + 4 * k..12 + 4 * k]);
    let charmm = control(19)? != 0;
    let fixed = control(8)?;
    let has_cell = charmm && control(10)? != 0;
    let four_d = charmm && control(11)? != 0;
    if int(&head[88..92])? != 84 {
        return None;
    }
    // Title record.
    let mut marker = [0u8; 4];
    file.read_exact(&mut marker).ok()?;
    let title = int(&marker)?;
    if title < 0 {
        return None;
    }
    file.seek(SeekFrom::Current(title + 4)).ok()?;
    // Atom-count record.
    let mut natom_record = [0u8; 12];
    file.read_exact(&mut natom_record).ok()?;
    if int(&natom_record[0..4])? != 4 {
        return None;
    }
    let atoms = int(&natom_record[4..8])?;
    if atoms <= 0 || fixed < 0 || fixed > atoms {
        return None;
    }
    let mut header = 92 + 4 + title as u64 + 4 + 12;
    if fixed > 0 {
        header += 8 + 4 * (atoms - fixed) as u64;
    }
    let record = |n: i64| 8 + 4 * n as u64;
    let extras = if has_cell { 56 } else { 0 };
    let first_bytes = extras + record(atoms) * if four_d { 4 } else { 3 };
    let frame_bytes = extras + record(atoms - fixed) * if four_d { 4 } else { 3 };
    let body = total.checked_sub(header)?;
    if body < first_bytes {
        return Some(DcdTail {
            complete: 0,
            trailing: body,
            frame_bytes,
        });
    }
    let rest = body - first_bytes;
    Some(DcdTail {
        complete: 1 + (rest / frame_bytes) as usize,
        trailing: rest % frame_bytes,
        frame_bytes,
    })
}

/// Checks that the sizes in the header of the DCD file at `path` fit the file, before chemfiles
/// allocates for them (a 4-byte edit of the atom count made it grow to 8 GB). Headers this check
/// does not understand pass (chemfiles then decides); sizes that cannot fit give the reason.
#[cfg(feature = "chemfiles")]
pub(crate) fn check_header(path: &Path) -> Result<(), DcdError> {
    let Ok(mut file) = std::fs::File::open(path) else {
        return Ok(());
    };
    let total = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut head = [0u8; 92];
    if file.read_exact(&mut head).is_err() {
        return Ok(());
    }
    let little = match &head[4..8] {
        b"CORD" if u32::from_le_bytes([head[0], head[1], head[2], head[3]]) == 84 => true,
        b"CORD" if u32::from_be_bytes([head[0], head[1], head[2], head[3]]) == 84 => false,
        _ => return Ok(()),
    };
    let int = |b: &[u8]| -> i64 {
        let bytes = [b[0], b[1], b[2], b[3]];
        i64::from(if little {
            i32::from_le_bytes(bytes)
        } else {
            i32::from_be_bytes(bytes)
        })
    };
    let fixed = int(&head[8 + 4 * 8..]);
    let mut marker = [0u8; 4];
    if file.read_exact(&mut marker).is_err() {
        return Err(DcdError::HeaderTruncated);
    }
    let title = int(&marker);
    if title < 0 || title as u64 > total {
        return Err(DcdError::HeaderTitleSize { title, total });
    }
    if file.seek(SeekFrom::Current(title + 4)).is_err() {
        return Err(DcdError::HeaderTruncated);
    }
    let mut natom_record = [0u8; 12];
    if file.read_exact(&mut natom_record).is_err() {
        return Err(DcdError::HeaderTruncated);
    }
    if int(&natom_record[0..4]) != 4 {
        return Ok(());
    }
    let atoms = int(&natom_record[4..8]);
    // One frame needs at least 3 × 4 bytes per free atom; the first frame holds all atoms.
    if atoms <= 0 || (atoms as u64) * 12 > total {
        return Err(DcdError::AtomsDontFit { atoms, total });
    }
    if fixed < 0 || fixed > atoms {
        return Err(DcdError::BadFixed { fixed, atoms });
    }
    if fixed > 0 {
        let free = (atoms - fixed) as usize;
        let mut record = vec![0u8; 4 * free + 4];
        if file.read_exact(&mut record).is_err() {
            return Err(DcdError::HeaderTruncated);
        }
        let bad = (0..free)
            .map(|k| int(&record[4 + 4 * k..]))
            .any(|index| index < 1 || index > atoms);
        if int(&record[0..4]) != 4 * free as i64 || bad {
            return Err(DcdError::FreeAtomList);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes a minimal little-endian CHARMM DCD with `frames` frames of `atoms` atoms and a
    /// unit cell, plus `extra` bytes of a partial frame.
    fn write_dcd(path: &Path, atoms: i32, frames: i32, extra: usize) {
        let mut out = Vec::new();
        let rec = |out: &mut Vec<u8>, data: &[u8]| {
            out.extend_from_slice(&(data.len() as i32).to_le_bytes());
            out.extend_from_slice(data);
            out.extend_from_slice(&(data.len() as i32).to_le_bytes());
        };
        let mut header = b"CORD".to_vec();
        let mut control = [0i32; 20];
        control[0] = frames;
        control[10] = 1;
        control[19] = 24;
        control
            .iter()
            .for_each(|c| header.extend_from_slice(&c.to_le_bytes()));
        rec(&mut out, &header);
        let mut title = 1i32.to_le_bytes().to_vec();
        title.extend_from_slice(&[b' '; 80]);
        rec(&mut out, &title);
        rec(&mut out, &atoms.to_le_bytes());
        for _ in 0..frames {
            rec(&mut out, &[0u8; 48]);
            for _ in 0..3 {
                rec(&mut out, &vec![0u8; 4 * atoms as usize]);
            }
        }
        out.extend(std::iter::repeat_n(7u8, extra));
        std::fs::write(path, out).expect("write dcd");
    }

    #[test]
    fn counts_complete_frames_and_trailing_bytes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("t.dcd");
        write_dcd(&path, 10, 3, 0);
        let frame_bytes = 56 + 3 * (8 + 40);
        assert_eq!(
            measure(&path),
            Some(DcdTail {
                complete: 3,
                trailing: 0,
                frame_bytes
            })
        );
        write_dcd(&path, 10, 3, 30);
        assert_eq!(
            measure(&path),
            Some(DcdTail {
                complete: 3,
                trailing: 30,
                frame_bytes
            })
        );
        std::fs::write(
            &path,
            b"not a dcd file at all, just some text that is long enough to fill the header....",
        )
        .expect("write");
        assert_eq!(measure(&path), None);
    }

    #[cfg(feature = "chemfiles")]
    #[test]
    fn the_header_check_names_sizes_that_cannot_fit() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("t.dcd");
        write_dcd(&path, 10, 3, 0);
        assert_eq!(check_header(&path), Ok(()));
        write_dcd(&path, 1_000_000, 0, 0);
        let total = std::fs::metadata(&path).expect("size").len();
        assert_eq!(
            check_header(&path),
            Err(DcdError::AtomsDontFit {
                atoms: 1_000_000,
                total
            })
        );
        let bytes = std::fs::read(&path).expect("read");
        std::fs::write(&path, &bytes[..94]).expect("write");
        assert_eq!(check_header(&path), Err(DcdError::HeaderTruncated));
    }
}
