//! An [`Expr`] bound to a topology: every part that does not depend on positions is evaluated
//! once into a mask ([`Node::Mask`]); what is left ([`Node::Coord`], [`Node::Within`], and the
//! boolean and `same ... as` nodes above them) is evaluated per frame by [`Node::eval`].

use std::collections::HashMap;

use regex::Regex;

use super::ast::{Expr, Group, NumField, NumTest, Pattern, StrField};
use super::within::within;
use crate::model::{Frame, Labels, Topology};

/// A bound selection expression.
#[derive(Debug, Clone)]
pub(crate) enum Node {
    /// A constant per-atom mask.
    Mask(Vec<bool>),
    /// Atoms not in the operand.
    Not(Box<Node>),
    /// Atoms in every operand (constant masks first).
    And(Vec<Node>),
    /// Atoms in any operand (constant masks first).
    Or(Vec<Node>),
    /// A coordinate (0 x, 1 y, 2 z) passing any of the tests (Å).
    Coord(usize, Vec<NumTest>),
    /// Atoms within `distance` Å of the operand's atoms (see [`Expr::Within`]).
    Within {
        /// Cutoff in Å.
        distance: f32,
        /// Leave the operand's atoms out.
        exclude: bool,
        /// The operand.
        inner: Box<Node>,
        /// The operand's atoms when it is constant (the usual case: `within 5 of protein`).
        sources: Option<Vec<u32>>,
    },
    /// Whole groups holding an operand atom.
    Same {
        /// Group id of each atom, `0..count`.
        groups: Vec<u32>,
        /// Number of groups.
        count: usize,
        /// The operand.
        inner: Box<Node>,
    },
}

/// A compiled string pattern.
pub(crate) enum Matcher {
    /// Exact text.
    Exact(String),
    /// A whole-string regex (from a glob or a quoted regex).
    Regex(Regex),
}

impl Matcher {
    fn matches(&self, s: &str) -> bool {
        match self {
            Matcher::Exact(e) => e == s,
            Matcher::Regex(r) => r.is_match(s),
        }
    }
}

/// Why a name pattern does not compile; displays as one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum PatternError {
    /// A quoted regex (or a glob turned regex) the regex engine refuses, with its last line of
    /// explanation.
    #[error("bad regex \"{regex}\": {detail}")]
    BadRegex { regex: String, detail: String },
    /// A glob with `[` and no closing `]`.
    #[error("unclosed '[' in '{glob}'")]
    UnclosedClass { glob: String },
}

/// Compiles `pattern`; the error is one line. Elements are matched upper-cased, so their
/// regexes are case-insensitive.
pub(crate) fn compile(pattern: &Pattern, field: StrField) -> Result<Matcher, PatternError> {
    let flags = if field == StrField::Element {
        "(?i)"
    } else {
        ""
    };
    let source = match pattern {
        Pattern::Exact(s) => return Ok(Matcher::Exact(s.clone())),
        Pattern::Glob(g) => glob_to_regex(g)?,
        Pattern::Regex(r) => r.clone(),
    };
    Regex::new(&format!("{flags}^(?:{source})$"))
        .map(Matcher::Regex)
        .map_err(|e| {
            let detail = e.to_string();
            let last = detail.lines().last().unwrap_or("").trim();
            let last = last.strip_prefix("error: ").unwrap_or(last);
            PatternError::BadRegex {
                regex: source,
                detail: last.to_string(),
            }
        })
}

/// A shell glob as a regex body: `*` any run, `?` one character, `[...]` a class (`[!...]`
/// negated); everything else literal.
fn glob_to_regex(glob: &str) -> Result<String, PatternError> {
    let mut out = String::new();
    let mut chars = glob.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '*' => out.push_str(".*"),
            '?' => out.push('.'),
            '[' => {
                let mut class = String::from("[");
                if chars.peek() == Some(&'!') {
                    chars.next();
                    class.push('^');
                }
                let mut closed = false;
                for c in chars.by_ref() {
                    if c == ']' {
                        closed = true;
                        break;
                    }
                    if c == '\\' || c == '[' || c == '^' || c == '&' || c == '~' {
                        class.push('\\');
                    }
                    class.push(c);
                }
                if !closed {
                    return Err(PatternError::UnclosedClass {
                        glob: glob.to_string(),
                    });
                }
                class.push(']');
                out.push_str(&class);
            }
            _ => out.push_str(&regex::escape(&c.to_string())),
        }
    }
    Ok(out)
}

/// The value of string `field` for atom `i` (empty when the topology lacks the field).
fn string_of(topology: &Topology, field: StrField, i: usize) -> &str {
    let v = match field {
        StrField::Name => topology.names.get(i),
        StrField::Type => topology.types.get(i).or(topology.names.get(i)),
        StrField::Element => topology.elements.get(i),
        StrField::ResName => topology.residue_names.get(i),
        StrField::Chain => topology.chains.get(i),
        StrField::Segment => topology.segments.get(i),
    };
    v.unwrap_or("")
}

/// The value of constant numeric `field` for atom `i`, with the topology's defaults.
fn number_of(topology: &Topology, field: NumField, i: usize) -> f64 {
    let f = |v: &[f32], default: f32| v.get(i).copied().unwrap_or(default) as f64;
    match field {
        NumField::ResId => topology.residue_ids.get(i).copied().unwrap_or(0) as f64,
        NumField::Residue => topology.residue_index.get(i).copied().unwrap_or(0) as f64,
        NumField::Index => i as f64,
        NumField::Serial => topology.serials.get(i).copied().unwrap_or(i as i64 + 1) as f64,
        NumField::Mass => f(&topology.masses, 0.0),
        NumField::Charge => f(&topology.charges, 0.0),
        NumField::Beta => f(&topology.b_factors, 0.0),
        NumField::Occupancy => f(&topology.occupancies, 1.0),
        NumField::Coord(_) => f64::NAN,
    }
}

/// Binds `expr` to `topology`.
pub(crate) fn bind(expr: &Expr, topology: &Topology) -> Node {
    let n = topology.len();
    match expr {
        Expr::All => Node::Mask(vec![true; n]),
        Expr::None => Node::Mask(vec![false; n]),
        Expr::Macro(m) => Node::Mask(m.mask(topology)),
        Expr::Strings(field, patterns) => Node::Mask(string_mask(topology, *field, patterns)),
        Expr::Numbers(NumField::Coord(axis), tests) => Node::Coord(*axis, tests.clone()),
        Expr::Numbers(field, tests) => Node::Mask(
            (0..n)
                .map(|i| {
                    let v = number_of(topology, *field, i);
                    tests.iter().any(|t| t.passes(v))
                })
                .collect(),
        ),
        Expr::Not(e) => match bind(e, topology) {
            Node::Mask(m) => Node::Mask(m.into_iter().map(|b| !b).collect()),
            node => Node::Not(Box::new(node)),
        },
        Expr::And(..) | Expr::Or(..) => bind_boolean(expr, topology),
        Expr::Within {
            distance,
            exclude,
            inner,
        } => {
            let inner = bind(inner, topology);
            let sources = match &inner {
                Node::Mask(m) => Some(indices(m)),
                _ => None,
            };
            Node::Within {
                distance: *distance,
                exclude: *exclude,
                inner: Box::new(inner),
                sources,
            }
        }
        Expr::Same(group, inner) => {
            let (groups, count) = group_ids(topology, *group);
            match bind(inner, topology) {
                Node::Mask(m) => Node::Mask(expand_groups(&groups, count, &m, &vec![true; n])),
                inner => Node::Same {
                    groups,
                    count,
                    inner: Box::new(inner),
                },
            }
        }
    }
}

/// Binds a chain of `and` (or of `or`) as one node, its constant operands merged into one mask.
fn bind_boolean(expr: &Expr, topology: &Topology) -> Node {
    let is_and = matches!(expr, Expr::And(..));
    let mut operands = Vec::new();
    flatten(expr, is_and, &mut operands);
    let mut constant: Option<Vec<bool>> = None;
    let mut dynamic = Vec::new();
    for e in operands {
        match bind(e, topology) {
            Node::Mask(m) => match &mut constant {
                None => constant = Some(m),
                Some(c) => c.iter_mut().zip(m).for_each(|(c, m)| {
                    *c = if is_and { *c && m } else { *c || m };
                }),
            },
            node => dynamic.push(node),
        }
    }
    if dynamic.is_empty() {
        return Node::Mask(constant.unwrap_or_else(|| vec![is_and; topology.len()]));
    }
    let mut nodes: Vec<Node> = constant.map(Node::Mask).into_iter().collect();
    nodes.extend(dynamic);
    if is_and {
        Node::And(nodes)
    } else {
        Node::Or(nodes)
    }
}

/// The operands of a chain of `and` (`is_and`) or `or`.
fn flatten<'a>(expr: &'a Expr, is_and: bool, out: &mut Vec<&'a Expr>) {
    match (expr, is_and) {
        (Expr::And(a, b), true) | (Expr::Or(a, b), false) => {
            flatten(a, is_and, out);
            flatten(b, is_and, out);
        }
        _ => out.push(expr),
    }
}

/// Whether each atom's `field` matches any of `patterns`; each distinct string is tested once.
fn string_mask(topology: &Topology, field: StrField, patterns: &[Pattern]) -> Vec<bool> {
    // The parser has compiled every pattern once already, so these cannot fail.
    let matchers: Vec<Matcher> = patterns
        .iter()
        .filter_map(|p| compile(p, field).ok())
        .collect();
    let mut seen: HashMap<&str, bool> = HashMap::new();
    (0..topology.len())
        .map(|i| {
            let s = string_of(topology, field, i);
            *seen.entry(s).or_insert_with(|| {
                let upper;
                let s = if field == StrField::Element {
                    upper = s.to_ascii_uppercase();
                    upper.as_str()
                } else {
                    s
                };
                matchers.iter().any(|m| m.matches(s))
            })
        })
        .collect()
}

/// Group ids `0..count` of every atom for `same GROUP as`.
fn group_ids(topology: &Topology, group: Group) -> (Vec<u32>, usize) {
    let n = topology.len();
    let by_string = |values: &Labels| {
        let mut ids: HashMap<&str, u32> = HashMap::new();
        let groups: Vec<u32> = (0..n)
            .map(|i| {
                let s = values.get(i).unwrap_or("");
                let next = ids.len() as u32;
                *ids.entry(s).or_insert(next)
            })
            .collect();
        (groups, ids.len())
    };
    match group {
        Group::Residue => {
            let groups: Vec<u32> = (0..n)
                .map(|i| topology.residue_index.get(i).copied().unwrap_or(i as u32))
                .collect();
            let count = groups.iter().max().map_or(0, |&m| m as usize + 1);
            (groups, count)
        }
        Group::Chain => by_string(&topology.chains),
        Group::Segment => by_string(&topology.segments),
    }
}

/// Atoms of `domain` whose group holds an atom of `mask`.
fn expand_groups(groups: &[u32], count: usize, mask: &[bool], domain: &[bool]) -> Vec<bool> {
    let mut hit = vec![false; count];
    for (g, _) in groups.iter().zip(mask).filter(|(_, m)| **m) {
        hit[*g as usize] = true;
    }
    groups
        .iter()
        .zip(domain)
        .map(|(g, d)| *d && hit[*g as usize])
        .collect()
}

/// The indices of the set entries of `mask`, ascending.
pub(crate) fn indices(mask: &[bool]) -> Vec<u32> {
    mask.iter()
        .enumerate()
        .filter(|(_, b)| **b)
        .map(|(i, _)| i as u32)
        .collect()
}

impl Node {
    /// The node's atoms among `domain` (entries outside `domain` are false) in `frame`.
    /// Atoms past the end of `frame.positions` fail every position test.
    pub(crate) fn eval(&self, frame: &Frame, domain: &[bool]) -> Vec<bool> {
        let and = |a: &[bool], b: &[bool]| a.iter().zip(b).map(|(a, b)| *a && *b).collect();
        match self {
            Node::Mask(m) => and(domain, m),
            Node::Not(inner) => {
                let inside = inner.eval(frame, domain);
                domain.iter().zip(inside).map(|(d, i)| *d && !i).collect()
            }
            Node::And(nodes) => nodes
                .iter()
                .fold(domain.to_vec(), |acc, node| node.eval(frame, &acc)),
            Node::Or(nodes) => {
                let mut acc = vec![false; domain.len()];
                for node in nodes {
                    let rest: Vec<bool> = domain.iter().zip(&acc).map(|(d, a)| *d && !a).collect();
                    let hit = node.eval(frame, &rest);
                    acc.iter_mut().zip(hit).for_each(|(a, h)| *a |= h);
                }
                acc
            }
            Node::Coord(axis, tests) => domain
                .iter()
                .enumerate()
                .map(|(i, d)| {
                    *d && frame.positions.get(i).is_some_and(|p| {
                        let v = p[*axis] as f64;
                        tests.iter().any(|t| t.passes(v))
                    })
                })
                .collect(),
            Node::Within {
                distance,
                exclude,
                inner,
                sources,
            } => {
                let computed;
                let sources = match sources {
                    Some(s) => s.as_slice(),
                    None => {
                        computed = indices(&inner.eval(frame, &vec![true; domain.len()]));
                        computed.as_slice()
                    }
                };
                let mut targets = domain.to_vec();
                if *exclude {
                    for &s in sources {
                        targets[s as usize] = false;
                    }
                }
                within(
                    &frame.positions,
                    frame.cell.as_ref(),
                    sources,
                    &targets,
                    *distance,
                )
            }
            Node::Same {
                groups,
                count,
                inner,
            } => {
                let mask = inner.eval(frame, &vec![true; domain.len()]);
                expand_groups(groups, *count, &mask, domain)
            }
        }
    }
}
