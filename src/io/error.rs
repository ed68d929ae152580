//! The one error type of the reading layer: every variant names the file (and the frame and atom
//! where it applies), and prints as one line.

use std::path::PathBuf;

/// Why a structure or trajectory could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IoError {
    /// The file does not exist or cannot be opened.
    #[error("{}: file not found or not readable ({reason})", path.display())]
    NotFound {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        reason: String,
    },
    /// The path is a folder, a pipe or a device, not a file (mdsurf reads its files more than
    /// once: it indexes the frames, then reads those shown).
    #[error("{}: {what}, not a file; give the path of a structure or trajectory file", path.display())]
    NotAFile {
        /// The path given.
        path: PathBuf,
        /// What it is: "a folder", "a pipe (such as `<(zcat file)`)", "a device or socket".
        what: &'static str,
    },
    /// The file name does not say which format it is in.
    #[error(
        "{}: unknown file format '{ext}' (known: pdb, ent, cif, mmcif, gro, xtc, trr, dcd, lammpstrj, lammpsdump, xyz, tng, nc, ncdf; optionally .gz/.bz2/.xz)",
        path.display()
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its extension as written (empty when it has none).
        ext: String,
    },
    /// The file could not be parsed.
    #[error("{}: cannot read: {message}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What the parser said (one line).
        message: String,
    },
    /// One frame could not be read (truncated or corrupt file).
    #[error("{}: frame {frame}: cannot read: {message}", path.display())]
    BadFrame {
        /// The file.
        path: PathBuf,
        /// Index of the frame, from 0.
        frame: usize,
        /// What the parser said (one line).
        message: String,
    },
    /// A live simulation's stream ended (the run finished, the engine was killed, or the
    /// connection dropped): the frames before stay readable.
    #[error("{}: the simulation stream ended after {frames} frames ({reason})", path.display())]
    LiveEnded {
        /// `imd://HOST:PORT`.
        path: PathBuf,
        /// Frames received.
        frames: usize,
        /// Why it ended (one line).
        reason: String,
    },
    /// Frames of a running simulation that arrived faster than they were read and left the
    /// ring of frames kept before being read: the oldest frame still held is `oldest`.
    #[error(
        "{}: frame {frame} is no longer held: the simulation sends frames faster than they are \
         read (frames {oldest} on are held, the last {kept})",
        path.display()
    )]
    LiveOverrun {
        /// `imd://HOST:PORT`.
        path: PathBuf,
        /// The frame asked for.
        frame: usize,
        /// The oldest frame still held.
        oldest: usize,
        /// Frames kept.
        kept: usize,
    },
    /// A frame index past the end of the trajectory was asked for.
    #[error("{}: frame {frame} does not exist (the trajectory has {len} frames)", path.display())]
    FrameOutOfRange {
        /// The file.
        path: PathBuf,
        /// The frame asked for.
        frame: usize,
        /// Number of frames in the file.
        len: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{}: frame {frame}: atom {atom} has a NaN or infinite coordinate", path.display())]
    NonFiniteCoordinate {
        /// The file.
        path: PathBuf,
        /// Index of the frame, from 0.
        frame: usize,
        /// Index of the atom, from 0.
        atom: usize,
    },
    /// A coordinate is so far out (beyond ±1e7 Å) that it can only be damage.
    #[error(
        "{}: frame {frame}: atom {atom} has an absurd coordinate ({value:e} Å; damaged file?)",
        path.display()
    )]
    AbsurdCoordinate {
        /// The file.
        path: PathBuf,
        /// Index of the frame, from 0.
        frame: usize,
        /// Index of the atom, from 0.
        atom: usize,
        /// The largest absolute coordinate of that atom, in Å.
        value: f32,
    },
    /// Topology and trajectory disagree on the number of atoms.
    #[error(
        "atom count mismatch: topology {} has {topology_atoms} atoms but trajectory {} has {trajectory_atoms} (frame {frame})",
        topology.display(), trajectory.display()
    )]
    AtomCountMismatch {
        /// The topology file.
        topology: PathBuf,
        /// Its atom count.
        topology_atoms: usize,
        /// The trajectory file.
        trajectory: PathBuf,
        /// Atoms in the frame that disagreed.
        trajectory_atoms: usize,
        /// The frame that disagreed.
        frame: usize,
    },
    /// The file holds no atoms or no frames.
    #[error("{}: nothing to read: {what}", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// What is missing ("no atoms", "no frames", "the file is empty").
        what: &'static str,
    },
    /// A coordinates-only trajectory was opened without a topology.
    #[error(
        "{}: this format has no atom names; give a topology file (pdb, gro, ...) before it",
        path.display()
    )]
    NeedsTopology {
        /// The trajectory file.
        path: PathBuf,
    },
}

impl IoError {
    /// For a frame a running simulation sent and pushed out of the frames kept before it was
    /// read ([`IoError::LiveOverrun`]): the oldest frame still held; `None` for other errors.
    pub fn oldest_held(&self) -> Option<usize> {
        match self {
            IoError::LiveOverrun { oldest, .. } => Some(*oldest),
            _ => None,
        }
    }

    /// The same error with the file `from` called `to` (its path fields, and where a message
    /// quotes it): a trajectory downloaded from a URL names the URL, not its temporary copy.
    pub(crate) fn renamed(mut self, from: &std::path::Path, to: &std::path::Path) -> Self {
        let rename = |path: &mut PathBuf| {
            if path == from {
                *path = to.to_path_buf();
            }
        };
        let (old, new) = (from.display().to_string(), to.display().to_string());
        let requote = |text: &mut String| {
            if !old.is_empty() && text.contains(&old) {
                *text = text.replace(&old, &new);
            }
        };
        match &mut self {
            IoError::NotFound { path, reason: text }
            | IoError::Unreadable {
                path,
                message: text,
            }
            | IoError::BadFrame {
                path,
                message: text,
                ..
            }
            | IoError::LiveEnded {
                path, reason: text, ..
            } => {
                rename(path);
                requote(text);
            }
            IoError::UnknownFormat { path, .. }
            | IoError::LiveOverrun { path, .. }
            | IoError::FrameOutOfRange { path, .. }
            | IoError::NonFiniteCoordinate { path, .. }
            | IoError::AbsurdCoordinate { path, .. }
            | IoError::Empty { path, .. }
            | IoError::NotAFile { path, .. }
            | IoError::NeedsTopology { path } => rename(path),
            IoError::AtomCountMismatch {
                topology,
                trajectory,
                ..
            } => {
                rename(topology);
                rename(trajectory);
            }
        }
        self
    }

    /// Builds an [`IoError::Unreadable`], squeezing a multi-line message onto one line.
    pub(crate) fn unreadable(path: &std::path::Path, message: impl std::fmt::Display) -> Self {
        IoError::Unreadable {
            path: path.to_path_buf(),
            message: one_line(&message.to_string()),
        }
    }

    /// Builds an [`IoError::BadFrame`], squeezing a multi-line message onto one line.
    pub(crate) fn bad_frame(
        path: &std::path::Path,
        frame: usize,
        message: impl std::fmt::Display,
    ) -> Self {
        IoError::BadFrame {
            path: path.to_path_buf(),
            frame,
            message: one_line(&message.to_string()),
        }
    }
}

/// Joins the lines of a parser message with "; " so errors stay on one line, and replaces
/// control characters with `?`.
pub(crate) fn one_line(message: &str) -> String {
    let parts: Vec<&str> = message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if parts.is_empty() {
        "unknown error".to_string()
    } else {
        // Control characters from a file's bytes (quoted by a parser) must not reach a terminal.
        parts
            .join("; ")
            .chars()
            .map(|c| if c.is_control() { '?' } else { c })
            .collect()
    }
}
