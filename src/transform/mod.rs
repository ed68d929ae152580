//! Per-frame transformations between the reader and the surface engine, in this order, each
//! optional: make molecules whole across the periodic box ([`whole`]), centre a selection in
//! the box with molecules wrapped around it ([`center`]), fit a selection onto a reference
//! frame ([`fit`]), and average positions over neighbouring frames ([`smooth`]).
//!
//! A [`TransformChain`] is built once per trajectory from [`TransformOptions`], the topology and
//! the first frame ([`chain_for`] does it for an opened trajectory); [`TransformChain::apply`] runs the first three steps on one frame. Smoothing
//! needs neighbouring frames, so whoever reads frames does it with [`smooth::smooth_frame`]
//! (the viewer's frame streamer caches transformed frames; the command line uses
//! [`reader::TransformedFrames`]).

pub(crate) mod center;
pub(crate) mod fit;
pub(crate) mod reader;
#[cfg(feature = "readers")]
pub(crate) mod setup;
pub mod smooth;
pub(crate) mod whole;

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

pub use crate::model::pbc::PbcCell;
use crate::model::{Frame, Topology};
use crate::selection::{BoundSelection, Selection, SelectionError};
pub use crate::surface::periodic::Replicate;
pub use reader::TransformedFrames;
#[cfg(feature = "readers")]
pub use setup::{ChainSetupError, chain_for};
pub use whole::{Connectivity, Molecules};

/// The widest smoothing window half-width, in frames.
pub const MAX_SMOOTH: usize = 50;

/// Which frame `--fit` superposes every frame on.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitReference {
    /// The trajectory's first frame (after making whole and centring).
    #[default]
    First,
    /// The coordinates in the topology file.
    Topology,
}

impl FromStr for FitReference {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "first" => Ok(FitReference::First),
            "topology" | "top" => Ok(FitReference::Topology),
            _ => Err(format!(
                "bad fit reference '{s}': expected first or topology"
            )),
        }
    }
}

impl fmt::Display for FitReference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FitReference::First => "first",
            FitReference::Topology => "topology",
        })
    }
}

/// Which transformations run. The default makes molecules whole when the file has a box and
/// connectivity, and does nothing else.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransformOptions {
    /// Make molecules whole: `Some(true)` on (a file without a box is an error), `Some(false)`
    /// off, `None` on when the file has a box and bonds or residues.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub whole: Option<bool>,
    /// Selection whose centre is put at the box centre (molecules wrapped around it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub center: Option<String>,
    /// Selection fitted (least squares) onto the reference frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<String>,
    /// The frame `fit` superposes on.
    pub fit_reference: FitReference,
    /// Half-width of the smoothing window in frames (0: no smoothing).
    pub smooth: usize,
    /// Periodic density: Gaussians reach across the box faces and the mesh is the surface in
    /// one box ([`crate::surface::periodic`]); needs an orthorhombic box.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub periodic: bool,
    /// Images of the box shown side by side along x, y, z with `periodic` (1,1,1: one box).
    #[serde(skip_serializing_if = "Replicate::is_one")]
    pub replicate: Replicate,
}

/// Which step a message is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Making molecules whole.
    Whole,
    /// Centring.
    Center,
    /// Fitting.
    Fit,
    /// Smoothing.
    Smooth,
    /// Periodic density.
    Periodic,
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Step::Whole => "--whole",
            Step::Center => "--center",
            Step::Fit => "--fit",
            Step::Smooth => "--smooth",
            Step::Periodic => "--periodic",
        })
    }
}

/// Why transformations could not be set up or applied; each prints as one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// A step that needs a periodic box on a file without one.
    #[error("{file}: {step} needs a periodic box, and the file has none")]
    NoBox {
        /// The file frames come from.
        file: String,
        /// The step.
        step: Step,
    },
    /// A selection that does not parse.
    #[error("{step} '{text}': {error}")]
    BadSelection {
        /// The step.
        step: Step,
        /// The selection as given.
        text: String,
        /// The parse error.
        error: SelectionError,
    },
    /// A selection that matches no atom.
    #[error("{step} '{text}' matches no atom in {file}")]
    EmptySelection {
        /// The step.
        step: Step,
        /// The selection as given.
        text: String,
        /// The file.
        file: String,
    },
    /// The reference frame cannot be used.
    #[error("{file}: --fit reference: {reason}")]
    BadReference {
        /// The reference file.
        file: String,
        /// Why.
        reason: String,
    },
    /// A smoothing window too wide.
    #[error("--smooth {k}: at most {MAX_SMOOTH} frames each side")]
    SmoothTooWide {
        /// The half-width asked for.
        k: usize,
    },
    /// A box `--periodic` cannot use (too small or flat).
    #[error("{file}: --periodic: {reason}")]
    BadBox {
        /// The file.
        file: String,
        /// Why, naming the cell.
        reason: String,
    },
    /// A `--replicate` value out of range.
    #[error(transparent)]
    BadReplicate(#[from] crate::surface::periodic::ReplicateError),
    /// `--periodic` with `--fit`, which rotates the box.
    #[error("{file}: --periodic cannot be combined with --fit (fitting rotates the periodic box)")]
    PeriodicWithFit {
        /// The file.
        file: String,
    },
    /// One frame cannot be transformed.
    #[error("{file}: frame {frame}: {reason}")]
    Frame {
        /// The file.
        file: String,
        /// The frame.
        frame: usize,
        /// Why.
        reason: String,
    },
}

impl TransformError {
    /// The message without the file and frame (for callers that add them).
    pub fn reason(&self) -> String {
        match self {
            TransformError::Frame { reason, .. } => reason.clone(),
            other => other.to_string(),
        }
    }

    /// This error as one frame's failure, displayed without the file and frame (for the
    /// frame streamer, which adds them).
    pub fn at_frame(self) -> FrameFailure {
        FrameFailure(self)
    }
}

/// A [`TransformError`] displayed as [`TransformError::reason`]: what went wrong with one
/// frame, for a caller that names the file and frame itself.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", .0.reason())]
pub struct FrameFailure(pub TransformError);

/// The centring step.
#[derive(Debug, Clone)]
struct Centre {
    text: String,
    selection: BoundSelection,
}

/// Whole, centre and fit for one trajectory, built once; cheap to clone and shareable
/// between threads.
#[derive(Debug, Clone)]
pub struct TransformChain {
    file: String,
    molecules: Option<Arc<Molecules>>,
    whole: bool,
    masses: Arc<Vec<f32>>,
    centre: Option<Arc<Centre>>,
    fit: Option<Arc<fit::Fit>>,
    fit_text: String,
    fit_reference: FitReference,
    smooth: usize,
    /// Periodic density and the images shown (`None`: off).
    periodic: Option<Replicate>,
}

impl TransformChain {
    /// The chain for a trajectory read from `file` (named in messages) with `topology`;
    /// `first` is its first frame (it decides the defaults, the guessed bonds and, unless
    /// `reference` is given, the fit reference). `reference` is the frame to fit onto when
    /// `options.fit_reference` is [`FitReference::Topology`] (the topology's coordinates).
    pub fn new(
        options: &TransformOptions,
        topology: &Topology,
        first: &Frame,
        reference: Option<&Frame>,
        file: &str,
    ) -> Result<TransformChain, TransformError> {
        let file = file.to_string();
        if options.smooth > MAX_SMOOTH {
            return Err(TransformError::SmoothTooWide { k: options.smooth });
        }
        let has_box = PbcCell::of(first).is_some();
        let no_box = |step| TransformError::NoBox {
            file: file.clone(),
            step,
        };
        if options.whole == Some(true) && !has_box {
            return Err(no_box(Step::Whole));
        }
        if options.center.is_some() && !has_box {
            return Err(no_box(Step::Center));
        }
        if options.periodic {
            options
                .replicate
                .validate()
                .map_err(TransformError::BadReplicate)?;
            let Some(rows) = first.cell.as_ref() else {
                return Err(no_box(Step::Periodic));
            };
            crate::surface::periodic::PeriodicCell::from_cell(rows).map_err(|e| {
                TransformError::BadBox {
                    file: file.clone(),
                    reason: e.to_string(),
                }
            })?;
            if options.fit.is_some() {
                return Err(TransformError::PeriodicWithFit { file: file.clone() });
            }
        }
        let parse = |step, text: &str| {
            Selection::parse(text).map_err(|error| TransformError::BadSelection {
                step,
                text: text.to_string(),
                error,
            })
        };
        let centre_sel = options
            .center
            .as_deref()
            .map(|t| parse(Step::Center, t))
            .transpose()?;
        let fit_sel = options
            .fit
            .as_deref()
            .map(|t| parse(Step::Fit, t))
            .transpose()?;
        let molecules = has_box.then(|| Arc::new(Molecules::new(topology, first)));
        let whole = match options.whole {
            Some(w) => w,
            None => molecules.as_ref().is_some_and(|m| m.has_links()),
        };
        let mut masses = topology.masses.clone();
        if masses.len() != topology.len() {
            masses.clear();
        }
        let mut chain = TransformChain {
            file,
            molecules,
            whole,
            masses: Arc::new(masses),
            centre: None,
            fit: None,
            fit_text: String::new(),
            fit_reference: options.fit_reference,
            smooth: options.smooth,
            periodic: options.periodic.then_some(options.replicate),
        };
        if let Some(sel) = centre_sel {
            let selection = sel.bind(topology);
            chain.centre = Some(Arc::new(Centre {
                text: sel.text().to_string(),
                selection,
            }));
            // A selection that matches nothing in the first frame is an error now.
            let mut probe = first.clone();
            chain.apply(&mut probe).map_err(|e| match e {
                TransformError::Frame { .. } => TransformError::EmptySelection {
                    step: Step::Center,
                    text: sel.text().to_string(),
                    file: chain.file.clone(),
                },
                other => other,
            })?;
        }
        if let Some(sel) = fit_sel {
            let mut reference = match (options.fit_reference, reference) {
                (FitReference::Topology, Some(r)) => r.clone(),
                _ => first.clone(),
            };
            if reference.positions.len() != topology.len() {
                return Err(TransformError::BadReference {
                    file: chain.file.clone(),
                    reason: format!(
                        "it has {} atoms, the topology {}",
                        reference.positions.len(),
                        topology.len()
                    ),
                });
            }
            if reference.cell.is_none() {
                reference.cell = first.cell;
            }
            chain.apply(&mut reference)?;
            let indices = sel.bind(topology).indices(&reference);
            let fit =
                fit::Fit::new(indices, &reference.positions, &chain.masses).ok_or_else(|| {
                    TransformError::EmptySelection {
                        step: Step::Fit,
                        text: sel.text().to_string(),
                        file: chain.file.clone(),
                    }
                })?;
            chain.fit = Some(Arc::new(fit));
            chain.fit_text = sel.text().to_string();
        }
        Ok(chain)
    }

    /// A chain that changes nothing.
    pub fn identity() -> TransformChain {
        TransformChain {
            file: String::new(),
            molecules: None,
            whole: false,
            masses: Arc::new(Vec::new()),
            centre: None,
            fit: None,
            fit_text: String::new(),
            fit_reference: FitReference::First,
            smooth: 0,
            periodic: None,
        }
    }

    /// True when [`TransformChain::apply`] changes nothing and there is no smoothing.
    pub fn is_identity(&self) -> bool {
        !self.whole
            && self.centre.is_none()
            && self.fit.is_none()
            && self.smooth == 0
            && self.periodic.is_none()
    }

    /// The images shown side by side when the surface is periodic (`--periodic`), else `None`.
    pub fn periodic(&self) -> Option<Replicate> {
        self.periodic
    }

    /// True when molecules are made whole.
    pub fn whole(&self) -> bool {
        self.whole
    }

    /// The molecules (when the file has a box).
    pub fn molecules(&self) -> Option<&Molecules> {
        self.molecules.as_deref()
    }

    /// Half-width of the smoothing window in frames.
    pub fn smooth(&self) -> usize {
        self.smooth
    }

    /// Makes whole, centres and fits `frame`, as the options ask. Fails (one line, naming
    /// the file and frame) when a step needs a box the frame lacks, or when the centring
    /// selection matches nothing in this frame.
    pub fn apply(&self, frame: &mut Frame) -> Result<(), TransformError> {
        let index = frame.index;
        let frame_error = |reason: String| TransformError::Frame {
            file: self.file.clone(),
            frame: index,
            reason,
        };
        if self.whole || self.centre.is_some() {
            let Some(cell) = PbcCell::of(frame) else {
                let step = if self.whole {
                    Step::Whole
                } else {
                    Step::Center
                };
                return Err(frame_error(format!("no periodic box ({step} needs one)")));
            };
            let molecules = self.molecules.as_deref();
            if self.whole
                && let Some(m) = molecules
            {
                m.make_whole(&mut frame.positions, &cell);
            }
            if let Some(centre) = &self.centre {
                let indices = centre.selection.indices(frame);
                let Some(c) = center::centre_of(&frame.positions, &indices, &self.masses) else {
                    return Err(frame_error(format!(
                        "--center '{}' matches no atom",
                        centre.text
                    )));
                };
                match molecules {
                    Some(m) => {
                        center::centre_in_box(&mut frame.positions, c, &cell, m, &self.masses)
                    }
                    None => {
                        let shift = cell.centre() - c;
                        frame.positions.iter_mut().for_each(|p| *p += shift);
                    }
                }
            }
        }
        if let Some(fit) = &self.fit {
            fit.apply(&mut frame.positions, frame.cell.as_mut());
        }
        if self.periodic.is_some() {
            let Some(rows) = frame.cell.as_ref() else {
                return Err(frame_error("no periodic box (--periodic needs one)".into()));
            };
            crate::surface::periodic::PeriodicCell::from_cell(rows)
                .map_err(|e| frame_error(format!("--periodic: {e}")))?;
        }
        Ok(())
    }

    /// A short description of what runs, e.g. `whole (guessed bonds), fit 'name CA' on the
    /// first frame, smooth ±2`; empty when nothing does.
    pub fn summary(&self) -> String {
        let mut parts = Vec::new();
        if self.whole {
            let how = match self.molecules.as_deref().map(Molecules::connectivity) {
                Some(Connectivity::FileBonds) => " (bonds from the file and guessed)",
                Some(Connectivity::GuessedBonds) => " (bonds guessed from distances)",
                Some(Connectivity::Residues) => " (residues)",
                _ => "",
            };
            parts.push(format!("whole{how}"));
        }
        if let Some(c) = &self.centre {
            parts.push(format!("center '{}'", c.text));
        }
        if self.fit.is_some() {
            let on = match self.fit_reference {
                FitReference::First => "the first frame",
                FitReference::Topology => "the topology's coordinates",
            };
            parts.push(format!("fit '{}' on {on}", self.fit_text));
        }
        if self.smooth > 0 {
            parts.push(format!("smooth ±{}", self.smooth));
        }
        match self.periodic {
            Some(r) if !r.is_one() => parts.push(format!("periodic, replicate {r}")),
            Some(_) => parts.push("periodic".into()),
            None => {}
        }
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_send_sync<T: Send + Sync + Clone>() {}

    #[test]
    fn chain_is_shareable() {
        assert_send_sync::<TransformChain>();
    }

    #[test]
    fn options_round_trip_through_toml() {
        let o = TransformOptions {
            whole: Some(false),
            center: Some("protein".into()),
            fit: None,
            fit_reference: FitReference::Topology,
            smooth: 3,
            periodic: true,
            replicate: Replicate([2, 2, 1]),
        };
        let text = toml::to_string(&o).expect("toml");
        let back: TransformOptions = toml::from_str(&text).expect("parse");
        assert_eq!(back, o);
        assert_eq!(
            "topology".parse::<FitReference>(),
            Ok(FitReference::Topology)
        );
    }
}
