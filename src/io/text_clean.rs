//! Text made clean for chemfiles, chunk by chunk (see [`super::prepare`]): in the fixed-column
//! formats every non-ASCII byte becomes `?` (columns stay where they are), in the free formats a
//! byte that is not UTF-8 is read as Latin-1 and written as UTF-8, and a leading UTF-8 byte
//! order mark is dropped in both (chemfiles reads it as part of the first line: an XYZ file's
//! atom count `\u{feff}5547` is not a number).

/// The UTF-8 byte order mark.
pub(crate) const BOM: &[u8] = b"\xEF\xBB\xBF";

/// How the text of a format may be cleaned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TextKind {
    /// Fixed columns: every non-ASCII byte becomes `?` (one byte for one byte).
    Columns,
    /// Whitespace-separated: invalid UTF-8 bytes are read as Latin-1.
    Free,
}

pub(crate) fn text_kind(base: &str) -> Option<TextKind> {
    match base {
        "PDB" | "GRO" => Some(TextKind::Columns),
        "mmCIF" | "XYZ" | "LAMMPS" | "MOL2" => Some(TextKind::Free),
        _ => None,
    }
}

/// Turns bytes into clean text, chunk by chunk (a UTF-8 character may span two chunks).
pub(crate) struct Cleaner {
    kind: TextKind,
    pending: Vec<u8>,
    /// The file's first bytes, held until they say whether it starts with a [`BOM`].
    head: Option<Vec<u8>>,
}

impl Cleaner {
    pub(crate) fn new(kind: TextKind) -> Self {
        Cleaner {
            kind,
            pending: Vec::new(),
            head: Some(Vec::new()),
        }
    }

    /// Cleans `bytes` (the next part of the file) into `out`; `last` flushes what is pending.
    pub(crate) fn push(&mut self, bytes: &[u8], last: bool, out: &mut Vec<u8>) {
        let Some(mut head) = self.head.take() else {
            return self.clean(bytes, last, out);
        };
        head.extend_from_slice(bytes);
        if head.len() < BOM.len() && !last {
            self.head = Some(head);
            return;
        }
        self.clean(head.strip_prefix(BOM).unwrap_or(&head), last, out);
    }

    fn clean(&mut self, bytes: &[u8], last: bool, out: &mut Vec<u8>) {
        match self.kind {
            TextKind::Columns => {
                out.extend(bytes.iter().map(|&b| if b.is_ascii() { b } else { b'?' }));
            }
            TextKind::Free => {
                self.pending.extend_from_slice(bytes);
                let mut rest: &[u8] = &self.pending;
                loop {
                    match std::str::from_utf8(rest) {
                        Ok(s) => {
                            out.extend_from_slice(s.as_bytes());
                            rest = &[];
                            break;
                        }
                        Err(e) => {
                            let valid = e.valid_up_to();
                            out.extend_from_slice(&rest[..valid]);
                            match e.error_len() {
                                Some(bad) => {
                                    for &b in &rest[valid..valid + bad] {
                                        let mut utf8 = [0u8; 4];
                                        out.extend_from_slice(
                                            char::from(b).encode_utf8(&mut utf8).as_bytes(),
                                        );
                                    }
                                    rest = &rest[valid + bad..];
                                }
                                None if last => {
                                    for &b in &rest[valid..] {
                                        let mut utf8 = [0u8; 4];
                                        out.extend_from_slice(
                                            char::from(b).encode_utf8(&mut utf8).as_bytes(),
                                        );
                                    }
                                    rest = &[];
                                    break;
                                }
                                None => {
                                    rest = &rest[valid..];
                                    break;
                                }
                            }
                        }
                    }
                }
                let keep = rest.to_vec();
                self.pending = keep;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clean(kind: TextKind, parts: &[&[u8]]) -> Vec<u8> {
        let mut c = Cleaner::new(kind);
        let mut out = Vec::new();
        for p in parts {
            c.push(p, false, &mut out);
        }
        c.push(&[], true, &mut out);
        out
    }

    #[test]
    fn latin1_becomes_utf8_and_utf8_stays() {
        let out = clean(TextKind::Free, &[b"Prot\xe9ine caf\xc3", b"\xa9 x\xff"]);
        assert_eq!(String::from_utf8(out).unwrap(), "Protéine café xÿ");
    }

    #[test]
    fn a_leading_bom_is_dropped_however_the_file_comes_in_pieces() {
        let whole = clean(TextKind::Free, &[b"\xef\xbb\xbf3\nC 1 2 3\n"]);
        assert_eq!(whole, b"3\nC 1 2 3\n");
        let pieces = clean(
            TextKind::Columns,
            &[b"\xef", b"\xbb", b"\xbfAB\xef\xbb\xbf"],
        );
        assert_eq!(pieces, b"AB???");
        assert_eq!(clean(TextKind::Free, &[b"ab"]), b"ab");
    }

    #[test]
    fn columns_keep_their_width() {
        let out = clean(TextKind::Columns, &[b"AB\xe9C\xc3\xa9"]);
        assert_eq!(out, b"AB?C??");
    }
}
