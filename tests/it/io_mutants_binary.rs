//! Structured mutants of the binary formats (XTC, TRR, DCD, Amber NetCDF, TNG) for
//! `io_mutants_structured`: where each frame starts, and the seeded edits (header fields,
//! counts and record lengths made hostile, DCD record markers changed in pairs so they stay
//! consistent, NetCDF dimension lengths and record counts, TNG block ids and sizes and block
//! contents with their MD5 recomputed, NaN coordinates, cuts inside a frame or at a frame
//! boundary), each with what the run must give.

use std::ops::Range;

use crate::io_mutants::Rng;
use crate::io_mutants_structured::{Expect, Frame, pick};

/// The binary formats under test.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Binary {
    Xtc,
    Trr,
    Dcd,
    NetCdf,
    Tng,
}

/// Hostile 32-bit values: 0, -1 (2^32-1), 2^31-1, 2^31, near 2^31, the bits of a NaN float.
const HOSTILE32: [u32; 6] = [
    0,
    u32::MAX,
    0x7fff_ffff,
    0x8000_0000,
    0x7fff_fff0,
    0x7fc0_0000,
];
/// Hostile 64-bit values.
const HOSTILE64: [i64; 8] = [
    0,
    -1,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    1 << 62,
    i64::MIN,
    i64::MAX,
];

/// One 4-byte field of a frame or header: its offset and what it holds.
type Field = (usize, &'static str);

fn be32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes(b[at..at + 4].try_into().unwrap())
}

fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

pub(crate) fn le64(b: &[u8], at: usize) -> i64 {
    i64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// A hostile value for a 32-bit field now holding `now`: an edge value, or one off or double.
fn hostile32(rng: &mut Rng, now: u32) -> u32 {
    match rng.below(4) {
        0 => now.wrapping_add(1),
        1 => now.wrapping_sub(1),
        2 => now.wrapping_mul(2),
        _ => pick(rng, &HOSTILE32),
    }
}

/// Makes the 32-bit field at `at` (big- or little-endian) hostile; says what it did.
fn set32(out: &mut [u8], at: usize, what: &str, big: bool, rng: &mut Rng) -> String {
    let now = if big { be32(out, at) } else { le32(out, at) };
    let v = hostile32(rng, now);
    let bytes = if big {
        v.to_be_bytes()
    } else {
        v.to_le_bytes()
    };
    out[at..at + 4].copy_from_slice(&bytes);
    format!("{what} at byte {at}: {now:#x} -> {v:#x}")
}

/// The byte spans of an unmutated file's frames (for TNG: frame sets, of which the test file
/// has two; the second holds its last frame).
pub(crate) fn binary_frames(format: Binary, bytes: &[u8], frames: usize) -> Vec<Frame> {
    let starts: Vec<usize> = match format {
        Binary::Xtc => (0..bytes.len() - 8)
            .step_by(4)
            .filter(|&i| be32(bytes, i) == 1995 && be32(bytes, i + 4) == be32(bytes, 4))
            .collect(),
        Binary::Tng => tng_blocks(bytes)
            .iter()
            .filter(|b| b.id == 2)
            .map(|b| b.offset)
            .collect(),
        _ => {
            let header = match format {
                Binary::Dcd => dcd_records(bytes)[3].start - 4,
                Binary::NetCdf => netcdf_header(bytes).data_start,
                _ => 0,
            };
            let size = (bytes.len() - header) / frames;
            (0..frames).map(|k| header + k * size).collect()
        }
    };
    let ends: Vec<usize> = starts
        .iter()
        .skip(1)
        .copied()
        .chain([bytes.len()])
        .collect();
    starts
        .iter()
        .zip(ends)
        .enumerate()
        .map(|(k, (&start, end))| Frame {
            // A TNG frame set holds many frames; the test file's later sets hold one each.
            index: if format == Binary::Tng && k > 0 {
                frames - (starts.len() - k)
            } else {
                k
            },
            start,
            cut: start + 1..end,
        })
        .collect()
}

/// The Fortran records of a DCD (little-endian): byte ranges of their contents.
fn dcd_records(bytes: &[u8]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut at = 0;
    while at + 4 <= bytes.len() {
        let len = le32(bytes, at) as usize;
        out.push(at + 4..at + 4 + len);
        at += len + 8;
    }
    out
}

/// What the test needs of a classic NetCDF header: its count and size fields, and where the
/// records start.
struct NetCdfHeader {
    fields: Vec<Field>,
    data_start: usize,
}

/// Walks a classic (CDF-1 or CDF-2) header: numrecs, dimension lengths, attribute value counts,
/// variable dimension counts, sizes and offsets.
fn netcdf_header(b: &[u8]) -> NetCdfHeader {
    let offset64 = b[3] == 2;
    let mut fields = vec![(4, "numrecs")];
    let mut record_dim = u32::MAX;
    let mut at = 8;
    let name = |at: &mut usize| *at += 4 + (be32(b, *at) as usize).div_ceil(4) * 4;
    // Dimensions.
    at += 4;
    let dims = be32(b, at);
    at += 4;
    for d in 0..dims {
        name(&mut at);
        if be32(b, at) == 0 {
            record_dim = d;
        }
        fields.push((at, "dimension length"));
        at += 4;
    }
    let attributes = |at: &mut usize, fields: &mut Vec<Field>| {
        *at += 4;
        let n = be32(b, *at);
        *at += 4;
        for _ in 0..n {
            name(at);
            let kind = be32(b, *at);
            fields.push((*at + 4, "attribute length"));
            let count = be32(b, *at + 4) as usize;
            let size = [0, 1, 1, 2, 4, 4, 8][kind.min(6) as usize];
            *at += 8 + (count * size).div_ceil(4) * 4;
        }
    };
    attributes(&mut at, &mut fields);
    at += 4;
    let vars = be32(b, at);
    at += 4;
    let mut data_start = usize::MAX;
    for _ in 0..vars {
        name(&mut at);
        fields.push((at, "variable rank"));
        let rank = be32(b, at) as usize;
        let is_record = rank > 0 && be32(b, at + 4) == record_dim;
        for d in 0..rank {
            fields.push((at + 4 + 4 * d, "variable dimension id"));
        }
        at += 4 + 4 * rank;
        attributes(&mut at, &mut fields);
        fields.push((at, "variable type"));
        fields.push((at + 4, "variable size"));
        let begin = if offset64 {
            fields.push((at + 12, "variable offset (low word)"));
            u64::from_be_bytes(b[at + 8..at + 16].try_into().unwrap()) as usize
        } else {
            fields.push((at + 8, "variable offset"));
            be32(b, at + 8) as usize
        };
        if is_record {
            data_start = data_start.min(begin);
        }
        at += if offset64 { 16 } else { 12 };
    }
    NetCdfHeader { fields, data_start }
}

/// One block of a TNG file (little-endian, as the test file).
struct TngBlock {
    offset: usize,
    header: usize,
    contents: usize,
    id: i64,
}

fn tng_blocks(b: &[u8]) -> Vec<TngBlock> {
    let mut out = Vec::new();
    let mut at = 0;
    while at + 40 <= b.len() {
        let (header, contents) = (le64(b, at) as usize, le64(b, at + 8) as usize);
        out.push(TngBlock {
            offset: at,
            header,
            contents,
            id: le64(b, at + 16),
        });
        at += header + contents;
    }
    out
}

/// Recomputes the MD5 of a TNG block's contents (where the writer recorded one).
fn tng_rehash(b: &mut [u8], block: &TngBlock) {
    let at = block.offset + 24;
    if b[at..at + 16] != [0; 16] {
        let contents = block.offset + block.header..block.offset + block.header + block.contents;
        let digest = md5::compute(&b[contents]).0;
        b[at..at + 16].copy_from_slice(&digest);
    }
}

/// Where the contents of the TNG blocks with id `id` start, in file order.
pub(crate) fn tng_contents_of(bytes: &[u8], id: i64) -> Vec<usize> {
    tng_blocks(bytes)
        .iter()
        .filter(|b| b.id == id)
        .map(|b| b.offset + b.header)
        .collect()
}

/// A copy of the TNG file `bytes` with the 8-byte value at byte `at` (inside a block's
/// contents) set to `value` and that block's MD5 recomputed: a hostile edit the checksum
/// cannot see.
pub(crate) fn tng_patched(bytes: &[u8], at: usize, value: i64) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out[at..at + 8].copy_from_slice(&value.to_le_bytes());
    let blocks = tng_blocks(bytes);
    let block = blocks
        .iter()
        .find(|b| (b.offset + b.header..b.offset + b.header + b.contents).contains(&at))
        .expect("a byte inside a block's contents");
    tng_rehash(&mut out, block);
    out
}

/// The byte of the first molecule type's molecule count in a TNG file (its MOLECULES block,
/// id 1: the number of types, then the type's id, name, quaternary structure and count).
pub(crate) fn tng_molecule_count_at(bytes: &[u8]) -> usize {
    let c = tng_contents_of(bytes, 1)[0];
    let name = bytes[c + 16..]
        .iter()
        .position(|&b| b == 0)
        .expect("a name");
    c + 16 + name + 1 + 8
}

/// The byte of the atom count of the `k`-th POSITIONS block (id 0x10000001) of a TNG file
/// whose positions are compressed, sparse and per frame and atom (after the data type,
/// dependency, sparse flag, values per atom, codec, multiplier, first frame, stride and first
/// atom).
pub(crate) fn tng_positions_count_at(bytes: &[u8], k: usize) -> usize {
    tng_contents_of(bytes, 0x1000_0001)[k] + 51
}

/// One seeded structured mutant of the binary file `bytes` (its frames from
/// [`binary_frames`]), what the run must give, and a label.
pub(crate) fn mutate_binary(
    format: Binary,
    bytes: &[u8],
    frames: &[Frame],
    rng: &mut Rng,
) -> (Vec<u8>, Expect, String) {
    let mut out = bytes.to_vec();
    let k = rng.below(frames.len());
    let f = &frames[k];
    let total = frames[frames.len() - 1].index + 1;
    let choice = rng.below(10);
    if choice >= 8 {
        // Cuts: inside frame k (damage), or at a frame boundary (every whole frame kept; where
        // the header promises more frames, TNG's index and NetCDF's record count, that is
        // damage too).
        if choice == 8 {
            let at = f.cut.start + rng.below(f.cut.len());
            out.truncate(at);
            return (
                out,
                Expect::Frames {
                    upto: f.index,
                    exit: 2,
                },
                format!("cut at byte {at}, inside frame {}", f.index),
            );
        }
        let j = 1 + rng.below(frames.len());
        let (end, upto) = frames
            .get(j)
            .map_or((bytes.len(), total), |f| (f.start, f.index));
        out.truncate(end);
        let promised = matches!(format, Binary::Tng | Binary::NetCdf);
        let exit = if promised && upto != total { 2 } else { 0 };
        return (
            out,
            Expect::Frames { upto, exit },
            format!("cut at byte {end}, a frame boundary"),
        );
    }
    let label = match format {
        Binary::Xtc => {
            // magic, natoms, step, time, box (9), natoms again, precision, min/max ints (6),
            // the small-index, the compressed byte count.
            let names = [
                "magic",
                "natoms",
                "step",
                "time",
                "box",
                "natoms (second)",
                "precision",
                "bounds",
                "smallidx",
                "byte count",
            ];
            let offsets = [
                0,
                4,
                8,
                12,
                16 + 4 * rng.below(9),
                52,
                56,
                60 + 4 * rng.below(6),
                84,
                88,
            ];
            let i = rng.below(names.len());
            if i == 1 && rng.below(2) == 0 {
                // Both atom counts changed alike.
                let v = hostile32(rng, be32(&out, f.start + 4));
                out[f.start + 4..f.start + 8].copy_from_slice(&v.to_be_bytes());
                out[f.start + 52..f.start + 56].copy_from_slice(&v.to_be_bytes());
                format!("both natoms of frame {k} := {v:#x}")
            } else {
                set32(&mut out, f.start + offsets[i], names[i], true, rng)
            }
        }
        Binary::Trr => {
            // magic, version string lengths, then ir, e, box, vir, pres, top, sym, x, v, f
            // sizes, natoms, step, nre, time, lambda.
            let offsets: Vec<usize> = [0, 4, 8].into_iter().chain((24..84).step_by(4)).collect();
            let at = f.start + pick(rng, &offsets);
            if rng.below(4) == 0 {
                // A NaN coordinate (single precision; the positions end the frame).
                let end = frames.get(k + 1).map_or(bytes.len(), |f| f.start);
                let at = end - 4 * (1 + rng.below(30));
                out[at..at + 4].copy_from_slice(&f32::NAN.to_be_bytes());
                format!("NaN coordinate at byte {at}")
            } else {
                set32(&mut out, at, "header field", true, rng)
            }
        }
        Binary::Dcd => {
            let records = dcd_records(bytes);
            match rng.below(5) {
                0 => {
                    // A field of the first header record (NSET, ISTART, NSAVC, fixed atoms,
                    // time step, cell flag, version, ...).
                    let at = records[0].start + 4 + 4 * rng.below(20);
                    set32(&mut out, at, "header field", false, rng)
                }
                1 => set32(&mut out, records[1].start, "title count", false, rng),
                2 => set32(&mut out, records[2].start, "atom count", false, rng),
                3 => {
                    // A record's length, both markers alike (a header record or one of frame k).
                    let in_frame: Vec<usize> = (3..records.len())
                        .filter(|&r| f.cut.contains(&records[r].start))
                        .collect();
                    let r = if rng.below(2) == 0 {
                        rng.below(3)
                    } else {
                        pick(rng, &in_frame)
                    };
                    let v = hostile32(rng, records[r].len() as u32);
                    out[records[r].start - 4..records[r].start].copy_from_slice(&v.to_le_bytes());
                    out[records[r].end..records[r].end + 4].copy_from_slice(&v.to_le_bytes());
                    format!("record {r} length (both markers) := {v:#x}")
                }
                _ => {
                    // The title count and record rebuilt with 0 to 3 titles: a legal header.
                    let titles = rng.below(4);
                    let mut record = (titles as u32).to_le_bytes().to_vec();
                    for t in 0..titles {
                        record.extend(format!("{:<80}", format!("* mutant title {t}")).bytes());
                    }
                    let len = (record.len() as u32).to_le_bytes();
                    let mut whole = len.to_vec();
                    whole.extend(record);
                    whole.extend(len);
                    out.splice(records[1].start - 4..records[1].end + 4, whole);
                    return (out, Expect::Same, format!("{titles} titles"));
                }
            }
        }
        Binary::NetCdf => {
            let header = netcdf_header(bytes);
            if rng.below(4) == 0 {
                let at = f.start + 4 * rng.below(f.cut.len() / 4);
                out[at..at + 4].copy_from_slice(&f32::NAN.to_be_bytes());
                format!("NaN in the record of frame {k} at byte {at}")
            } else {
                let (at, what) = pick(rng, &header.fields);
                let label = set32(&mut out, at, what, true, rng);
                // A smaller record count is the format's word: that many frames, read whole.
                let records = be32(&out, 4) as usize;
                if at == 4 && (1..frames.len()).contains(&records) {
                    let expect = Expect::Frames {
                        upto: records,
                        exit: 0,
                    };
                    return (out, expect, label);
                }
                label
            }
        }
        Binary::Tng => {
            let blocks = tng_blocks(bytes);
            let block = &blocks[rng.below(blocks.len())];
            let what = rng.below(4);
            let at = match what {
                0..=2 => block.offset + 8 * what,
                _ => block.offset + block.header + 8 * rng.below(block.contents.min(128) / 8),
            };
            let v = if rng.below(3) == 0 {
                le64(&out, at).wrapping_add(1)
            } else {
                pick(rng, &HOSTILE64)
            };
            out[at..at + 8].copy_from_slice(&v.to_le_bytes());
            if what == 3 {
                tng_rehash(&mut out, block);
            }
            let field = [
                "header size",
                "contents size",
                "block id",
                "contents (MD5 recomputed)",
            ][what];
            let label = format!("block at byte {} {field} := {v:#x}", block.offset);
            // Past the first block, a new id or new contents with their MD5 make another
            // well-formed file, which may hold fewer frames (see `Expect::Clean`).
            if what >= 2 && block.offset > 0 {
                return (out, Expect::Clean, label);
            }
            label
        }
    };
    (out, Expect::Hostile, label)
}
