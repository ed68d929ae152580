//! [`chain_for`]: the transformation chain of an opened trajectory, built the one way the
//! viewer and the commands share: from its first frame (the oldest one a running simulation
//! still holds, when it has pushed frame 0 out already) and, for `--fit-reference topology`,
//! the topology file's own coordinates.

use super::{FitReference, TransformChain, TransformError, TransformOptions};
use crate::io::{self, IoError, Trajectory, read_held};

/// Why [`chain_for`] could not build a chain; each prints as one line naming the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChainSetupError {
    /// The trajectory's first frame cannot be read.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The topology file asked for as the fit reference cannot be read.
    #[error("--fit-reference topology: {0}")]
    FitReference(IoError),
    /// The transformations cannot be set up on this trajectory.
    #[error(transparent)]
    Transform(#[from] TransformError),
}

/// The chain `options` ask for on `trajectory`: its first frame decides the defaults, and the
/// topology file's coordinates are read when the fit needs them.
pub fn chain_for(
    options: &TransformOptions,
    trajectory: &Trajectory,
) -> Result<TransformChain, ChainSetupError> {
    let (_, first) = read_held(0, |i| trajectory.read_frame(i), IoError::oldest_held)?;
    let reference = if options.fit.is_some() && options.fit_reference == FitReference::Topology {
        let frame = io::open(trajectory.topology_path(), None).and_then(|t| t.read_frame(0));
        Some(frame.map_err(ChainSetupError::FitReference)?)
    } else {
        None
    };
    let file = trajectory.path().display().to_string();
    Ok(TransformChain::new(
        options,
        trajectory.topology(),
        &first,
        reference.as_ref(),
        &file,
    )?)
}
