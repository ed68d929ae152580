//! Scenes: what the viewer, `render`, `surface` and the command line share about *which* atoms
//! to show and how, below `app` and `cli`. The surface engine stays a function of (atoms,
//! params) and knows nothing of scenes.
//!
//! - [`selection`]: the atom-selection language, parsed once and evaluated per frame.

pub mod defaults;
pub mod layer;
pub mod representation;
pub mod selection;
pub mod state_file;

pub use selection::{BoundSelection, Selection, SelectionError};
