//! The tokens of a CIF file (CIF 1.1 syntax, as PDBx/mmCIF files use it), for [`super::mmcif`].
//!
//! Values are separated by any run of whitespace (spaces, tabs, line breaks, blank lines); a
//! `#` that starts a token starts a comment running to the end of the line. A value is
//! unquoted (`CA`), quoted with `'` or `"` (the quote closes only where whitespace or the end
//! of the line follows it, so `'O5''` is not closed early and `"O5'"` holds `O5'`), or a text
//! field: a line that starts with `;` opens it and the next line that starts with `;` closes
//! it. Unquoted `.` (inapplicable) and `?` (unknown) are told apart from quoted ones. Tags
//! (`_atom_site.id`) and the reserved words `loop_`, `data_NAME`, `save_`, `global_` and
//! `stop_` (any case) are tokens of their own. Each token carries its line (from 1) and
//! whether it is the first token on that line. A quote or text field that is never closed is
//! an error naming its line; no input panics.

/// What a token is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// An unquoted value.
    Value,
    /// A quoted value or a text field (never a tag, reserved word, `.` or `?`).
    Quoted,
    /// An unquoted `?`: the value is unknown.
    Unknown,
    /// An unquoted `.`: the value does not apply.
    Inapplicable,
    /// A data name, `_category.item`.
    Tag,
    /// `loop_`.
    Loop,
    /// `data_NAME`, `save_`, `global_` or `stop_`: ends whatever came before.
    Block,
}

impl Kind {
    /// True for the tokens that are values (of a tag or a loop).
    pub(crate) fn is_value(self) -> bool {
        matches!(
            self,
            Kind::Value | Kind::Quoted | Kind::Unknown | Kind::Inapplicable
        )
    }
}

/// One token: `bytes[start..end]` of the file (a quoted value without its quotes, a text field
/// without its `;` lines' markers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Token {
    pub kind: Kind,
    pub start: usize,
    pub end: usize,
    /// The line it starts on, from 1.
    pub line: usize,
    /// True when no token comes before it on its line.
    pub first_on_line: bool,
}

/// Where a token cannot be read: its line and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LexError {
    pub line: usize,
    pub reason: &'static str,
}

/// The tokens of `bytes`, in order (an iterator of `Result`s: the first error ends it).
pub(crate) struct Lexer<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    /// A token already started on the current line.
    line_has_token: bool,
}

impl<'a> Lexer<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Lexer {
            bytes,
            pos: 0,
            line: 1,
            line_has_token: false,
        }
    }

    /// The next token, `Ok(None)` at the end of the input.
    pub(crate) fn next_token(&mut self) -> Result<Option<Token>, LexError> {
        let bytes = self.bytes;
        loop {
            // Whitespace, line breaks and comments.
            while let Some(&b) = bytes.get(self.pos) {
                match b {
                    b'\n' => {
                        self.line += 1;
                        self.line_has_token = false;
                    }
                    b' ' | b'\t' | b'\r' | b'\x0B' | b'\x0C' => {}
                    _ => break,
                }
                self.pos += 1;
            }
            let Some(&b) = bytes.get(self.pos) else {
                return Ok(None);
            };
            if b == b'#' {
                self.pos =
                    memchr::memchr(b'\n', &bytes[self.pos..]).map_or(bytes.len(), |k| self.pos + k);
                continue;
            }
            let first_on_line = !self.line_has_token;
            self.line_has_token = true;
            let line = self.line;
            let token = |kind, start, end| Token {
                kind,
                start,
                end,
                line,
                first_on_line,
            };
            let at_line_start = self.pos == 0 || bytes[self.pos - 1] == b'\n';
            if b == b';' && at_line_start {
                return self
                    .text_field()
                    .map(|(s, e)| Some(token(Kind::Quoted, s, e)));
            }
            if b == b'\'' || b == b'"' {
                let start = self.pos + 1;
                let mut k = start;
                loop {
                    match bytes.get(k) {
                        None | Some(b'\n') | Some(b'\r') => {
                            return Err(LexError {
                                line,
                                reason: "a quoted value is not closed on its line",
                            });
                        }
                        Some(&q) if q == b && bytes.get(k + 1).is_none_or(|&n| is_space(n)) => {
                            self.pos = k + 1;
                            return Ok(Some(token(Kind::Quoted, start, k)));
                        }
                        Some(_) => k += 1,
                    }
                }
            }
            let start = self.pos;
            let end = bytes[start..]
                .iter()
                .position(|&c| is_space(c))
                .map_or(bytes.len(), |k| start + k);
            self.pos = end;
            return Ok(Some(token(classify(&bytes[start..end]), start, end)));
        }
    }

    /// Reads the text field whose `;` is at `self.pos`; returns its content's range (the rest
    /// of the opening line and the lines up to the closing `;`, without the last line break).
    fn text_field(&mut self) -> Result<(usize, usize), LexError> {
        let bytes = self.bytes;
        let start = self.pos + 1;
        let Some(k) = memchr::memmem::find(&bytes[start..], b"\n;") else {
            return Err(LexError {
                line: self.line,
                reason: "a text field (a line starting with ';') is not closed",
            });
        };
        let close = start + k; // the '\n' before the closing ';'
        self.line += memchr::memchr_iter(b'\n', &bytes[start..=close]).count();
        self.pos = close + 2;
        let end = if close > start && bytes[close - 1] == b'\r' {
            close - 1
        } else {
            close
        };
        Ok((start, end))
    }
}

impl Iterator for Lexer<'_> {
    type Item = Result<Token, LexError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.next_token().transpose()
    }
}

/// CIF whitespace.
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | b'\r' | b'\x0B' | b'\x0C')
}

/// The kind of an unquoted token.
fn classify(text: &[u8]) -> Kind {
    match text {
        b"." => Kind::Inapplicable,
        b"?" => Kind::Unknown,
        [b'_', ..] => Kind::Tag,
        _ if text.eq_ignore_ascii_case(b"loop_") => Kind::Loop,
        _ if starts_with_ignore_case(text, b"data_")
            || starts_with_ignore_case(text, b"save_")
            || text.eq_ignore_ascii_case(b"global_")
            || text.eq_ignore_ascii_case(b"stop_") =>
        {
            Kind::Block
        }
        _ => Kind::Value,
    }
}

/// True when `text` starts with `prefix`, ignoring ASCII case.
pub(crate) fn starts_with_ignore_case(text: &[u8], prefix: &[u8]) -> bool {
    text.len() >= prefix.len() && text[..prefix.len()].eq_ignore_ascii_case(prefix)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (kind, text, line, first on line) of every token of `text`.
    fn lex(text: &str) -> Vec<(Kind, String, usize, bool)> {
        Lexer::new(text.as_bytes())
            .map(|t| {
                let t = t.expect("token");
                let value = text[t.start..t.end].to_string();
                (t.kind, value, t.line, t.first_on_line)
            })
            .collect()
    }

    #[test]
    fn whitespace_of_any_kind_separates_values() {
        let got = lex("loop_\n_a.x\n_a.y\nA\t1\n\n  B \t 2  # comment 'x\r\nC 3");
        let texts: Vec<&str> = got.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(
            texts,
            ["loop_", "_a.x", "_a.y", "A", "1", "B", "2", "C", "3"]
        );
        assert_eq!(got[0].0, Kind::Loop);
        assert_eq!(got[1].0, Kind::Tag);
        assert_eq!(got[3].0, Kind::Value);
        let lines: Vec<(usize, bool)> = got.iter().map(|t| (t.2, t.3)).collect();
        assert_eq!(
            lines,
            [
                (1, true),
                (2, true),
                (3, true),
                (4, true),
                (4, false),
                (6, true),
                (6, false),
                (7, true),
                (7, false)
            ]
        );
    }

    #[test]
    fn quotes_close_only_before_whitespace() {
        let got = lex("'O5''  \"O5'\" 'a b' \"x\"y\" ''\n. ? '.' '?'");
        let texts: Vec<&str> = got.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(texts, ["O5'", "O5'", "a b", "x\"y", "", ".", "?", ".", "?"]);
        let kinds: Vec<Kind> = got.iter().map(|t| t.0).collect();
        assert_eq!(kinds[5], Kind::Inapplicable);
        assert_eq!(kinds[6], Kind::Unknown);
        assert_eq!(kinds[7], Kind::Quoted);
        assert_eq!(kinds[8], Kind::Quoted);
    }

    #[test]
    fn text_fields_span_lines() {
        let got = lex("_x.t\n;first line\nsecond; line\n;\nA B\n;x\r\n;C");
        assert_eq!(got[1].1, "first line\nsecond; line");
        assert_eq!(got[1].0, Kind::Quoted);
        assert_eq!((got[1].2, got[2].2), (2, 5));
        assert_eq!(got[2].1, "A");
        assert_eq!(got[4].1, "x");
        assert_eq!(got[5], (Kind::Value, "C".to_string(), 7, false));
        // A ';' that does not start a line is an ordinary character.
        assert_eq!(lex("a ;b")[1].1, ";b");
    }

    #[test]
    fn reserved_words_and_errors() {
        let kinds: Vec<Kind> = lex("data_1ABC LOOP_ save_ Global_ stop_ loop_x _Atom_Site.ID")
            .iter()
            .map(|t| t.0)
            .collect();
        use Kind::*;
        assert_eq!(kinds, [Block, Loop, Block, Block, Block, Value, Tag]);
        let open_quote = Lexer::new(b"a\n'not closed\nb").collect::<Result<Vec<_>, _>>();
        assert_eq!(open_quote.unwrap_err().line, 2);
        let open_field = Lexer::new(b"a\nb\n;text\nmore").collect::<Result<Vec<_>, _>>();
        assert_eq!(open_field.unwrap_err().line, 3);
        assert!(lex("").is_empty());
        assert!(lex("  # only a comment").is_empty());
    }
}
