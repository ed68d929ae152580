//! How the frame loops of `surface` and `render` report on stderr: one line per frame with
//! `-v` (and for a single frame, or a running simulation whose length is unknown), one progress
//! bar with frames per second and time left on a terminal, and nothing per frame when stderr is
//! a file or a pipe (the command's final summary line says what was done). `-q` prints errors
//! only.

use std::fmt;
use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressState, ProgressStyle};

/// What the loop prints while it runs.
pub(crate) enum Progress {
    /// `-q`: nothing but errors.
    Quiet,
    /// One line per frame.
    Lines,
    /// One progress bar on the terminal.
    Bar(ProgressBar),
    /// Nothing per frame; the final summary only.
    SummaryOnly,
}

impl Progress {
    /// The report for a loop over `frames` frames (`None`: unknown, a running simulation),
    /// with the `-q` and `-v` flags.
    pub(crate) fn new(frames: Option<usize>, quiet: bool, verbose: bool) -> Progress {
        Self::choose(frames, quiet, verbose, std::io::stderr().is_terminal())
    }

    /// [`Progress::new`] with the terminal test given (`terminal`: stderr is a terminal).
    fn choose(frames: Option<usize>, quiet: bool, verbose: bool, terminal: bool) -> Progress {
        match frames {
            _ if quiet => Progress::Quiet,
            None | Some(0 | 1) => Progress::Lines,
            _ if verbose => Progress::Lines,
            Some(n) if terminal => Progress::Bar(bar(n)),
            Some(_) => Progress::SummaryOnly,
        }
    }

    /// Prints the line `line` makes when this report shows frame lines.
    pub(crate) fn line(&self, line: impl FnOnce() -> String) {
        if let Progress::Lines = self {
            eprintln!("{}", line());
        }
    }

    /// One frame done.
    pub(crate) fn advance(&self) {
        if let Progress::Bar(bar) = self {
            bar.inc(1);
        }
    }

    /// Removes the bar (before the final summary or an error is printed).
    pub(crate) fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }

    /// True unless `-q`: the final summary line is printed.
    pub(crate) fn shows_summary(&self) -> bool {
        !matches!(self, Progress::Quiet)
    }
}

/// A bar of `len` frames: position, frames per second and time left.
fn bar(len: usize) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {fps}  eta {eta}")
    {
        bar.set_style(
            style.with_key("fps", |state: &ProgressState, w: &mut dyn fmt::Write| {
                let _ = write!(w, "{:.1} frames/s", state.per_sec());
            }),
        );
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kind(p: &Progress) -> &'static str {
        match p {
            Progress::Quiet => "quiet",
            Progress::Lines => "lines",
            Progress::Bar(_) => "bar",
            Progress::SummaryOnly => "summary",
        }
    }

    #[test]
    fn lines_behind_verbose_a_bar_on_a_terminal_a_summary_elsewhere() {
        let pick = |frames, quiet, verbose, terminal| {
            kind(&Progress::choose(frames, quiet, verbose, terminal))
        };
        assert_eq!(pick(Some(100), false, false, false), "summary");
        assert_eq!(pick(Some(100), false, false, true), "bar");
        assert_eq!(pick(Some(100), false, true, true), "lines");
        assert_eq!(pick(Some(100), false, true, false), "lines");
        assert_eq!(pick(Some(100), true, true, true), "quiet");
        // One frame: its line is the result; a running simulation: no length for a bar.
        assert_eq!(pick(Some(1), false, false, false), "lines");
        assert_eq!(pick(None, false, false, true), "lines");
    }
}
