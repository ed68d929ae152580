//! `mdsurf merge STATS.csv`: joins the stats parts that the chunks of a job array wrote
//! (`STATS.part-IIII-of-NNNN.csv`, from `--chunk`) into `STATS.csv`, sorted by frame; refuses
//! parts of runs with other parameters and names missing or duplicated frames in one line
//! ([`mdsurf::export::stats_merge::merge_parts`]). A measurement table's parts (`--per-residue`,
//! `--per-atom`, `--interface-csv`, `--interface-residues`) are joined in chunk order
//! ([`mdsurf::export::table_merge::merge_csv_parts`], which tells the two apart by their
//! columns). `mdsurf merge MOVIE.mp4` (or `.gif`) joins the movie parts of `render --chunk`
//! without re-encoding ([`mdsurf::export::movie_merge::merge_movie_parts`]).

use std::path::PathBuf;

use anyhow::Result;
use mdsurf::export::movie::is_movie;
use mdsurf::export::movie_merge::merge_movie_parts;
use mdsurf::export::table_merge::merge_csv_parts;

/// Arguments of `mdsurf merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The merged stats or measurement CSV, or MP4/GIF movie; its parts are
    /// `STATS.part-IIII-of-NNNN.csv` (or `MOVIE.part-IIII-of-NNNN.mp4` / `.gif`, joined without
    /// re-encoding) beside it.
    #[arg(value_name = "TABLE.csv|MOVIE.mp4|MOVIE.gif")]
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
    if is_movie(&args.stats) {
        let summary = merge_movie_parts(&args.stats)?;
        remove_parts(&args, &summary.parts);
        if !args.quiet {
            eprintln!(
                "{}: {} frame(s), {:.2} s, {:.1} kB from {} part(s)",
                args.stats.display(),
                summary.frames,
                summary.seconds,
                summary.bytes as f64 / 1000.0,
                summary.parts.len()
            );
        }
        return Ok(());
    }
    let summary = merge_csv_parts(&args.stats)?;
    remove_parts(&args, &summary.parts);
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

/// Deletes the merged parts with `--remove-parts` (a part that cannot be removed is noted).
fn remove_parts(args: &MergeArgs, parts: &[PathBuf]) {
    if args.remove_parts {
        for part in parts {
            if let Err(e) = std::fs::remove_file(part) {
                eprintln!("note: cannot remove {}: {e}", part.display());
            }
        }
    }
}
