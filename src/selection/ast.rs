//! The parsed form of a selection: what [`parser`](super::parser) builds and
//! [`bind`](super::bind) evaluates against a topology. Plain data (no compiled regexes), so a
//! [`Selection`](super::Selection) can be compared and cloned cheaply.

use super::macros::Macro;

/// A selection expression.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Expr {
    /// Every atom.
    All,
    /// No atom.
    None,
    /// A named atom class (`protein`, `water`, ...).
    Macro(Macro),
    /// Atoms not in the operand.
    Not(Box<Expr>),
    /// Atoms in both operands.
    And(Box<Expr>, Box<Expr>),
    /// Atoms in either operand.
    Or(Box<Expr>, Box<Expr>),
    /// A string keyword matching any of its patterns (`name CA CB`, `resname "AL."`).
    Strings(StrField, Vec<Pattern>),
    /// A numeric keyword passing any of its tests (`resid 1 5 to 9`, `x > 10`).
    Numbers(NumField, Vec<NumTest>),
    /// Atoms within `distance` Å of the operand's atoms (periodic images included when the
    /// frame has a box); with `exclude`, the operand's own atoms are left out (`exwithin`).
    Within {
        /// Cutoff distance in Å (inclusive).
        distance: f32,
        /// True for `exwithin`.
        exclude: bool,
        /// The atoms distances are measured to.
        inner: Box<Expr>,
    },
    /// Every atom of each group (residue, chain, segment) that holds an operand atom.
    Same(Group, Box<Expr>),
}

/// A per-atom string property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StrField {
    /// Atom name (`name`).
    Name,
    /// Atom type (`type`).
    Type,
    /// Element symbol (`element`, matched case-insensitively).
    Element,
    /// Residue name (`resname`).
    ResName,
    /// Chain identifier (`chain`).
    Chain,
    /// Segment name (`segname`, `segid`).
    Segment,
}

/// A per-atom number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NumField {
    /// Residue number as written in the file (`resid`).
    ResId,
    /// 0-based residue index in file order (`residue`).
    Residue,
    /// 0-based atom index (`index`).
    Index,
    /// 1-based serial number from the file, else index + 1 (`serial`).
    Serial,
    /// Mass in amu (`mass`).
    Mass,
    /// Partial charge in e (`charge`).
    Charge,
    /// Temperature factor in Å² (`beta`, `bfactor`).
    Beta,
    /// Occupancy (`occupancy`).
    Occupancy,
    /// Cartesian coordinate in Å (`x`, `y`, `z`: 0, 1, 2); changes from frame to frame.
    Coord(usize),
}

impl NumField {
    /// True for the integer keywords (whose values must be whole numbers).
    pub(crate) fn is_integer(self) -> bool {
        matches!(
            self,
            NumField::ResId | NumField::Residue | NumField::Index | NumField::Serial
        )
    }

    /// True for single-precision fields, whose literals are rounded to `f32` before comparing.
    pub(crate) fn is_f32(self) -> bool {
        !self.is_integer()
    }
}

/// How a string value matches.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Pattern {
    /// The whole string, exactly.
    Exact(String),
    /// A shell glob: `*` any run, `?` one character, `[...]` a character class.
    Glob(String),
    /// A regular expression that must match the whole string (written in double quotes).
    Regex(String),
}

/// One test of a numeric keyword.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NumTest {
    /// Equal to the value.
    Equal(f64),
    /// Between the two values, both included (`10 to 20`, `10:20`).
    Range(f64, f64),
    /// A comparison with the value on the right (`x > 10`).
    Compare(CmpOp, f64),
}

impl NumTest {
    /// True when `v` passes.
    #[inline]
    pub(crate) fn passes(self, v: f64) -> bool {
        match self {
            NumTest::Equal(a) => v == a,
            NumTest::Range(a, b) => a <= v && v <= b,
            NumTest::Compare(op, a) => op.holds(v, a),
        }
    }
}

/// A comparison operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CmpOp {
    /// `<`
    Less,
    /// `<=`
    LessEq,
    /// `>`
    Greater,
    /// `>=`
    GreaterEq,
    /// `==` or `=`
    Equal,
    /// `!=`
    NotEqual,
}

impl CmpOp {
    /// Parses an operator token.
    pub(crate) fn parse(op: &str) -> Option<CmpOp> {
        Some(match op {
            "<" => CmpOp::Less,
            "<=" => CmpOp::LessEq,
            ">" => CmpOp::Greater,
            ">=" => CmpOp::GreaterEq,
            "==" | "=" => CmpOp::Equal,
            "!=" => CmpOp::NotEqual,
            _ => return None,
        })
    }

    /// `v OP a`.
    #[inline]
    pub(crate) fn holds(self, v: f64, a: f64) -> bool {
        match self {
            CmpOp::Less => v < a,
            CmpOp::LessEq => v <= a,
            CmpOp::Greater => v > a,
            CmpOp::GreaterEq => v >= a,
            CmpOp::Equal => v == a,
            CmpOp::NotEqual => v != a,
        }
    }
}

/// What `same ... as` groups atoms by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Group {
    /// Residues ([`Topology::residue_index`](crate::model::Topology::residue_index)).
    Residue,
    /// Chains.
    Chain,
    /// Segments.
    Segment,
}

impl Expr {
    /// True when the expression depends on positions (`within`, `exwithin`, `x`, `y`, `z`, or
    /// `same ... as` of such an expression).
    pub(crate) fn is_dynamic(&self) -> bool {
        match self {
            Expr::All | Expr::None | Expr::Macro(_) | Expr::Strings(..) => false,
            Expr::Numbers(field, _) => matches!(field, NumField::Coord(_)),
            Expr::Not(e) | Expr::Same(_, e) => e.is_dynamic(),
            Expr::And(a, b) | Expr::Or(a, b) => a.is_dynamic() || b.is_dynamic(),
            Expr::Within { .. } => true,
        }
    }
}
