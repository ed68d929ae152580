//! A structural check of GROMACS XTC and TRR files, done once when one opens and before
//! chemfiles reads any frame. chemfiles follows the frames' byte counts without checking the
//! headers it lands on, and its XTC decoder corrupts the heap on data that is not a frame (a
//! chunk of the file duplicated or deleted). This walks the frame headers (XDR, big-endian) and
//! ends the readable range at the first inconsistent one, so chemfiles never decodes a damaged
//! frame, and checks the atom count before anything is allocated for it.
//!
//! XTC frame: magic 1995, natoms, step, time, box (9 f32), natoms again; then 3 f32 per atom
//! for 9 atoms or less, else precision, minint\[3\], maxint\[3\], smallidx, a byte count and
//! that many bytes padded to 4.
//!
//! TRR frame: magic 1993, the version string (`GMX_trn_file`), 13 sizes and counts (ir, e, box,
//! vir, pres, top, sym, x, v, f, natoms, step, nre), time and lambda (f32 or f64), then the
//! blocks the sizes announce.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::xdr_error::XdrError;

const XTC_MAGIC: i32 = 1995;
const TRR_MAGIC: i32 = 1993;
/// Bounds of the XTC `smallidx` (the xdrfile `FIRSTIDX` and the size of its `MAGICINTS`).
const XTC_FIRST_IDX: u32 = 9;
const XTC_LAST_IDX: u32 = 73;
/// Box lengths beyond this (nm) are not a box but damage.
const MAX_BOX_NM: f32 = 1.0e6;

/// What the frame headers say.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Walk {
    /// Atoms per frame (from the first frame's header).
    pub natoms: usize,
    /// Frames that can be read safely (all of them when `damage` is `None`).
    pub frames: usize,
    /// Why frame `frames` cannot be read, when the walk stopped before the end of the file.
    pub damage: Option<String>,
    /// Byte offset of each readable frame (`frames` of them).
    pub offsets: Vec<u64>,
}

/// Walks the frames of the XTC or TRR file `path` (`base` is `"XTC"` or `"TRR"`). `Ok(None)` for
/// other formats; `Err` (a one-line reason) when not even the first frame is sound.
pub(crate) fn walk(path: &Path, base: &str) -> Result<Option<Walk>, XdrError> {
    if !matches!(base, "XTC" | "TRR") {
        return Ok(None);
    }
    let file = File::open(path).map_err(XdrError::os)?;
    let size = file.metadata().map_err(XdrError::os)?.len();
    walk_source(file, size, base, &mut |_| {})
}

/// [`walk`] over any source of `size` bytes (a file, or a URL read through range requests),
/// calling `on_frame` with the byte offset reached after each sound frame. A network failure of
/// the source (see [`super::xdr_error::RemoteFailure`]) is returned as the error, not taken for
/// damage.
pub(crate) fn walk_source<F: Read + Seek>(
    file: F,
    size: u64,
    base: &str,
    on_frame: &mut dyn FnMut(u64),
) -> Result<Option<Walk>, XdrError> {
    let step: fn(&mut Reader<F>, u64) -> Result<FrameInfo, XdrError> = match base {
        "XTC" => xtc_frame,
        "TRR" => trr_frame,
        _ => return Ok(None),
    };
    let mut reader = Reader { file, size };
    let mut offset = 0u64;
    let mut offsets = Vec::new();
    let mut frames = 0usize;
    let mut natoms = None;
    let mut damage = None;
    while offset < size {
        let result = step(&mut reader, offset).and_then(|info| {
            match natoms {
                None => natoms = Some(info.natoms),
                Some(n) if n != info.natoms => {
                    return Err(XdrError::AtomCountChanged {
                        offset,
                        natoms: info.natoms,
                        first: n,
                    });
                }
                Some(_) => {}
            }
            if offset + info.bytes > size {
                return Err(XdrError::Truncated {
                    have: size - offset,
                    need: info.bytes,
                });
            }
            Ok(info)
        });
        match result {
            Ok(info) => {
                offsets.push(offset);
                offset += info.bytes;
                frames += 1;
                on_frame(offset);
            }
            Err(reason) if reason.remote().is_some() => return Err(reason),
            Err(reason) => {
                damage = Some(reason);
                break;
            }
        }
    }
    let Some(natoms) = natoms else {
        return Err(damage.unwrap_or(XdrError::NoFrame));
    };
    let damage = damage.map(|reason| {
        if reason.is_truncation() {
            reason.to_string()
        } else if frames > 0 {
            // The frame before a damaged header may hold part of the damage (a chunk inserted
            // or deleted inside its data): it is not read either.
            frames -= 1;
            XdrError::DamagedAfter(Box::new(reason)).to_string()
        } else {
            reason.to_string()
        }
    });
    offsets.truncate(frames);
    Ok(Some(Walk {
        natoms,
        frames,
        damage,
        offsets,
    }))
}

/// One frame's atom count and size in bytes.
struct FrameInfo {
    natoms: usize,
    bytes: u64,
}

/// Where a TRR frame keeps what we read (byte offsets from the start of the file).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrrBlocks {
    /// Bytes per real number: 4 (single precision) or 8 (double).
    pub real: u64,
    /// The frame's time (ps), a real.
    pub time_at: u64,
    /// The box (9 reals, nm, rows a, b, c), when the frame has one.
    pub box_at: Option<u64>,
    /// The positions (3 reals per atom, nm), when the frame has them.
    pub x_at: Option<u64>,
}

/// Reads the blocks of the TRR frame at `offset` of `file` (whose size is `size` bytes).
pub(crate) fn trr_blocks(
    file: &mut (impl Read + Seek),
    size: u64,
    offset: u64,
) -> Result<TrrBlocks, XdrError> {
    let mut reader = Reader { file, size };
    Ok(trr_header(&mut reader, offset)?.1)
}

struct Reader<F> {
    file: F,
    size: u64,
}

impl<F: Read + Seek> Reader<F> {
    /// Up to `n` bytes at `offset` (fewer at the end of the file).
    fn bytes(&mut self, offset: u64, n: usize) -> Result<Vec<u8>, XdrError> {
        let n = n.min(self.size.saturating_sub(offset) as usize);
        let mut buffer = vec![0u8; n];
        self.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| self.file.read_exact(&mut buffer))
            .map_err(XdrError::os)?;
        Ok(buffer)
    }
}

fn int(b: &[u8], at: usize) -> i32 {
    i32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn float(b: &[u8], at: usize) -> f32 {
    f32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn truncated_header(offset: u64) -> XdrError {
    XdrError::TruncatedHeader { offset }
}

fn xtc_frame(reader: &mut Reader<impl Read + Seek>, offset: u64) -> Result<FrameInfo, XdrError> {
    let b = reader.bytes(offset, 92)?;
    if b.len() < 56 {
        return Err(truncated_header(offset));
    }
    if int(&b, 0) != XTC_MAGIC {
        return Err(XdrError::NoHeader {
            format: "XTC",
            offset,
        });
    }
    let natoms = int(&b, 4);
    if natoms < 0 || int(&b, 52) != natoms {
        return Err(XdrError::AtomCounts { offset });
    }
    if !(0..9).all(|k| float(&b, 16 + 4 * k).abs() <= MAX_BOX_NM) {
        return Err(XdrError::AbsurdBox { offset });
    }
    let natoms = natoms as u64;
    if natoms <= 9 {
        return Ok(FrameInfo {
            natoms: natoms as usize,
            bytes: 56 + 12 * natoms,
        });
    }
    if b.len() < 92 {
        return Err(truncated_header(offset));
    }
    let precision = float(&b, 56);
    if !(precision.is_finite() && precision > 0.0) {
        return Err(XdrError::Precision { offset });
    }
    if !(0..3).all(|k| int(&b, 60 + 4 * k) <= int(&b, 72 + 4 * k)) {
        return Err(XdrError::CoordinateRange { offset });
    }
    let small = int(&b, 84) as u32;
    if !(XTC_FIRST_IDX..XTC_LAST_IDX).contains(&small) {
        return Err(XdrError::CompressionIndex { offset });
    }
    let count = int(&b, 88);
    // Each atom takes at least one bit, and at most about 3 × 32 bits plus run flags.
    if count < 0 || (count as u64) * 8 + 8 < natoms || count as u64 > natoms * 24 + 1024 {
        return Err(XdrError::DataSize {
            offset,
            count,
            natoms,
        });
    }
    let padded = (count as u64 + 3) & !3;
    Ok(FrameInfo {
        natoms: natoms as usize,
        bytes: 92 + padded,
    })
}

fn trr_frame(reader: &mut Reader<impl Read + Seek>, offset: u64) -> Result<FrameInfo, XdrError> {
    Ok(trr_header(reader, offset)?.0)
}

fn trr_header(
    reader: &mut Reader<impl Read + Seek>,
    offset: u64,
) -> Result<(FrameInfo, TrrBlocks), XdrError> {
    let head = reader.bytes(offset, 12)?;
    if head.len() < 12 {
        return Err(truncated_header(offset));
    }
    if int(&head, 0) != TRR_MAGIC {
        return Err(XdrError::NoHeader {
            format: "TRR",
            offset,
        });
    }
    let len = int(&head, 8);
    if !(0..=128).contains(&len) {
        return Err(XdrError::VersionString { offset });
    }
    let ints_at = 12 + ((len as usize + 3) & !3);
    let b = reader.bytes(offset, ints_at + 13 * 4)?;
    if b.len() < ints_at + 13 * 4 {
        return Err(truncated_header(offset));
    }
    let field = |k: usize| int(&b, ints_at + 4 * k);
    // ir, e, box, vir, pres, top, sym, x, v, f, natoms, step, nre
    let sizes: Vec<i32> = (0..10).map(field).collect();
    let natoms = field(10);
    if natoms < 0 || sizes.iter().any(|&s| s < 0) {
        return Err(XdrError::NegativeSize { offset });
    }
    let natoms = natoms as u64;
    let (box_size, x, v, f) = (
        sizes[2] as u64,
        sizes[7] as u64,
        sizes[8] as u64,
        sizes[9] as u64,
    );
    let real = if box_size > 0 {
        box_size / 9
    } else if natoms > 0 {
        [x, v, f].into_iter().find(|&s| s > 0).unwrap_or(0) / (natoms * 3)
    } else {
        0
    };
    if real != 4 && real != 8 {
        return Err(XdrError::RealSize { offset });
    }
    let vector = natoms * 3 * real;
    let matrix = 9 * real;
    let matrices_ok = [sizes[2], sizes[3], sizes[4]]
        .iter()
        .all(|&s| s == 0 || s as u64 == matrix);
    let vectors_ok = [x, v, f].iter().all(|&s| s == 0 || s == vector);
    if !(matrices_ok && vectors_ok) {
        return Err(XdrError::SizesDoNotFit { offset, natoms });
    }
    let header = (ints_at + 13 * 4) as u64 + 2 * real;
    let body: u64 = sizes.iter().map(|&s| s as u64).sum();
    // Blocks in order: ir, e, box, vir, pres, top, sym, x, v, f.
    let before = |k: usize| offset + header + sizes[..k].iter().map(|&s| s as u64).sum::<u64>();
    let blocks = TrrBlocks {
        real,
        time_at: offset + (ints_at + 13 * 4) as u64,
        box_at: (box_size > 0).then(|| before(2)),
        x_at: (x > 0).then(|| before(7)),
    };
    let info = FrameInfo {
        natoms: natoms as usize,
        bytes: header + body,
    };
    Ok((info, blocks))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TRR with `frames` frames of `natoms` atoms (f32, box and positions).
    fn trr(natoms: usize, frames: usize) -> Vec<u8> {
        let mut out = Vec::new();
        let put = |out: &mut Vec<u8>, v: i32| out.extend_from_slice(&v.to_be_bytes());
        for step in 0..frames {
            put(&mut out, TRR_MAGIC);
            put(&mut out, 13);
            put(&mut out, 12);
            out.extend_from_slice(b"GMX_trn_file");
            let x = (natoms * 12) as i32;
            for s in [0, 0, 36, 0, 0, 0, 0, x, 0, 0, natoms as i32, step as i32, 0] {
                put(&mut out, s);
            }
            out.extend_from_slice(&[0u8; 8]);
            out.extend(std::iter::repeat_n(0u8, 36 + natoms * 12));
        }
        out
    }

    #[test]
    fn trr_walk_finds_a_cut_frame() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.trr");
        let whole = trr(5, 3);
        std::fs::write(&path, &whole).unwrap();
        let w = walk(&path, "TRR").unwrap().unwrap();
        assert_eq!((w.natoms, w.frames, w.damage.is_none()), (5, 3, true));
        std::fs::write(&path, &whole[..whole.len() - 10]).unwrap();
        let w = walk(&path, "TRR").unwrap().unwrap();
        assert_eq!(w.frames, 2);
        assert!(w.damage.unwrap().contains("truncated"));
    }
}
