//! [`TransformedFrames`]: reads frames through a [`TransformChain`] for callers that walk a
//! trajectory in order (the headless commands), keeping the transformed frames a smoothing
//! window still needs so each frame is read and transformed once.

use std::sync::Arc;

use super::smooth::{smooth_frame, window};
use super::{TransformChain, TransformError};
use crate::model::Frame;

/// Transformed (and smoothed) frames of one trajectory, with a small cache.
#[derive(Debug, Clone)]
pub struct TransformedFrames {
    chain: TransformChain,
    len: usize,
    cache: Vec<(usize, Arc<Frame>)>,
}

impl TransformedFrames {
    /// Frames of a trajectory of `len` frames through `chain`.
    pub fn new(chain: TransformChain, len: usize) -> TransformedFrames {
        TransformedFrames {
            chain,
            len,
            cache: Vec::new(),
        }
    }

    /// The chain.
    pub fn chain(&self) -> &TransformChain {
        &self.chain
    }

    /// Frame `index` made whole, centred, fitted and smoothed as the chain says; `raw(i)` reads
    /// frame `i` from the file. With smoothing, the frames of the window are read (each once
    /// while the window slides).
    pub fn read<E>(
        &mut self,
        index: usize,
        mut raw: impl FnMut(usize) -> Result<Frame, E>,
    ) -> Result<Frame, E>
    where
        E: From<TransformError>,
    {
        let k = self.chain.smooth();
        if k == 0 {
            let mut frame = raw(index)?;
            self.chain.apply(&mut frame)?;
            return Ok(frame);
        }
        let keep = window(index, self.len.max(index + 1), k);
        self.cache.retain(|(i, _)| keep.contains(i));
        let (chain, cache) = (&self.chain, &mut self.cache);
        smooth_frame(index, self.len, k, |j| -> Result<Arc<Frame>, E> {
            if let Some((_, f)) = cache.iter().find(|(i, _)| *i == j) {
                return Ok(f.clone());
            }
            let mut frame = raw(j)?;
            chain.apply(&mut frame)?;
            let frame = Arc::new(frame);
            cache.push((j, frame.clone()));
            Ok(frame)
        })
    }
}
