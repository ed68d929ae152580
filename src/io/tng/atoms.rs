//! The atom count of a TNG file checked against its particle data before the TNG library reads
//! it. The library takes the number of atoms from the MOLECULES block (each molecule type's atom
//! count times its number of molecules) and trusts it: a hostile count there (its MD5
//! recomputed) made it read 32,768 atoms of garbage from a 1,000-atom file, or abort. Here the
//! count is summed (overflow checked) and each positions and velocities block must hold atoms
//! inside it; the positions blocks of a frame set must hold every atom. The first block that
//! disagrees is the damage (the frame sets before it are kept, see [`super::salvage`]).
//!
//! Layouts (TNG 1.x). MOLECULES contents: the number of molecule types, then per type: id, name
//! (NUL-ended), quaternary structure, its number of molecules (only when the atom count is
//! constant), number of chains, residues, atoms; then its chains (id, name, residue count), each
//! followed by its residues (id, name, atom count), each followed by its atoms (id, name, type),
//! or, without chains, the residues so, or, without residues, the atoms; then the bonds (a count,
//! then two ids each). A data block's contents start with: data type (1 byte), dependency (1
//! byte: 1 frame, 2 particle), when frame-dependent a sparse flag (1 byte), values per item,
//! codec id, a multiplier when compressed (8 bytes), when frame-dependent and sparse the first
//! frame and the stride, and when particle-dependent the first atom and the number of atoms.

use super::{Block, FRAME_SET, GENERAL_INFO, Ints, TngDamage};

/// Block ids (TNG 1.x): molecule types and counts, positions, velocities.
const MOLECULES: i64 = 1;
const POSITIONS: i64 = 0x1000_0001;
const VELOCITIES: i64 = 0x1000_0002;
/// Bytes from the end of the GENERAL INFO contents back to its "atom count varies" flag (then
/// come the frames per frame set, the first and last frame set's positions, two strides and
/// the distance unit, 8 bytes each).
const VARIABLE_FLAG_FROM_END: usize = 49;
/// Molecule types named in a message before "...".
const TYPES_NAMED: usize = 3;

/// Reads a block's contents front to back (the file's byte order); `None` past their end.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    end: usize,
    ints: Ints,
}

impl<'a> Cursor<'a> {
    fn over(bytes: &'a [u8], block: &Block, ints: Ints) -> Self {
        Cursor {
            bytes,
            at: block.offset + block.header,
            end: block.end(),
            ints,
        }
    }

    fn int(&mut self) -> Option<i64> {
        (self.at + 8 <= self.end).then(|| {
            self.at += 8;
            self.ints.get(self.bytes, self.at - 8)
        })
    }

    fn byte(&mut self) -> Option<u8> {
        (self.at < self.end).then(|| {
            self.at += 1;
            self.bytes[self.at - 1]
        })
    }

    /// A NUL-ended string (lossy UTF-8).
    fn string(&mut self) -> Option<String> {
        let rest = &self.bytes[self.at..self.end];
        let len = rest.iter().position(|&b| b == 0)?;
        self.at += len + 1;
        Some(String::from_utf8_lossy(&rest[..len]).into_owned())
    }

    /// Skips a record of an id and `strings` strings (a chain or residue name, an atom's name
    /// and type).
    fn skip_named(&mut self, strings: usize) -> Option<()> {
        let _id = self.int()?;
        for _ in 0..strings {
            self.string()?;
        }
        Some(())
    }
}

/// What the MOLECULES block says: its atom count and the molecule types for messages.
struct Molecules {
    offset: usize,
    atoms: i64,
    /// Per type: name, number of molecules, atoms per molecule.
    types: Vec<(String, i64, i64)>,
}

impl Molecules {
    /// "the MOLECULES block at byte 153 counts 1000 atoms (Argon: 1000 × 1 atom)".
    fn counts(&self) -> String {
        let mut named: Vec<String> = self
            .types
            .iter()
            .take(TYPES_NAMED)
            .map(|(name, count, atoms)| format!("{name}: {count} × {}", plural(*atoms, "atom")))
            .collect();
        if self.types.len() > TYPES_NAMED {
            named.push("...".into());
        }
        format!(
            "the MOLECULES block at byte {} counts {} atoms ({})",
            self.offset,
            self.atoms,
            named.join(", ")
        )
    }
}

/// "1 atom", "3 atoms".
fn plural(n: i64, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}

/// Damage at `block`: `what` in one line.
fn damage(block: &Block, what: String) -> Option<(usize, TngDamage)> {
    Some((block.offset, TngDamage::Atoms(what)))
}

/// The first of the sound `blocks` (in file order) whose particle data disagree with the
/// MOLECULES block's atom count, or the MOLECULES block itself when it cannot be read, with the
/// reason; `None` when all agree, when the file has no MOLECULES block before its first frame
/// set, or when its atom count may vary (then each frame set holds the counts).
pub(super) fn first_disagreement(
    bytes: &[u8],
    ints: Ints,
    blocks: &[Block],
) -> Option<(usize, TngDamage)> {
    let info = blocks
        .first()
        .filter(|b| b.id == GENERAL_INFO && b.contents >= VARIABLE_FLAG_FROM_END)?;
    if bytes[info.end() - VARIABLE_FLAG_FROM_END] != 0 {
        return None;
    }
    let block = blocks
        .iter()
        .take_while(|b| b.id != FRAME_SET)
        .find(|b| b.id == MOLECULES)?;
    let molecules = match read_molecules(bytes, ints, block) {
        Ok(m) => m,
        Err(what) => return damage(block, format!("the MOLECULES block at byte {what}")),
    };
    let mut frame_set = None::<usize>;
    let mut first_positions = None::<&Block>;
    let mut held = 0i64;
    for b in blocks {
        if b.id == FRAME_SET {
            if let Some(short) = short(&molecules, frame_set, first_positions, held) {
                return Some(short);
            }
            frame_set = Some(frame_set.map_or(0, |k| k + 1));
            first_positions = None;
            held = 0;
            continue;
        }
        if b.id != POSITIONS && b.id != VELOCITIES {
            continue;
        }
        let name = if b.id == POSITIONS {
            "POSITIONS"
        } else {
            "VELOCITIES"
        };
        let Some(range) = particles(bytes, ints, b) else {
            return damage(
                b,
                format!(
                    "the {name} block at byte {} ends inside its data header",
                    b.offset
                ),
            );
        };
        let Some((first, n)) = range else { continue };
        let inside = first >= 0
            && n >= 0
            && first
                .checked_add(n)
                .is_some_and(|end| end <= molecules.atoms);
        if !inside {
            let last = first.saturating_add(n).saturating_sub(1);
            let what = format!(
                "{}, but the {name} block at byte {} holds atoms {first} to {last}",
                molecules.counts(),
                b.offset
            );
            return damage(b, what);
        }
        if b.id == POSITIONS && frame_set.is_some() {
            first_positions.get_or_insert(b);
            held = held.saturating_add(n);
        }
    }
    short(&molecules, frame_set, first_positions, held)
}

/// Closes frame set `set` (from 0) whose first positions block is `first` and whose positions
/// blocks hold `held` atoms: damage at `first` unless they hold every atom.
fn short(
    molecules: &Molecules,
    set: Option<usize>,
    first: Option<&Block>,
    held: i64,
) -> Option<(usize, TngDamage)> {
    let (set, first) = (set?, first?);
    if held == molecules.atoms {
        return None;
    }
    let what = format!(
        "{}, but the positions of frame set {set} (from byte {}) hold {held}",
        molecules.counts(),
        first.offset
    );
    damage(first, what)
}

/// The atom count and molecule types of the MOLECULES block `block`; `Err` says (after "the
/// MOLECULES block at byte ") what is wrong.
fn read_molecules(bytes: &[u8], ints: Ints, block: &Block) -> Result<Molecules, String> {
    let mut c = Cursor::over(bytes, block, ints);
    let at = block.offset;
    let cut = |m: usize| format!("{at} ends inside molecule type {m}");
    let types = c.int().ok_or_else(|| cut(0))?;
    let mut molecules = Molecules {
        offset: at,
        atoms: 0,
        types: Vec::new(),
    };
    // Each type takes at least 57 bytes, so a hostile count ends at the block's end.
    for m in 0..types.max(0) as usize {
        let read = |c: &mut Cursor| -> Option<(String, i64, i64)> {
            c.int()?;
            let name = c.string()?;
            c.int()?;
            let count = c.int()?;
            let (chains, residues, atoms) = (c.int()?, c.int()?, c.int()?);
            if chains > 0 {
                for _ in 0..chains {
                    c.skip_named(1)?;
                    for _ in 0..c.int()? {
                        c.skip_named(1)?;
                        for _ in 0..c.int()? {
                            c.skip_named(2)?;
                        }
                    }
                }
            } else if residues > 0 {
                for _ in 0..residues {
                    c.skip_named(1)?;
                    for _ in 0..c.int()? {
                        c.skip_named(2)?;
                    }
                }
            } else {
                for _ in 0..atoms {
                    c.skip_named(2)?;
                }
            }
            for _ in 0..c.int()? {
                c.int()?;
                c.int()?;
            }
            Some((name, count, atoms))
        };
        let (name, count, atoms) = read(&mut c).ok_or_else(|| cut(m))?;
        let total = count
            .checked_mul(atoms)
            .and_then(|n| molecules.atoms.checked_add(n))
            .filter(|_| count >= 0 && atoms >= 0);
        let Some(total) = total else {
            return Err(format!(
                "{at} gives molecule type {m} ({name}) {count} molecules of {}",
                plural(atoms, "atom")
            ));
        };
        molecules.atoms = total;
        molecules.types.push((name, count, atoms));
    }
    Ok(molecules)
}

/// The atoms a data block holds (first, how many), `Some(None)` when it is not per atom, `None`
/// when its contents end before that is said.
fn particles(bytes: &[u8], ints: Ints, block: &Block) -> Option<Option<(i64, i64)>> {
    let mut c = Cursor::over(bytes, block, ints);
    let _data_type = c.byte()?;
    let dependency = c.byte()?;
    let per_frame = dependency & 1 != 0;
    let sparse = if per_frame { c.byte()? != 0 } else { false };
    let _values = c.int()?;
    let codec = c.int()?;
    if codec != 0 {
        c.int()?;
    }
    if per_frame && sparse {
        c.int()?;
        c.int()?;
    }
    if dependency & 2 == 0 {
        return Some(None);
    }
    Some(Some((c.int()?, c.int()?)))
}

#[cfg(test)]
mod tests {
    use super::super::walk;
    use super::*;

    #[test]
    fn the_argon_file_counts_1000_atoms_and_its_positions_hold_them() {
        let data = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/argon_npt_compressed.tng"
        );
        let bytes = std::fs::read(data).unwrap();
        let ints = Ints { little: true };
        let (blocks, damage) = walk(&bytes, ints);
        assert!(damage.is_none());
        let molecules = blocks.iter().find(|b| b.id == MOLECULES).unwrap();
        let m = read_molecules(&bytes, ints, molecules).unwrap();
        assert_eq!(m.atoms, 1000);
        assert_eq!(m.types, [("Argon".to_string(), 1000, 1)]);
        let positions: Vec<_> = blocks.iter().filter(|b| b.id == POSITIONS).collect();
        assert_eq!(positions.len(), 2);
        for b in positions {
            assert_eq!(particles(&bytes, ints, b), Some(Some((0, 1000))));
        }
        assert!(first_disagreement(&bytes, ints, &blocks).is_none());
    }
}
