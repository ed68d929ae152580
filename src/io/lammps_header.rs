//! The header of one LAMMPS dump frame (see [`super::lammps`]): the `ITEM:` lines before the
//! atoms (`UNITS` and `TIME` optional, `TIMESTEP`, `NUMBER OF ATOMS`, `BOX BOUNDS` with its three
//! lines, `ATOMS` with the column names), and which columns hold what. A damaged header is a
//! [`LammpsError`] naming the line.

use super::fast::{parse_f64, parse_i64, parse_u64, trim};
use super::reader_errors::LammpsError;
use super::text_scan::cell_rows;
use glam::Vec3;

/// A frame's header.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    /// Number of atom lines after the header.
    pub atoms: usize,
    /// The box: its lower corner (Å, or the dump's length unit) and rows a, b, c.
    pub origin: [f64; 3],
    /// Rows a, b, c of the box (as the dump writes them: xlo..xhi with the tilts xy, xz, yz).
    pub rows: [[f64; 3]; 3],
    /// The box as [`crate::model::Frame::cell`] holds it (`None`: a zero box).
    pub cell: Option<[Vec3; 3]>,
    /// What the atom columns hold.
    pub columns: Columns,
    /// Number of header lines.
    pub lines: u64,
}

/// Which atom column (from 0) holds what.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Columns {
    /// Number of columns.
    pub count: usize,
    /// `id`.
    pub id: Option<usize>,
    /// `type`.
    pub kind: Option<usize>,
    /// `element`.
    pub element: Option<usize>,
    /// `mass`.
    pub mass: Option<usize>,
    /// `q`.
    pub charge: Option<usize>,
    /// x, y, z of the positions chosen (see [`Columns::choose`]).
    pub position: [Option<usize>; 3],
    /// True when those positions are scaled (fractions of the box).
    pub scaled: bool,
    /// `ix`, `iy`, `iz` when the positions are wrapped and images are given: they are added.
    pub images: Option<[Option<usize>; 3]>,
}

/// The position columns a dump may hold: wrapped (`x`), scaled (`xs`), unwrapped (`xu`),
/// scaled unwrapped (`xsu`).
const STYLES: [[&str; 3]; 4] = [
    ["x", "y", "z"],
    ["xs", "ys", "zs"],
    ["xu", "yu", "zu"],
    ["xsu", "ysu", "zsu"],
];

impl Columns {
    /// The columns named after `ITEM: ATOMS`. Positions as chemfiles picks them: the style with
    /// the most of its three columns present, unwrapped before scaled unwrapped before wrapped
    /// before scaled on ties. `None` when there is none.
    pub(crate) fn choose(names: &[&[u8]]) -> Option<Columns> {
        let mut columns = Columns {
            count: names.len(),
            ..Columns::default()
        };
        let mut styles = [[None; 3]; 4];
        let mut images = [None; 3];
        for (k, &name) in names.iter().enumerate() {
            match name {
                b"id" => columns.id = Some(k),
                b"type" => columns.kind = Some(k),
                b"element" => columns.element = Some(k),
                b"mass" => columns.mass = Some(k),
                b"q" => columns.charge = Some(k),
                b"ix" => images[0] = Some(k),
                b"iy" => images[1] = Some(k),
                b"iz" => images[2] = Some(k),
                _ => {
                    for (style, axes) in styles.iter_mut().zip(STYLES) {
                        for (slot, axis) in style.iter_mut().zip(axes) {
                            if name == axis.as_bytes() {
                                *slot = Some(k);
                            }
                        }
                    }
                }
            }
        }
        let count = |s: usize| styles[s].iter().flatten().count();
        let (wrapped, scaled, unwrapped, scaled_unwrapped) =
            (count(0), count(1), count(2), count(3));
        let style = if wrapped + scaled + unwrapped + scaled_unwrapped == 0 {
            return None;
        } else if unwrapped >= scaled_unwrapped && unwrapped >= wrapped && unwrapped >= scaled {
            2
        } else if scaled_unwrapped >= wrapped && scaled_unwrapped >= scaled {
            3
        } else if wrapped >= scaled {
            0
        } else {
            1
        };
        columns.position = styles[style];
        columns.scaled = style == 1 || style == 3;
        let unwrapped_already = style == 2 || style == 3;
        if images.iter().any(Option::is_some) && !unwrapped_already {
            columns.images = Some(images);
        }
        Some(columns)
    }
}

/// `ITEM: NAME` as `NAME` (trimmed); `None` for any other line.
pub(crate) fn item(line: &[u8]) -> Option<&[u8]> {
    let colon = memchr::memchr(b':', line)?;
    (trim(&line[..colon]) == b"ITEM").then(|| trim(&line[colon + 1..]))
}

/// The whitespace-separated words of `line`.
pub(crate) fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|&b| matches!(b, b' ' | b'\t' | b'\x0C'))
        .filter(|w| !w.is_empty())
}

/// Reads a header from `lines` (the frame's lines, the first one numbered `first_line`), up to
/// and with its `ITEM: ATOMS` line. Errors name the line.
pub(crate) fn parse<'a>(
    lines: &mut impl Iterator<Item = &'a [u8]>,
    first_line: u64,
) -> Result<Header, LammpsError> {
    let mut number = first_line - 1;
    let mut next = |what: &'static str| {
        number += 1;
        lines
            .next()
            .map(|line| (number, line))
            .ok_or(LammpsError::EndsBefore { what })
    };
    let mut atoms = None;
    let mut bounds = None;
    let mut timestep = false;
    loop {
        let (at, line) = next("ITEM: ATOMS")?;
        let Some(name) = item(line) else {
            return Err(LammpsError::NotAnItem {
                line: at,
                shown: String::from_utf8_lossy(trim(line)).into_owned(),
            });
        };
        match name {
            b"UNITS" | b"TIME" => {
                next("the value of an ITEM")?;
            }
            b"TIMESTEP" => {
                let (at, value) = next("the time step")?;
                parse_i64(value).ok_or(LammpsError::BadTimestep { line: at })?;
                timestep = true;
            }
            b"NUMBER OF ATOMS" => {
                let (at, value) = next("the atom count")?;
                let count = parse_u64(value).and_then(|n| usize::try_from(n).ok());
                atoms = Some(count.ok_or(LammpsError::BadAtomCount { line: at })?);
            }
            _ if name.starts_with(b"BOX BOUNDS") => {
                let flags: Vec<&[u8]> = words(&name[10..]).collect();
                if flags.first() == Some(&&b"abc"[..]) {
                    return Err(LammpsError::GeneralTriclinic { line: at });
                }
                let tilted = flags
                    .windows(3)
                    .any(|w| w == [&b"xy"[..], &b"xz"[..], &b"yz"[..]]);
                let mut values = [[0.0f64; 3]; 3];
                for row in &mut values {
                    let (at, line) = next("the box")?;
                    let found: Vec<&[u8]> = words(line).collect();
                    let wanted = if tilted { 3 } else { 2 };
                    if found.len() != wanted {
                        return Err(LammpsError::BoxValueCount {
                            line: at,
                            found: found.len(),
                            wanted,
                        });
                    }
                    for (value, word) in row.iter_mut().zip(&found) {
                        *value = parse_f64(word).ok_or_else(|| LammpsError::BadBoxValue {
                            line: at,
                            shown: String::from_utf8_lossy(word).into_owned(),
                        })?;
                    }
                }
                bounds = Some((at, values, tilted));
            }
            _ if name.starts_with(b"ATOMS") => {
                let before = |missing| LammpsError::AtomsBefore { line: at, missing };
                if !timestep {
                    return Err(before("TIMESTEP"));
                }
                let atoms = atoms.ok_or_else(|| before("NUMBER OF ATOMS"))?;
                let (box_line, values, tilted) = bounds.ok_or_else(|| before("BOX BOUNDS"))?;
                let names: Vec<&[u8]> = words(&name[5..]).collect();
                let columns =
                    Columns::choose(&names).ok_or(LammpsError::NoPositions { line: at })?;
                let (origin, rows) = box_rows(values, tilted);
                let cell = cell_rows(rows).map_err(|error| LammpsError::Cell {
                    line: box_line,
                    error,
                })?;
                return Ok(Header {
                    atoms,
                    origin,
                    rows,
                    cell,
                    columns,
                    lines: at + 1 - first_line,
                });
            }
            other => {
                return Err(LammpsError::UnknownItem {
                    line: at,
                    shown: String::from_utf8_lossy(other).into_owned(),
                });
            }
        }
    }
}

/// The box of the three `BOX BOUNDS` lines (`lo hi`, or `lo_bound hi_bound tilt` when
/// `tilted`): its lower corner and rows a, b, c. A tilted box's lines hold the bounds of the
/// whole parallelepiped, from which LAMMPS' `xlo`, `xhi`, ... are recovered.
fn box_rows(values: [[f64; 3]; 3], tilted: bool) -> ([f64; 3], [[f64; 3]; 3]) {
    let [[xlo, xhi, xy], [ylo, yhi, xz], [zlo, zhi, yz]] = values;
    if !tilted {
        let rows = [
            [xhi - xlo, 0.0, 0.0],
            [0.0, yhi - ylo, 0.0],
            [0.0, 0.0, zhi - zlo],
        ];
        return ([xlo, ylo, zlo], rows);
    }
    let low_x = 0f64.min(xy).min(xz).min(xy + xz);
    let high_x = 0f64.max(xy).max(xz).max(xy + xz);
    let (xlo, xhi) = (xlo - low_x, xhi - high_x);
    let (ylo, yhi) = (ylo - 0f64.min(yz), yhi - 0f64.max(yz));
    let rows = [
        [xhi - xlo, 0.0, 0.0],
        [xy, yhi - ylo, 0.0],
        [xz, yz, zhi - zlo],
    ];
    ([xlo, ylo, zlo], rows)
}

#[cfg(test)]
mod tests {
    use super::super::text_scan::BoxError;
    use super::*;

    fn header(text: &str) -> Result<Header, LammpsError> {
        let mut lines = super::super::text_scan::lines(text.as_bytes());
        parse(&mut lines, 1)
    }

    #[test]
    fn positions_follow_chemfiles_choice() {
        let pick = |names: &str| {
            let names: Vec<&[u8]> = names.split(' ').map(str::as_bytes).collect();
            Columns::choose(&names)
        };
        let c = pick("id type x y z xs ys zs xu yu zu").unwrap();
        assert_eq!(
            (c.position, c.scaled),
            ([Some(8), Some(9), Some(10)], false)
        );
        let c = pick("id xs ys zs ix iy iz").unwrap();
        assert_eq!((c.position[0], c.scaled), (Some(1), true));
        assert_eq!(c.images, Some([Some(4), Some(5), Some(6)]));
        let c = pick("id xu yu zu ix iy iz").unwrap();
        assert_eq!(c.images, None);
        assert!(pick("id type vx vy vz").is_none());
    }

    #[test]
    fn headers_read_boxes_and_counts() {
        let text = "ITEM: TIMESTEP\n10\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n\
                    0 10\n-1 19\n0 30\nITEM: ATOMS id type x y z\n";
        let h = header(text).unwrap();
        assert_eq!((h.atoms, h.lines), (2, 9));
        assert_eq!(h.origin, [0.0, -1.0, 0.0]);
        assert_eq!(h.cell.unwrap()[1], Vec3::new(0.0, 20.0, 0.0));
        // A tilted box: bounds of the parallelepiped become xlo, xhi.
        let text = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\n\
                    ITEM: BOX BOUNDS xy xz yz pp pp pp\n-2 12 -2\n0 20 1\n0 30 3\nITEM: ATOMS x y z\n";
        let h = header(text).unwrap();
        assert_eq!(
            h.rows,
            [[11.0, 0.0, 0.0], [-2.0, 17.0, 0.0], [1.0, 3.0, 30.0]]
        );
        assert_eq!(h.origin, [0.0, 0.0, 0.0]);
        assert_eq!(
            header("ITEM: TIMESTEP\n0\n"),
            Err(LammpsError::EndsBefore {
                what: "ITEM: ATOMS"
            })
        );
        assert_eq!(
            header("hello\n"),
            Err(LammpsError::NotAnItem {
                line: 1,
                shown: "hello".into()
            })
        );
        let no_box = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS x y z\n";
        let error = header(no_box).unwrap_err();
        assert_eq!(
            error.to_string(),
            "line 5: ITEM: ATOMS before ITEM: BOX BOUNDS"
        );
        let upside_down = "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\n\
                           ITEM: BOX BOUNDS pp pp pp\n10 0\n0 10\n0 10\nITEM: ATOMS x y z\n";
        assert!(matches!(
            header(upside_down),
            Err(LammpsError::Cell {
                line: 5,
                error: BoxError::NegativeLength(_)
            })
        ));
    }
}
