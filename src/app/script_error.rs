//! Why a console script (`mdsurf view --script`) could not be read: the file, or a line that
//! does not parse. Each prints as one line naming the file (and the line, from 1).

use std::path::PathBuf;

use super::console::ConsoleError;

/// A console script that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    /// The file could not be read.
    #[error("cannot read script {}: {source}", path.display())]
    Read {
        /// The script file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A line does not parse as a console command.
    #[error("{}:{line}: {source}", path.display())]
    Line {
        /// The script file.
        path: PathBuf,
        /// The line, from 1.
        line: usize,
        /// Why it does not parse.
        source: ConsoleError,
    },
}
