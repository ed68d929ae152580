//! Residue numbers chemfiles can use in an mmCIF file's `_atom_site` loop. chemfiles reads
//! mmCIF files only on the reference path ([`super::open_via_chemfiles`], for tests); our
//! reader ([`super::mmcif`]) numbers residues by the same rules.
//!
//! chemfiles 0.10 numbers a residue by `label_seq_id`, and where that is `.` (waters, ligands,
//! sugars: every atom outside a polymer sequence) by `label_entity_id`. Two things go wrong:
//!
//! - All the waters of a chain share one entity, so they became one residue: `same residue as`
//!   around one water oxygen picked every water of 1gbt (117 atoms), and residue colours, beads
//!   and `resid` saw one residue.
//! - A `label_entity_id` of `?` (files written by other tools, as Biopython's 7CFN) is not a
//!   number, and the whole file failed to open ("invalid CIF residue or entity numeric").
//!
//! So the copy chemfiles reads gives every atom with a `label_seq_id` that is not a number the
//! author's residue number (`auth_seq_id`) as its `label_seq_id`, or its entity number, or 0
//! when neither is a number. Polymer residues keep their `label_seq_id` (author numbers repeat
//! with insertion codes, as 1gbt's 184 and 184A). Atom order, count and positions do not change.
//!
//! A row with fewer values than its loop has columns (a cut file) is found by [`short_row`]:
//! chemfiles would read past its end.

/// `bytes` with the `_atom_site` rows rewritten as the module says, or `None` when no row
/// needs it. Rows whose token count does not match the loop's columns (quoted values with
/// spaces) are left as they are.
pub(crate) fn renumber(bytes: &[u8]) -> Option<Vec<u8>> {
    let lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
    // (line index, rewritten line) of every row that changes.
    let mut changes: Vec<(usize, Vec<u8>)> = Vec::new();
    for_each_row(&lines, |i, width, fields| {
        if let Some(row) = renumbered_row(lines[i], width, fields) {
            changes.push((i, row));
        }
    });
    if changes.is_empty() {
        return None;
    }
    let mut out = Vec::with_capacity(bytes.len() + changes.len() * 4);
    let mut next = changes.into_iter().peekable();
    for (i, line) in lines.iter().enumerate() {
        match next.next_if(|(k, _)| *k == i) {
            Some((_, row)) => out.extend_from_slice(&row),
            None => out.extend_from_slice(line),
        }
    }
    Some(out)
}

/// The first `_atom_site` row with fewer values than its loop has columns, as (line number
/// from 1, values, columns). chemfiles reads past the end of such a row (a segmentation fault
/// on a cut `.cif.gz`), so the file is refused with this instead.
pub(crate) fn short_row(bytes: &[u8]) -> Option<(usize, usize, usize)> {
    let lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
    let mut found = None;
    for_each_row(&lines, |i, width, _| {
        let values = tokens(lines[i]).len();
        if found.is_none() && values < width {
            found = Some((i + 1, values, width));
        }
    });
    found
}

/// Calls `row(line index, column count, fields)` for every row of every `_atom_site` loop of
/// `lines`.
fn for_each_row(lines: &[&[u8]], mut row: impl FnMut(usize, usize, &Fields)) {
    let mut columns: Vec<&[u8]> = Vec::new();
    let mut in_header = false;
    let mut in_rows = false;
    let mut fields = Fields::default();
    for (i, line) in lines.iter().enumerate() {
        let first = line.split(u8::is_ascii_whitespace).find(|t| !t.is_empty());
        let Some(first) = first else {
            continue;
        };
        if first == b"loop_" {
            columns.clear();
            (in_header, in_rows) = (true, false);
            continue;
        }
        if in_header && let Some(name) = first.strip_prefix(b"_atom_site.") {
            columns.push(name);
            continue;
        }
        if in_header && !columns.is_empty() && !first.starts_with(b"_") {
            in_header = false;
            in_rows = true;
            fields = Fields::find(&columns);
        } else if first.starts_with(b"_") || first.starts_with(b"#") || first.starts_with(b"data_")
        {
            (in_header, in_rows) = (false, false);
            columns.clear();
            continue;
        }
        if in_rows {
            row(i, columns.len(), &fields);
        }
    }
}

/// The whitespace-separated values of `line`.
fn tokens(line: &[u8]) -> Vec<&[u8]> {
    line.split(u8::is_ascii_whitespace)
        .filter(|t| !t.is_empty())
        .collect()
}

/// Column positions of the `_atom_site` fields the renumbering reads.
#[derive(Debug, Default)]
struct Fields {
    label_seq: Option<usize>,
    entity: Option<usize>,
    auth_seq: Option<usize>,
}

impl Fields {
    fn find(columns: &[&[u8]]) -> Fields {
        let at = |name: &[u8]| columns.iter().position(|c| *c == name);
        Fields {
            label_seq: at(b"label_seq_id"),
            entity: at(b"label_entity_id"),
            auth_seq: at(b"auth_seq_id"),
        }
    }
}

/// The row `line` with a numeric `label_seq_id`, or `None` when it has one already, has no
/// such column, or does not split into `width` tokens.
fn renumbered_row(line: &[u8], width: usize, fields: &Fields) -> Option<Vec<u8>> {
    let seq = fields.label_seq?;
    let tokens = tokens(line);
    if tokens.len() != width || is_integer(tokens[seq]) {
        return None;
    }
    let number = |column: Option<usize>| column.map(|c| tokens[c]).filter(|t| is_integer(t));
    let new_seq: &[u8] = number(fields.auth_seq)
        .or_else(|| number(fields.entity))
        .unwrap_or(b"0");
    let mut row = Vec::with_capacity(line.len() + 4);
    for (k, token) in tokens.iter().enumerate() {
        if k > 0 {
            row.push(b' ');
        }
        row.extend_from_slice(if k == seq { new_seq } else { token });
    }
    row.push(b'\n');
    Some(row)
}

/// True for an optionally signed decimal integer that fits an i64 (what chemfiles parses).
fn is_integer(token: &[u8]) -> bool {
    std::str::from_utf8(token).is_ok_and(|t| t.parse::<i64>().is_ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "data_x\nloop_\n_atom_site.group_PDB\n_atom_site.id\n\
        _atom_site.label_atom_id\n_atom_site.label_comp_id\n_atom_site.label_asym_id\n\
        _atom_site.label_entity_id\n_atom_site.label_seq_id\n_atom_site.Cartn_x\n\
        _atom_site.Cartn_y\n_atom_site.Cartn_z\n_atom_site.auth_seq_id\n";

    #[test]
    fn waters_get_their_author_numbers_and_polymer_rows_stay() {
        let text = format!(
            "{HEADER}ATOM 1 CA ALA A 1 1 0.0 0.0 0.0 5\n\
             HETATM 2 O HOH B 2 . 1.0 0.0 0.0 301\n\
             HETATM 3 O HOH B 2 . 2.0 0.0 0.0 302\n#\n_cell.length_a 10\n"
        );
        let out = String::from_utf8(renumber(text.as_bytes()).expect("waters renumbered")).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        assert!(
            lines.contains(&"ATOM 1 CA ALA A 1 1 0.0 0.0 0.0 5"),
            "{out}"
        );
        assert!(
            lines.contains(&"HETATM 2 O HOH B 2 301 1.0 0.0 0.0 301"),
            "{out}"
        );
        assert!(
            lines.contains(&"HETATM 3 O HOH B 2 302 2.0 0.0 0.0 302"),
            "{out}"
        );
        assert!(out.ends_with("#\n_cell.length_a 10\n"), "{out}");
        assert_eq!(out.lines().count(), text.lines().count());
    }

    #[test]
    fn unknown_entity_and_author_numbers_fall_back_in_order() {
        let text = format!(
            "{HEADER}HETATM 1 C1 LIG F ? . 0.0 0.0 0.0 401\n\
             HETATM 2 C1 LIG G 7 ? 0.0 0.0 0.0 ?\n\
             HETATM 3 C1 LIG H ? . 0.0 0.0 0.0 .\n"
        );
        let out = String::from_utf8(renumber(text.as_bytes()).expect("renumbered")).unwrap();
        assert!(out.contains("HETATM 1 C1 LIG F ? 401 0.0"), "{out}");
        assert!(out.contains("HETATM 2 C1 LIG G 7 7 0.0"), "{out}");
        assert!(out.contains("HETATM 3 C1 LIG H ? 0 0.0"), "{out}");
    }

    #[test]
    fn a_row_cut_short_is_found_with_its_line() {
        let whole = format!("{HEADER}ATOM 1 CA ALA A 1 1 0.0 0.0 0.0 5\n");
        assert_eq!(short_row(whole.as_bytes()), None);
        let cut = format!("{whole}ATOM 2 CB ALA A 1 1 0.0");
        let line = cut.lines().count();
        assert_eq!(short_row(cut.as_bytes()), Some((line, 8, 11)));
    }

    #[test]
    fn a_file_with_numbered_residues_or_odd_rows_is_left_alone() {
        let numbered = format!("{HEADER}ATOM 1 CA ALA A 1 1 0.0 0.0 0.0 5\n");
        assert_eq!(renumber(numbered.as_bytes()), None);
        // A quoted value with a space: the row does not split into the loop's columns.
        let quoted = format!("{HEADER}HETATM 1 'C 1' LIG F 2 . 0.0 0.0 0.0 401\n");
        assert_eq!(renumber(quoted.as_bytes()), None);
        // Another category's loop with a `label_seq_id` of its own is not touched.
        let other = "data_x\nloop_\n_struct_conn.label_seq_id\n_struct_conn.id\n. 1\n";
        assert_eq!(renumber(other.as_bytes()), None);
    }
}
