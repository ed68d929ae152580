//! `mdsurf select TOP [TRAJ] [--frame N] [--indices] EXPR`: evaluates a selection (see
//! [`mdsurf::selection`]) on one frame and prints the number of matching atoms on the
//! first line and, with `--indices`, their 0-based indices space-separated on the second.
//! A bad selection is reported as one line with the column of the first bad token (status 2).

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use mdsurf::selection::Selection;

/// Arguments of `mdsurf select`.
#[derive(clap::Args, Debug)]
pub struct SelectArgs {
    /// TOP [TRAJ] EXPR: a structure file, optionally a trajectory, and the selection (quote it,
    /// e.g. 'within 5 of protein').
    #[arg(value_name = "TOP [TRAJ] EXPR", required = true)]
    pub args: Vec<String>,
    /// Frame to evaluate (0-based).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub frame: usize,
    /// Also print the selected atoms' 0-based indices on a second line.
    #[arg(long)]
    pub indices: bool,
    /// Print only errors besides the result (taken by every command; `select` prints its
    /// count on stdout and nothing else on stderr).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `mdsurf select`.
pub fn run(args: SelectArgs) -> Result<()> {
    let (files, expr) = match args.args.split_last() {
        Some((expr, files)) if (1..=2).contains(&files.len()) => (files, expr),
        _ => bail!(
            "select takes TOP [TRAJ] EXPR (2 or 3 arguments), got {}",
            args.args.len()
        ),
    };
    // The selection is checked before any file is read.
    let selection = Selection::parse(expr)
        .map_err(|e| anyhow!(e))
        .with_context(|| format!("selection '{expr}'"))?;
    let top = PathBuf::from(&files[0]);
    let traj = files.get(1).map(PathBuf::from);
    let trajectory = mdsurf::io::open(&top, traj.as_deref())?;
    if args.frame >= trajectory.len() {
        bail!(
            "--frame {}: {} has {} frames",
            args.frame,
            trajectory.path().display(),
            trajectory.len()
        );
    }
    let frame = trajectory.read_frame(args.frame)?;
    let indices = selection.bind(trajectory.topology()).indices(&frame);
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", indices.len())?;
    if args.indices {
        let line: Vec<String> = indices.iter().map(u32::to_string).collect();
        writeln!(out, "{}", line.join(" "))?;
    }
    Ok(())
}
