//! Scenes: what the viewer, `render`, `surface` and the command line share about *which* atoms
//! to show and how, below `app` and `cli`. The surface engine stays a function of (atoms,
//! params) and knows nothing of scenes.
//!
//! - [`selection`]: the atom-selection language, parsed once and evaluated per frame.
//! - [`engine`]: the [`SceneEngine`], the one frame path from a frame to every
//!   representation's particles and surface ([`frame`]: what it returns).

pub mod defaults;
pub mod engine;
pub mod frame;
pub mod layer;
pub mod movie;
pub mod representation;
pub mod selection;
pub mod state_file;

pub use engine::{SceneBackend, SceneEngine};
pub use frame::{LayerResult, ParticleData, RepId, RepRequest, SceneError, SceneFrame};
pub use selection::{BoundSelection, Selection, SelectionError};
