//! Structured mutants of the text formats (PDB, GRO, XYZ, LAMMPS dump, mmCIF) for
//! `io_mutants_structured`: where each frame's lines are, and the seeded edits (hostile header
//! fields and counts, a field made non-numeric, blank lines, tabs, a UTF-8 BOM, CRLF and CR-only
//! line ends, a missing final newline, cuts inside a frame or at a frame boundary), each with
//! what the run must give.

use std::ops::Range;

use crate::io_mutants::Rng;
use crate::io_mutants_structured::{Expect, Frame, pick};

/// The text formats under test.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Text {
    Pdb,
    Gro,
    Xyz,
    Lammps,
    Cif,
}

/// Values a hostile field gets: zero, negative, the 32-bit edges, huge, not a number.
const HOSTILE: [&str; 12] = [
    "0",
    "-1",
    "2147483647",
    "2147483648",
    "4294967295",
    "99999999999999999999999",
    "NaN",
    "nan",
    "-inf",
    "1e308",
    "1e39",
    "",
];
/// A numeric field made non-numeric.
const NOT_NUMBERS: [&str; 6] = ["x", "1.2.3", "--1", "1e", "0x10", "1,5"];

/// The lines of one frame: header lines worth damaging (counts, box, title, column names) and
/// the atom lines (indices into the file's lines).
#[derive(Clone, Debug)]
struct FrameLines {
    first: usize,
    header: Vec<usize>,
    atoms: Range<usize>,
}

/// The file's lines (byte ranges without the `\n`) and its frames.
pub(crate) struct TextLayout {
    format: Text,
    lines: Vec<Range<usize>>,
    frames: Vec<FrameLines>,
}

fn split_lines(bytes: &[u8]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, b) in bytes.iter().enumerate() {
        if *b == b'\n' {
            out.push(start..i);
            start = i + 1;
        }
    }
    if start < bytes.len() {
        out.push(start..bytes.len());
    }
    out
}

impl TextLayout {
    /// Finds the frames of an unmutated file (panics on a file the test data does not hold).
    pub(crate) fn new(format: Text, bytes: &[u8]) -> TextLayout {
        let lines = split_lines(bytes);
        let text = |i: usize| std::str::from_utf8(&bytes[lines[i].clone()]).unwrap_or("");
        let count = |i: usize| text(i).trim().parse::<usize>().expect("atom count");
        let mut frames = Vec::new();
        match format {
            Text::Pdb => {
                let cryst: Vec<usize> = (0..lines.len())
                    .filter(|&i| text(i).starts_with("CRYST1"))
                    .collect();
                let models: Vec<usize> = (0..lines.len())
                    .filter(|&i| text(i).starts_with("MODEL"))
                    .collect();
                for (m, &first) in models.iter().enumerate() {
                    let end = models.get(m + 1).copied().unwrap_or(lines.len());
                    let atom =
                        |i: &usize| text(*i).starts_with("ATOM") || text(*i).starts_with("HETATM");
                    let a = (first..end).find(atom).expect("atoms");
                    let b = (first..end).rfind(atom).expect("atoms") + 1;
                    let mut header = vec![first];
                    header.extend(cryst.iter().filter(|_| m == 0));
                    frames.push(FrameLines {
                        first,
                        header,
                        atoms: a..b,
                    });
                }
            }
            Text::Gro | Text::Xyz => {
                let mut i = 0;
                while i < lines.len() {
                    let (n_at, skip) = if format == Text::Gro {
                        (i + 1, 2)
                    } else {
                        (i, 2)
                    };
                    let n = count(n_at);
                    let atoms = i + skip..i + skip + n;
                    let mut header = vec![i, i + 1];
                    let next = if format == Text::Gro {
                        header.push(atoms.end);
                        atoms.end + 1
                    } else {
                        atoms.end
                    };
                    frames.push(FrameLines {
                        first: i,
                        header,
                        atoms,
                    });
                    i = next;
                }
            }
            Text::Lammps => {
                let starts: Vec<usize> = (0..lines.len())
                    .filter(|&i| text(i) == "ITEM: TIMESTEP")
                    .collect();
                for (m, &first) in starts.iter().enumerate() {
                    let end = starts.get(m + 1).copied().unwrap_or(lines.len());
                    let item = |name: &str| (first..end).find(|&i| text(i).starts_with(name));
                    let atoms_at = item("ITEM: ATOMS").expect("ITEM: ATOMS");
                    let count_at = item("ITEM: NUMBER OF ATOMS").expect("count") + 1;
                    let box_at = item("ITEM: BOX BOUNDS").expect("box") + 1;
                    let header = vec![
                        first + 1,
                        count_at,
                        box_at,
                        box_at + 1,
                        box_at + 2,
                        atoms_at,
                    ];
                    frames.push(FrameLines {
                        first,
                        header,
                        atoms: atoms_at + 1..end,
                    });
                }
            }
            Text::Cif => {
                let tags: Vec<usize> = (0..lines.len())
                    .filter(|&i| text(i).starts_with("_atom_site."))
                    .collect();
                let rows: Vec<usize> = (0..lines.len())
                    .filter(|&i| text(i).starts_with("ATOM ") || text(i).starts_with("HETATM "))
                    .collect();
                frames.push(FrameLines {
                    first: 0,
                    header: tags,
                    atoms: rows[0]..rows[rows.len() - 1] + 1,
                });
            }
        }
        assert!(!frames.is_empty() && frames.iter().all(|f| !f.atoms.is_empty()));
        TextLayout {
            format,
            lines,
            frames,
        }
    }

    /// Each frame's byte span and the bytes where a cut loses at least one whole atom line.
    pub(crate) fn frames(&self) -> Vec<Frame> {
        let frames = &self.frames;
        (0..frames.len())
            .map(|k| {
                let f = &frames[k];
                let start = self.lines[f.first].start;
                // A PDB cut inside the MODEL line leaves a stray record (ignored, as any
                // unknown record is): the cut starts after the model's first atom.
                let from = if self.format == Text::Pdb {
                    self.lines[f.atoms.start].start + 1
                } else {
                    start + 1
                };
                Frame {
                    index: k,
                    start,
                    cut: from..self.lines[f.atoms.end - 1].start + 1,
                }
            })
            .collect()
    }

    /// Formats with fixed columns: tabs only where a number's padding is.
    fn fixed_columns(&self) -> Option<Range<usize>> {
        match self.format {
            Text::Pdb => Some(30..54),
            Text::Gro => Some(20..44),
            _ => None,
        }
    }
}

/// `bytes` with the byte range `at` replaced by `with`.
fn splice(bytes: &[u8], at: Range<usize>, with: &[u8]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out.splice(at, with.iter().copied());
    out
}

/// The whitespace-separated tokens of `line` (byte ranges into `bytes`).
fn tokens(bytes: &[u8], line: &Range<usize>) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    for i in line.clone().chain([line.end]) {
        let space = i == line.end || bytes[i].is_ascii_whitespace();
        match (space, start) {
            (true, Some(s)) => {
                out.push(s..i);
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    out
}

/// `value` padded on the left to `width` (fixed-column fields keep their columns).
fn padded(value: &str, width: usize) -> Vec<u8> {
    format!("{value:>width$}").into_bytes()
}

/// One seeded structured mutant of the text file `bytes`, what the run must give, and a label.
pub(crate) fn mutate_text(
    layout: &TextLayout,
    bytes: &[u8],
    rng: &mut Rng,
) -> (Vec<u8>, Expect, String) {
    let frames = layout.frames();
    let k = rng.below(frames.len());
    let frame = &layout.frames[k];
    let line_of =
        |rng: &mut Rng| layout.lines[frame.atoms.start + rng.below(frame.atoms.len())].clone();
    let anywhere_blank = matches!(layout.format, Text::Pdb | Text::Cif);
    match rng.below(11) {
        0 => {
            // A header field (count, box, title, model number, column name) made hostile.
            let line = layout.lines[pick(rng, &frame.header)].clone();
            let toks = tokens(bytes, &line);
            let value = pick(rng, &HOSTILE);
            if toks.is_empty() {
                return (
                    splice(bytes, line, value.as_bytes()),
                    Expect::Hostile,
                    format!("header line of frame {k} := {value:?}"),
                );
            }
            let t = pick(rng, &toks);
            let with = padded(value, t.len());
            (
                splice(bytes, t, &with),
                Expect::Hostile,
                format!("header field of frame {k} := {value:?}"),
            )
        }
        1 | 2 => {
            // A field of an atom line made hostile or non-numeric; in a LAMMPS dump, ids out of
            // range (0, -1, past the atom count, 2^31 and beyond).
            let line = line_of(rng);
            let toks = tokens(bytes, &line);
            let (t, value) = if layout.format == Text::Lammps && rng.below(2) == 0 {
                let n = frame.atoms.len();
                let ids = [
                    "0".to_string(),
                    "-1".into(),
                    (n + 1).to_string(),
                    "2147483648".into(),
                    "4294967296".into(),
                    "2147483647".into(),
                ];
                (toks[0].clone(), pick(rng, &ids))
            } else if rng.below(2) == 0 {
                (pick(rng, &toks), pick(rng, &HOSTILE).to_string())
            } else {
                let numeric: Vec<_> = toks
                    .iter()
                    .filter(|t| {
                        std::str::from_utf8(&bytes[(*t).clone()])
                            .is_ok_and(|s| s.parse::<f64>().is_ok())
                    })
                    .cloned()
                    .collect();
                (pick(rng, &numeric), pick(rng, &NOT_NUMBERS).to_string())
            };
            let with = padded(&value, t.len());
            (
                splice(bytes, t, &with),
                Expect::Hostile,
                format!("atom field in frame {k} := {value:?}"),
            )
        }
        3 => {
            // Blank lines: at the end (legal everywhere), or inside (legal in PDB and mmCIF).
            let blank = &b"\n\n"[..1 + rng.below(2)];
            if rng.below(3) == 0 {
                let mut out = bytes.to_vec();
                out.extend_from_slice(blank);
                (out, Expect::Same, "blank lines at the end".into())
            } else {
                let at = layout.lines[frame.first + rng.below(frame.atoms.end - frame.first)].start;
                let expect = if anywhere_blank {
                    Expect::Same
                } else {
                    Expect::Hostile
                };
                (
                    splice(bytes, at..at, blank),
                    expect,
                    format!("blank line inside frame {k}"),
                )
            }
        }
        4 => {
            // Tabs for spaces on every atom line (in the number columns of fixed-column formats).
            let mut out = bytes.to_vec();
            let columns = layout.fixed_columns();
            for f in &layout.frames {
                for line in &layout.lines[f.atoms.clone()] {
                    for i in line.clone() {
                        let in_columns = columns
                            .as_ref()
                            .is_none_or(|c| c.contains(&(i - line.start)));
                        // mmCIF: only the spaces before a number (quoted names keep theirs).
                        let before_number = layout.format != Text::Cif
                            || bytes
                                .get(i + 1)
                                .is_some_and(|b| b.is_ascii_digit() || *b == b'-');
                        if out[i] == b' ' && in_columns && before_number {
                            out[i] = b'\t';
                        }
                    }
                }
            }
            (out, Expect::Same, "tabs for spaces".into())
        }
        5 => {
            let mut out = b"\xef\xbb\xbf".to_vec();
            out.extend_from_slice(bytes);
            (out, Expect::Same, "UTF-8 BOM".into())
        }
        6 => {
            let crlf = rng.below(2) == 0;
            let mut out = Vec::with_capacity(bytes.len() * 2);
            for &b in bytes {
                if b == b'\n' {
                    out.extend_from_slice(if crlf { b"\r\n" } else { b"\r" });
                } else {
                    out.push(b);
                }
            }
            (
                out,
                Expect::Same,
                if crlf {
                    "CRLF line ends"
                } else {
                    "CR-only line ends"
                }
                .into(),
            )
        }
        7 => {
            let end = bytes.len() - usize::from(bytes.ends_with(b"\n"));
            (
                bytes[..end].to_vec(),
                Expect::Same,
                "no final newline".into(),
            )
        }
        8 | 9 if layout.format != Text::Cif => {
            let f = &frames[k];
            let at = f.cut.start + rng.below(f.cut.len());
            let expect = Expect::Frames {
                upto: f.index,
                exit: 2,
            };
            (
                bytes[..at].to_vec(),
                expect,
                format!("cut at byte {at}, inside frame {k}"),
            )
        }
        _ => {
            // A cut at a frame boundary (or, for one frame, the whole file without its final
            // newline): every whole frame is kept.
            let j = 1 + rng.below(frames.len());
            let end = frames.get(j).map_or(bytes.len(), |f| f.start);
            let expect = Expect::Frames { upto: j, exit: 0 };
            (
                bytes[..end].to_vec(),
                expect,
                format!("cut at the end of frame {}", j - 1),
            )
        }
    }
}
