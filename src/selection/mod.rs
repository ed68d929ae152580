//! Atom selections: a small VMD/MDAnalysis-style language, parsed once into a [`Selection`],
//! bound to a topology once ([`BoundSelection`]: everything that does not depend on positions
//! is evaluated there and cached), and evaluated per frame to sorted 0-based atom indices.
//! The viewer, `render`, `surface` and the command line (`mdsurf select`) share it; the surface
//! engine only ever sees the atoms it yields.
//!
//! # The language
//!
//! - Boolean: `and`, `or`, `not`, parentheses; `not` binds tightest, then `and`, then `or`.
//!   `all` and `none`.
//! - String keywords, each followed by one or more values (any may match): `name`, `type`,
//!   `element` (case-insensitive), `resname`, `chain`, `segname`/`segid`. A value is exact text
//!   (`resname ALA GLY`), a glob with `*`, `?` or `[...]` (`name C*`, `name H?1`), or a regex in
//!   double quotes that must match the whole string (`name "C[AB]"`).
//! - Numeric keywords: `resid` (number in the file), `residue` (0-based residue index),
//!   `index` (0-based atom index), `serial` (1-based file serial, else index + 1), `mass`
//!   (amu), `charge` (e), `beta`/`bfactor` (Å²), `occupancy`, and the coordinates `x`, `y`, `z`
//!   (Å). Values are numbers, inclusive ranges (`resid 10 to 20`, `index 0:99`), or one
//!   comparison (`x > 10`, `mass < 2.0`, `resid >= 5`, `==`, `!=`, `<=`).
//! - Macros: `protein nucleic backbone sidechain water ion lipid hydrogen heavy noh ligand`,
//!   defined in [`macros`] (residue and atom-name lists there).
//! - Per frame: `within D of SEL` (atoms within D Å of SEL, SEL included), `exwithin D of SEL`
//!   (SEL excluded; MDAnalysis's `around`), `same residue as SEL`, `same chain as SEL`,
//!   `same segname as SEL`. These take everything to their right (`within 5 of protein or
//!   water` is `within 5 of (protein or water)`). Distances count periodic images when the
//!   frame has a box.
//!
//! Keywords are lowercase; atom and residue names are matched case-sensitively.

mod ast;
mod bind;
pub(crate) mod macros;
mod parser;
mod within;

use crate::model::{Frame, Topology};

use bind::Node;

/// A parse error: the 1-based column (in characters) of the first bad token and what is wrong.
/// Displays as one line, e.g. `column 12: unknown keyword 'resnam' (did you mean resname?)`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct SelectionError {
    /// 1-based column of the first bad token.
    pub column: usize,
    /// What is wrong, one line.
    pub message: String,
}

/// A parsed selection; see the [module documentation](self) for the language.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    text: String,
    expr: ast::Expr,
}

impl Selection {
    /// Parses `text`; fails with the column of the first bad token.
    pub fn parse(text: &str) -> Result<Selection, SelectionError> {
        let expr = parser::parse(text)?;
        Ok(Selection {
            text: text.to_string(),
            expr,
        })
    }

    /// The text this selection was parsed from.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// True when the selection depends on positions (`within`, `exwithin`, `x`, `y`, `z`, or
    /// `same ... as` of such a part), so it must be evaluated per frame.
    pub fn is_dynamic(&self) -> bool {
        self.expr.is_dynamic()
    }

    /// Binds the selection to `topology`: every part that does not depend on positions is
    /// evaluated here, once.
    pub fn bind(&self, topology: &Topology) -> BoundSelection {
        let root = bind::bind(&self.expr, topology);
        let cached = match &root {
            Node::Mask(mask) => Some((mask.clone(), bind::indices(mask))),
            _ => None,
        };
        BoundSelection {
            atoms: topology.len(),
            root,
            cached,
        }
    }
}

/// A selection bound to one topology; evaluate it per frame with [`BoundSelection::indices`]
/// or [`BoundSelection::mask`]. A selection that does not depend on positions returns its
/// cached result without looking at the frame.
#[derive(Debug, Clone)]
pub struct BoundSelection {
    atoms: usize,
    root: Node,
    /// The mask and indices when the selection is constant.
    cached: Option<(Vec<bool>, Vec<u32>)>,
}

impl BoundSelection {
    /// True when the result depends on the frame's positions.
    pub fn is_dynamic(&self) -> bool {
        self.cached.is_none()
    }

    /// The selected atoms in `frame`: 0-based indices, ascending.
    pub fn indices(&self, frame: &Frame) -> Vec<u32> {
        match &self.cached {
            Some((_, indices)) => indices.clone(),
            None => bind::indices(&self.mask(frame)),
        }
    }

    /// Whether each atom of the topology is selected in `frame` (one entry per atom).
    pub fn mask(&self, frame: &Frame) -> Vec<bool> {
        match &self.cached {
            Some((mask, _)) => mask.clone(),
            None => self.root.eval(frame, &vec![true; self.atoms]),
        }
    }
}

#[cfg(test)]
mod tests;
