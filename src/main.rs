//! The `mdsurf` command line: no subcommand opens the viewer; `surface`, `render` and `bench` run
//! the same engine headless. Errors print as one line and exit with status 2.

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Gaussian density surfaces for molecular dynamics trajectories.
#[derive(Parser, Debug)]
#[command(
    name = "mdsurf",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    view: cli::view::ViewArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Compute surfaces headless: meshes and per-frame area/volume.
    Surface(cli::surface::SurfaceArgs),
    /// Render pictures headless with the viewer's renderer.
    Render(cli::render::RenderArgs),
    /// Time each stage of the engines.
    Bench(cli::bench::BenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Surface(args)) => cli::surface::run(args),
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Bench(args)) => cli::bench::run(args),
        None => cli::view::run(cli.view),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // One line: the error and its causes, outermost first.
            eprintln!("error: {err:#}");
            ExitCode::from(2)
        }
    }
}
