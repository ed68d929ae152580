//! The fast XYZ reader (see [`super::fast`]): a plain single-frame XYZ file (atom count,
//! comment, then `NAME X Y Z` per atom, in Å) read in one pass, giving what chemfiles' XYZ
//! reader gives: names that are also the types, no elements (guessed later from the names), no
//! residues, bonds or box, each atom's charge from chemfiles' table. Extended XYZ (a comment with
//! `Properties=species:S:1:pos:R:3`) and files with more than one frame go to chemfiles.

use super::fast::{FastRead, TypeTable, empty_topology, free_text, is_space, lines, parse_f64};
use super::fast::{parse_u64, to_vec3, trim};
use crate::model::{Frame, Labels};

/// Reads an XYZ file's only frame, or `None` when chemfiles should read it.
pub(crate) fn read(bytes: &[u8]) -> Option<FastRead> {
    let mut it = lines(bytes);
    let n = usize::try_from(parse_u64(it.next()?)?).ok()?;
    let comment = it.next()?;
    if n == 0 || memchr::memmem::find(comment, b"species:S:1:pos:R:3").is_some() {
        return None;
    }
    // Each atom line holds at least a name and three numbers (4 bytes and 3 spaces).
    if bytes.len() / 8 < n {
        return None;
    }
    let mut top = empty_topology(n);
    let mut positions = Vec::with_capacity(n);
    let mut table = TypeTable::default();
    let mut last: Option<(&[u8], usize)> = None;
    for _ in 0..n {
        let line = it.next()?;
        let mut tokens = line.split(|&b| is_space(b)).filter(|t| !t.is_empty());
        let name = tokens.next()?;
        let x = parse_f64(tokens.next()?)?;
        let y = parse_f64(tokens.next()?)?;
        let z = parse_f64(tokens.next()?)?;
        positions.push(to_vec3([x, y, z]));
        // Most neighbours share a name: reuse the previous atom's strings and charge.
        match last {
            Some((prev, i)) if prev == name => {
                top.names.push_like(i);
                top.charges.push(top.charges[i]);
            }
            _ => {
                let text = free_text(name);
                let (_, charge) = table.get(&text);
                top.names.push(text);
                top.charges.push(charge);
                last = Some((name, top.names.len() - 1));
            }
        }
    }
    // Names are the types; no element (guessed later from the name) and no mass.
    top.types = top.names.clone();
    top.elements = Labels::filled("", n);
    top.masses = vec![0.0; n];
    // chemfiles counts another frame unless the next line is blank (or there is none).
    if it.next().is_some_and(|line| !trim(line).is_empty()) {
        return None;
    }
    let no_residue = vec![u32::MAX; n];
    super::chem::number_residue_runs(&mut top, &no_residue);
    Some(FastRead {
        topology: top,
        frame: Frame {
            index: 0,
            time_ps: None,
            positions,
            cell: None,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_single_frames_only() {
        let f = read(b"2\nwater\nO 0 0 0\nH 0.96 0 0\n").expect("plain");
        assert_eq!(f.topology.names, vec!["O", "H"]);
        assert_eq!(f.topology.residue_index, vec![0, 1]);
        assert_eq!(f.frame.positions[1].x, 0.96);
        assert!(
            read(b"1\na\nO 0 0 0\n1\nb\nO 0 0 1\n").is_none(),
            "two frames"
        );
        assert!(read(b"2\na\nO 0 0 0\n").is_none(), "short");
        assert!(read(b"1\na\nO 0 0 zero\n").is_none(), "bad number");
        assert!(read(b"1\nProperties=species:S:1:pos:R:3\nO 0 0 0\n").is_none());
        assert!(read(b"0\nnothing\n").is_none());
    }
}
