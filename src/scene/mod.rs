//! Scenes: what the viewer, `render`, `surface` and the command line share about *which* atoms
//! to show and how, below `app` and `cli`. The surface engine stays a function of (atoms,
//! params) and knows nothing of scenes. Which atoms a representation takes is a
//! [`crate::selection::Selection`], from the top-level selection language.
//!
//! - [`engine`]: the [`SceneEngine`], the one frame path from a frame to every
//!   representation's particles and surface ([`frame`]: what it returns).

pub mod cavity_layer;
pub mod defaults;
pub(crate) mod engine;
pub(crate) mod exposure;
pub(crate) mod frame;
pub mod interface;
pub mod layer;
pub mod movie;
pub mod representation;
mod state_error;
pub mod state_file;

pub use engine::{SceneBackend, SceneEngine};
pub use frame::{LayerResult, ParticleData, RepId, RepRequest, SceneError, SceneFrame};
