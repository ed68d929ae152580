//! A structural check of TNG files, done before the TNG library opens one: the library crashes
//! (SIGSEGV) on some damaged files and prints its own complaints to stderr. A TNG file is a chain
//! of blocks, each with a header (its own size, the contents' size, an id, the MD5 of the
//! contents, a name, ...) followed by its contents. This walks the chain and checks each block's
//! MD5 where the writer recorded one (the `md5` crate), so a flipped byte, a cut or a duplicated
//! or deleted chunk is found here. Frames come in frame sets (a frame-set block followed by its
//! data blocks); when the damage comes after some whole frame sets, a copy of the file holding
//! only those is made, with the pointers to the removed frame sets cleared and the patched
//! blocks' MD5 recomputed, so the good frames stay readable. The frame set holding the damage is
//! dropped whole (a damaged block cannot say which frame set it belonged to).

mod atoms;

use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

/// Why a TNG file cannot be read at all (not even one frame set is sound); one line each.
#[derive(Debug, Clone, thiserror::Error)]
pub(crate) enum TngDamage {
    /// The operating system could not read the file.
    #[error(transparent)]
    Os(Arc<std::io::Error>),
    /// The file is shorter than one block header.
    #[error("the file ends inside its first block (truncated)")]
    FirstBlockCut,
    /// Block `block` (from 0) at byte `offset` is damaged; `what` says how.
    #[error("block {block} at byte {offset} {what} (damaged file)")]
    Block {
        block: usize,
        offset: usize,
        what: &'static str,
    },
    /// The MOLECULES block's atom count disagrees with the atoms a positions or velocities
    /// block holds, or cannot be read (see [`atoms`]); the text says which and the values.
    #[error("{0} (damaged file)")]
    Atoms(String),
    /// The chain ends after `have` frame sets, one short of what the index points to.
    #[error(
        "the file ends after frame set {have} of the {promised} its index promises (truncated)"
    )]
    IndexCut { have: usize, promised: usize },
}

/// Header sizes outside this range (bytes) are damage.
const HEADER_SIZES: std::ops::RangeInclusive<i64> = 40..=4096;
/// Block ids (TNG 1.x): the file's general information and the start of a frame set.
const GENERAL_INFO: i64 = 0;
const FRAME_SET: i64 = 2;

/// One block of the chain: where it starts, its header and contents sizes (bytes), its id.
#[derive(Debug, Clone, Copy)]
struct Block {
    offset: usize,
    header: usize,
    contents: usize,
    id: i64,
}

impl Block {
    fn end(&self) -> usize {
        self.offset + self.header + self.contents
    }
}

/// Reads 8-byte integers in the file's byte order.
#[derive(Clone, Copy)]
struct Ints {
    little: bool,
}

impl Ints {
    fn get(self, bytes: &[u8], at: usize) -> i64 {
        let b: [u8; 8] = bytes
            .get(at..at + 8)
            .and_then(|s| s.try_into().ok())
            .unwrap_or([0; 8]);
        if self.little {
            i64::from_le_bytes(b)
        } else {
            i64::from_be_bytes(b)
        }
    }

    fn put(self, bytes: &mut [u8], at: usize, value: i64) {
        let b = if self.little {
            value.to_le_bytes()
        } else {
            value.to_be_bytes()
        };
        bytes[at..at + 8].copy_from_slice(&b);
    }
}

/// What [`salvage`] found.
pub(crate) enum Salvage {
    /// The chain is sound: open the file as it is.
    Sound,
    /// The chain is damaged after some whole frame sets: `bytes` is a copy holding only those,
    /// with the pointers to the removed frame sets cleared; `reason` says where the damage is.
    Kept { bytes: Vec<u8>, reason: String },
}

/// Checks the block chain of the TNG file at `path` (each block's size and, where the writer
/// recorded one, its MD5). A damaged file keeps the frame sets before the damage (see
/// [`Salvage::Kept`]); `Err` (one line) when not even one frame set is sound.
pub(crate) fn salvage(path: &Path) -> Result<Salvage, TngDamage> {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| TngDamage::Os(Arc::new(e)))?;
    salvage_bytes(&bytes)
}

/// [`salvage`] of a file's bytes.
fn salvage_bytes(bytes: &[u8]) -> Result<Salvage, TngDamage> {
    if bytes.len() < 8 {
        return Err(TngDamage::FirstBlockCut);
    }
    // The first block's header size says the byte order (a small number: high bytes zero).
    let ints = Ints {
        little: bytes[0] != 0 && bytes[7] == 0,
    };
    let (mut blocks, mut damage) = walk(bytes, ints);
    // The chain starts with the general information block: the TNG library reads a file whose
    // first block has another id without complaint, and loses its last frame set.
    if blocks.first().is_some_and(|b| b.id != GENERAL_INFO) {
        return Err(TngDamage::Block {
            block: 0,
            offset: 0,
            what: "is not a general information block (wrong id)",
        });
    }
    // The TNG library trusts the atom count: particle data that disagree are damage.
    if let Some((at, why)) = atoms::first_disagreement(bytes, ints, &blocks) {
        blocks.retain(|b| b.offset < at);
        damage = Some((at, why));
    }
    let frame_sets: Vec<&Block> = blocks.iter().filter(|b| b.id == FRAME_SET).collect();
    let info = blocks
        .first()
        .filter(|b| b.id == GENERAL_INFO && b.contents >= 40);
    // How many frame sets to keep, and why not all of them.
    // Where the sound blocks end.
    let sound_end = damage.as_ref().map_or(bytes.len(), |(at, _)| *at);
    let (keep, reason) = match damage {
        // The frame set holding the damage and everything after it go; when the damaged block
        // starts a frame set (a cut inside its first block), the sets before it are whole.
        Some((damaged_at, reason)) => {
            let starts_set =
                bytes.len() >= damaged_at + 24 && ints.get(bytes, damaged_at + 16) == FRAME_SET;
            let holding = frame_sets.iter().rposition(|b| b.offset <= damaged_at);
            let keep = if starts_set {
                Some(frame_sets.len())
            } else {
                holding
            };
            (keep, reason)
        }
        None => {
            let (Some(info), Some(last)) = (info, frame_sets.last().filter(|b| b.contents >= 64))
            else {
                return Ok(Salvage::Sound);
            };
            // A sound chain cut at a block boundary: the index still points past the end.
            let last_pointer = ints.get(bytes, info.end() - 32);
            let next = ints.get(bytes, last.end() - 64);
            if last_pointer == last.offset as i64 && next == -1 {
                return Ok(Salvage::Sound);
            }
            // The last frame set is whole when the next one would start where the file ends.
            let whole = next >= 0 && next as u64 >= bytes.len() as u64;
            let keep = if whole {
                frame_sets.len()
            } else {
                frame_sets.len() - 1
            };
            let reason = TngDamage::IndexCut {
                have: frame_sets.len(),
                promised: frame_sets.len() + 1,
            };
            (Some(keep), reason)
        }
    };
    let (Some(j), Some(info)) = (keep.filter(|&j| j > 0), info) else {
        return Err(reason);
    };
    let cut = frame_sets.get(j).map_or(sound_end, |b| b.offset);
    let last_kept = frame_sets[j - 1].offset as i64;
    let mut kept = bytes[..cut].to_vec();
    // The general information points at the last frame set (40 bytes before the end of its
    // contents come the first and the last frame set's positions).
    let info_end = info.end();
    ints.put(&mut kept, info_end - 32, last_kept);
    rehash(&mut kept, info);
    // Frame set contents end with: next, previous, medium-stride next and previous, long-stride
    // next and previous frame set positions, the first frame's time and the time per frame.
    // A next pointer must lead forward to a kept frame set; any other (past the cut, or a
    // hostile one pointing back, which would loop the library) is cleared.
    let kept_sets: Vec<i64> = frame_sets[..j].iter().map(|b| b.offset as i64).collect();
    for set in &frame_sets[..j] {
        if set.contents < 64 {
            return Err(reason);
        }
        let end = set.end();
        for back in [64, 48, 32] {
            let next = ints.get(&kept, end - back);
            if next <= set.offset as i64 || !kept_sets.contains(&next) {
                ints.put(&mut kept, end - back, -1);
            }
        }
        rehash(&mut kept, set);
    }
    Ok(Salvage::Kept {
        bytes: kept,
        reason: format!("{reason}; the frame sets before it are kept"),
    })
}

/// The structural check of a TNG file's bytes, for the fuzz target `tng` (fuzz/): `Ok(None)`
/// when the chain is sound, `Ok(Some(copy))` with the frame sets kept before the damage, or the
/// one-line reason none is sound. The fuzz target holds a kept copy to the check itself: it
/// must be sound.
#[doc(hidden)]
pub fn check_chain(bytes: &[u8]) -> Result<Option<Vec<u8>>, String> {
    match salvage_bytes(bytes) {
        Ok(Salvage::Sound) => Ok(None),
        Ok(Salvage::Kept { bytes, .. }) => Ok(Some(bytes)),
        Err(damage) => Err(damage.to_string()),
    }
}

/// Walks the chain; returns the sound blocks and, when the chain breaks, the offset of the
/// first damaged block and why.
fn walk(bytes: &[u8], ints: Ints) -> (Vec<Block>, Option<(usize, TngDamage)>) {
    let size = bytes.len();
    let mut blocks = Vec::new();
    let mut offset = 0usize;
    while offset < size {
        let n = blocks.len();
        let damaged = |what: &'static str| {
            Some((
                offset,
                TngDamage::Block {
                    block: n,
                    offset,
                    what,
                },
            ))
        };
        if size - offset < 40 {
            return (blocks, damaged("is cut by the end of the file"));
        }
        let header = ints.get(bytes, offset);
        let contents = ints.get(bytes, offset + 8);
        if !HEADER_SIZES.contains(&header) || contents < 0 {
            return (blocks, damaged("has an invalid header"));
        }
        let end = (offset as u64)
            .checked_add(header as u64)
            .and_then(|e| e.checked_add(contents as u64));
        let Some(end) = end.filter(|&e| e <= size as u64) else {
            return (blocks, damaged("runs past the end of the file"));
        };
        let hash: [u8; 16] = bytes[offset + 24..offset + 40]
            .try_into()
            .unwrap_or([0; 16]);
        if hash != [0; 16] && md5::compute(&bytes[offset + header as usize..end as usize]).0 != hash
        {
            return (blocks, damaged("fails its checksum"));
        }
        blocks.push(Block {
            offset,
            header: header as usize,
            contents: contents as usize,
            id: ints.get(bytes, offset + 16),
        });
        offset = end as usize;
    }
    (blocks, None)
}

/// Recomputes the MD5 of `block`'s contents in `bytes` after a patch (when it has one).
fn rehash(bytes: &mut [u8], block: &Block) {
    let at = block.offset + 24;
    if bytes[at..at + 16] != [0; 16] {
        let digest = md5::compute(&bytes[block.offset + block.header..block.end()]).0;
        bytes[at..at + 16].copy_from_slice(&digest);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of one empty block (little-endian, no MD5) with id `id`, in a temporary file.
    fn one_block(id: i64) -> (tempfile::TempDir, std::path::PathBuf) {
        let mut bytes = Vec::new();
        for v in [40i64, 0, id] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes.resize(40, 0);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("one.tng");
        std::fs::write(&path, bytes).unwrap();
        (dir, path)
    }

    #[test]
    fn a_cut_inside_a_frame_set_block_keeps_the_frame_sets_before_it() {
        let data = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/argon_npt_compressed.tng"
        );
        let bytes = std::fs::read(data).unwrap();
        // The second (last) frame set starts at byte 398576 with its 149-byte frame-set block.
        let second = 398576;
        assert_eq!(Ints { little: true }.get(&bytes, second + 16), FRAME_SET);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.tng");
        std::fs::write(&path, &bytes[..second + 103]).unwrap();
        match salvage(&path) {
            Ok(Salvage::Kept { bytes, reason }) => {
                assert_eq!(bytes.len(), second);
                assert!(reason.contains("block 8 at byte 398576"), "{reason}");
            }
            Ok(Salvage::Sound) => panic!("a cut file read as sound"),
            Err(e) => panic!("the whole first frame set was lost: {e}"),
        }
    }

    #[test]
    fn a_first_block_that_is_not_general_information_is_damage() {
        let (_dir, path) = one_block(GENERAL_INFO);
        assert!(matches!(salvage(&path), Ok(Salvage::Sound)));
        let (_dir, path) = one_block(i64::MIN);
        let e = salvage(&path).err().expect("refused");
        assert!(matches!(e, TngDamage::Block { block: 0, .. }), "{e}");
        assert!(e.to_string().contains("wrong id"), "{e}");
    }

    #[test]
    fn a_kept_copy_passes_the_check_itself() {
        // The property the fuzz target `tng` holds on every input, on cuts of the real file.
        let data = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/argon_npt_compressed.tng"
        );
        let bytes = std::fs::read(data).unwrap();
        assert_eq!(check_chain(&bytes), Ok(None));
        let mut kept_any = 0;
        for cut in (bytes.len() / 2..bytes.len()).step_by(997) {
            if let Ok(Some(copy)) = check_chain(&bytes[..cut]) {
                assert!(
                    copy.len() <= cut,
                    "a cut at {cut} kept {} bytes",
                    copy.len()
                );
                assert_eq!(check_chain(&copy), Ok(None), "the copy of a cut at {cut}");
                kept_any += 1;
            }
        }
        assert!(kept_any > 0, "no cut kept a frame set");
    }

    #[test]
    fn fuzz_findings_keep_copies_that_pass_the_check() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fuzz/tng");
        let mut seen = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            if let Ok(Some(copy)) = check_chain(&bytes) {
                assert_eq!(check_chain(&copy), Ok(None), "{}", path.display());
            }
            seen += 1;
        }
        assert!(seen > 0, "no finding in {dir}");
    }
}
