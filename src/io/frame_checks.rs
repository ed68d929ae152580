//! The checks every reader's frames pass before anyone uses them, whichever reader read them
//! (ours or chemfiles): finite positions within [`MAX_COORDINATE`].

use std::path::Path;

use glam::Vec3;

use super::IoError;
use crate::surface::scan::first_failing;

/// Coordinates beyond this (Å, in any direction) are damage, not a structure: they would make
/// the density grid empty or astronomically large.
pub(crate) const MAX_COORDINATE: f32 = 1.0e7;

/// Fails on the first NaN, infinite or absurd (beyond [`MAX_COORDINATE`]) position of frame
/// `index` of `path`, naming the frame and the atom.
pub(crate) fn check_positions(
    path: &Path,
    index: usize,
    positions: &[Vec3],
) -> Result<(), IoError> {
    if let Some(atom) = first_failing(positions, |p| p.is_finite()) {
        return Err(IoError::NonFiniteCoordinate {
            path: path.to_path_buf(),
            frame: index,
            atom,
        });
    }
    if let Some(atom) = first_failing(positions, |p| p.abs().max_element() <= MAX_COORDINATE) {
        return Err(IoError::AbsurdCoordinate {
            path: path.to_path_buf(),
            frame: index,
            atom,
            value: positions[atom].abs().max_element(),
        });
    }
    Ok(())
}
