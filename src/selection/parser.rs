//! Text to [`Expr`]: a `peg` grammar for the selection language, and one-line errors naming the
//! 1-based column of the first bad token.
//!
//! Syntax errors come from peg (the furthest point the grammar could reach); meaning errors
//! (an unknown keyword, a name where a number belongs, a bad regex) are noted by the grammar's
//! actions as they match, with their position. The earliest of all is reported.

use std::cell::RefCell;

use super::SelectionError;
use super::ast::{CmpOp, Expr, Group, NumField, NumTest, Pattern, StrField};
use super::macros::{Keyword, Macro, keyword, suggest};

/// Words that end a value list or cannot name a keyword.
const RESERVED: [&str; 11] = [
    "and", "or", "not", "to", "of", "as", "within", "exwithin", "same", "all", "none",
];

/// Meaning errors noted while parsing: the earliest (byte offset, message).
#[derive(Default)]
pub(crate) struct Notes {
    first: RefCell<Option<(usize, String)>>,
}

impl Notes {
    /// Notes `message` at byte offset `pos`, keeping the earliest.
    fn add(&self, pos: usize, message: String) {
        let mut first = self.first.borrow_mut();
        if first.as_ref().is_none_or(|(p, _)| pos < *p) {
            *first = Some((pos, message));
        }
    }
}

/// One value after a keyword, as written.
#[derive(Debug, Clone)]
pub(crate) struct Value<'a> {
    /// Byte offset of the value in the selection.
    pos: usize,
    /// The text (without quotes).
    text: &'a str,
    /// The upper end of `A to B`.
    to: Option<&'a str>,
    /// True when written in double quotes (a regex).
    quoted: bool,
}

peg::parser! {
    grammar grammar(notes: &Notes) for str {
        rule ws() = quiet!{[' ' | '\t' | '\n' | '\r']}
        rule _() = ws()*
        rule __() = ws()+
        rule word() -> &'input str
            = $(['a'..='z' | 'A'..='Z' | '_'] ['a'..='z' | 'A'..='Z' | '0'..='9' | '_']*)
        rule kw(k: &'static str) = quiet!{ w:word() {? if w == k { Ok(()) } else { Err(k) } } }
            / expected!(k)
        rule name_word() -> &'input str
            = w:word() {? if RESERVED.contains(&w) { Err("a keyword") } else { Ok(w) } }

        pub rule selection() -> Expr = _ e:or_expr() _ end() { e }
        rule end() = quiet!{ ![_] } / expected!("end of selection")

        rule or_expr() -> Expr = h:and_expr() t:(_ kw("or") _ e:and_expr() { e })* {
            t.into_iter().fold(h, |a, b| Expr::Or(Box::new(a), Box::new(b)))
        }
        rule and_expr() -> Expr = h:unary() t:(_ kw("and") _ e:unary() { e })* {
            t.into_iter().fold(h, |a, b| Expr::And(Box::new(a), Box::new(b)))
        }
        rule unary() -> Expr
            = kw("not") _ e:unary() { Expr::Not(Box::new(e)) }
            / exclude:within_word() __ d:distance() __ kw("of") _ e:or_expr() {
                Expr::Within { distance: d, exclude, inner: Box::new(e) }
            }
            / kw("same") __ g:group() __ kw("as") _ e:or_expr() { Expr::Same(g, Box::new(e)) }
            / primary()
        rule within_word() -> bool = kw("within") { false } / kw("exwithin") { true }
        rule distance() -> f32
            = p:position!() t:$(quiet!{['0'..='9' | '.' | '-' | '+' | 'e' | 'E']+}) {
                match t.parse::<f32>() {
                    Ok(d) if d.is_finite() && d >= 0.0 => d,
                    _ => {
                        notes.add(p, format!("bad distance '{t}' (a number of Å, 0 or more)"));
                        0.0
                    }
                }
            }
            / expected!("a distance in Å")
        rule group() -> Group
            = kw("residue") { Group::Residue }
            / kw("chain") { Group::Chain }
            / (kw("segname") / kw("segid")) { Group::Segment }

        rule primary() -> Expr
            = "(" _ e:or_expr() _ ")" { e }
            / kw("all") { Expr::All }
            / kw("none") { Expr::None }
            / w:quiet!{ w:word() {? Macro::from_word(w).ok_or("macro") } } { Expr::Macro(w) }
            / p:position!() w:name_word() _ o:cmp_op() _ v:value() {
                compare(notes, p, w, o, &v)
            }
            / p:position!() w:name_word() vs:(__ v:value() { v })+ { values(notes, p, w, &vs) }
            / p:position!() w:name_word() { values(notes, p, w, &[]) }

        rule cmp_op() -> CmpOp
            = o:$("<=" / ">=" / "==" / "!=" / "<" / ">" / "=") {? CmpOp::parse(o).ok_or("operator") }

        rule value() -> Value<'input>
            = p:position!() "\"" t:$([^'"']*) "\"" {
                Value { pos: p, text: t, to: None, quoted: true }
            }
            / p:position!() "\"" [^'"']* ![_] {
                notes.add(p, "unterminated quote".to_string());
                Value { pos: p, text: "", to: None, quoted: true }
            }
            / p:position!() a:bare() __ kw("to") _ b:bare() {
                Value { pos: p, text: a, to: Some(b), quoted: false }
            }
            / p:position!() a:bare() { Value { pos: p, text: a, to: None, quoted: false } }
        rule bare() -> &'input str
            = quiet!{ t:$((!(ws() / ['(' | ')' | '"']) [_])+) {?
                if RESERVED.contains(&t) { Err("a value") } else { Ok(t) }
            } }
            / expected!("a value")
    }
}

/// Parses `text` into an expression, or the first error.
pub(crate) fn parse(text: &str) -> Result<Expr, SelectionError> {
    let notes = Notes::default();
    let parsed = grammar::selection(text, &notes);
    let mut first = notes.first.into_inner();
    if let Err(e) = &parsed {
        let pos = e.location.offset;
        if first.as_ref().is_none_or(|(p, _)| pos < *p) {
            first = Some((pos, syntax_message(text, pos, e.expected.tokens())));
        }
    }
    match (parsed, first) {
        (Ok(expr), None) => Ok(expr),
        (_, Some((pos, message))) => Err(SelectionError {
            column: text[..pos].chars().count() + 1,
            message,
        }),
        (Err(_), None) => unreachable!("a failed parse always notes an error"),
    }
}

/// "unexpected 'TOKEN' (expected A or B)" for a syntax error at byte `pos`.
fn syntax_message<'a>(text: &str, pos: usize, expected: impl Iterator<Item = &'a str>) -> String {
    let rest = &text[pos..];
    let found = if rest.trim().is_empty() {
        "end of selection".to_string()
    } else {
        let first = rest.chars().next().unwrap_or(' ');
        let token: String = if "()\"".contains(first) {
            first.to_string()
        } else {
            rest.chars()
                .take_while(|c| !c.is_whitespace() && !"()\"".contains(*c))
                .collect()
        };
        format!("'{token}'")
    };
    let mut wanted: Vec<String> = expected.map(|t| t.trim_matches('"').to_string()).collect();
    wanted.sort();
    wanted.dedup();
    match wanted.len() {
        1..=4 => {
            let list = match wanted.split_last() {
                Some((last, [])) => last.clone(),
                Some((last, init)) => format!("{} or {last}", init.join(", ")),
                None => String::new(),
            };
            format!("unexpected {found} (expected {list})")
        }
        _ => format!("unexpected {found}"),
    }
}

/// An unknown keyword's message, with the nearest known word when there is one.
fn unknown(word: &str) -> String {
    match suggest(word) {
        Some(s) => format!("unknown keyword '{word}' (did you mean {s}?)"),
        None => format!("unknown keyword '{word}'"),
    }
}

/// `KEYWORD OP VALUE`.
fn compare(notes: &Notes, pos: usize, word: &str, op: CmpOp, value: &Value) -> Expr {
    match keyword(word) {
        None => notes.add(pos, unknown(word)),
        Some(Keyword::Str(_)) => notes.add(
            pos,
            format!("'{word}' takes names, not comparisons (numeric keywords compare)"),
        ),
        Some(Keyword::Num(field)) => {
            if let Some(v) = number(notes, field, word, value.pos, value.text)
                && value.to.is_none()
                && !value.quoted
            {
                return Expr::Numbers(field, vec![NumTest::Compare(op, v)]);
            }
            if value.to.is_some() || value.quoted {
                notes.add(value.pos, format!("'{word}' compares with one number"));
            }
        }
    }
    Expr::None
}

/// `KEYWORD VALUE...`.
fn values(notes: &Notes, pos: usize, word: &str, values: &[Value]) -> Expr {
    let Some(kind) = keyword(word) else {
        notes.add(pos, unknown(word));
        return Expr::None;
    };
    if values.is_empty() {
        notes.add(pos, format!("keyword '{word}' needs a value"));
        return Expr::None;
    }
    match kind {
        Keyword::Str(field) => {
            let patterns = values
                .iter()
                .filter_map(|v| pattern(notes, field, word, v))
                .collect();
            Expr::Strings(field, patterns)
        }
        Keyword::Num(field) => {
            let mut tests = Vec::new();
            for v in values {
                if v.quoted {
                    notes.add(v.pos, format!("'{word}' takes numbers, not a regex"));
                    continue;
                }
                let test = match v.to {
                    Some(to) => {
                        let a = number(notes, field, word, v.pos, v.text);
                        let b = number(notes, field, word, v.pos, to);
                        a.zip(b).map(|(a, b)| NumTest::Range(a, b))
                    }
                    None => match v.text.split_once(':') {
                        Some((a, b)) => {
                            let a = number(notes, field, word, v.pos, a);
                            let b = number(notes, field, word, v.pos, b);
                            a.zip(b).map(|(a, b)| NumTest::Range(a, b))
                        }
                        None => number(notes, field, word, v.pos, v.text).map(NumTest::Equal),
                    },
                };
                tests.extend(test);
            }
            Expr::Numbers(field, tests)
        }
    }
}

/// A number for `field`, rounded to `f32` for single-precision fields; notes an error if not.
fn number(notes: &Notes, field: NumField, word: &str, pos: usize, text: &str) -> Option<f64> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Some(if field.is_f32() { v as f32 as f64 } else { v }),
        _ => {
            notes.add(
                pos,
                format!("'{text}' is not a number ('{word}' takes numbers)"),
            );
            None
        }
    }
}

/// A string value's pattern; a regex or glob is checked to compile.
fn pattern(notes: &Notes, field: StrField, word: &str, v: &Value) -> Option<Pattern> {
    if v.to.is_some() {
        notes.add(v.pos, format!("'{word}' takes names, not ranges"));
        return None;
    }
    let element = |s: &str| {
        if field == StrField::Element {
            s.to_ascii_uppercase()
        } else {
            s.to_string()
        }
    };
    let pattern = if v.quoted {
        Pattern::Regex(v.text.to_string())
    } else if v.text.contains(['*', '?', '[']) {
        Pattern::Glob(element(v.text))
    } else {
        return Some(Pattern::Exact(element(v.text)));
    };
    match super::bind::compile(&pattern, field) {
        Ok(_) => Some(pattern),
        Err(e) => {
            notes.add(v.pos, e.to_string());
            None
        }
    }
}
