//! `mdsurf merge STATS.csv`: joins the stats parts that the chunks of a job array wrote
//! (`STATS.part-IIII-of-NNNN.csv`, from `--chunk`) into `STATS.csv`, sorted by frame; refuses
//! parts of runs with other parameters and names missing or duplicated frames in one line. The
//! work is [`mdsurf::export::stats_merge::merge_parts`].

use std::path::PathBuf;

use anyhow::Result;
use mdsurf::export::stats_merge::merge_parts;

/// Arguments of `mdsurf merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The merged stats CSV; its parts are `STATS.part-IIII-of-NNNN.csv` beside it.
    #[arg(value_name = "STATS.csv")]
    pub stats: PathBuf,
    /// Delete the part files after a successful merge.
    #[arg(long)]
    pub remove_parts: bool,
    /// Print nothing on success.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `mdsurf merge`.
pub fn run(args: MergeArgs) -> Result<()> {
    let summary = merge_parts(&args.stats)?;
    if args.remove_parts {
        for part in &summary.parts {
            if let Err(e) = std::fs::remove_file(part) {
                eprintln!("note: cannot remove {}: {e}", part.display());
            }
        }
    }
    if !args.quiet {
        eprintln!(
            "{}: {} frame(s), {} row(s) from {} part(s)",
            args.stats.display(),
            summary.frames,
            summary.rows,
            summary.parts.len()
        );
    }
    Ok(())
}
