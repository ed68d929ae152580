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
    /// Count (and list) the atoms a selection matches in one frame.
    Select(cli::select::SelectArgs),
    /// Join the parts of a chunked run (--chunk): stats and measurement tables into one CSV in frame order, movies into one MP4 or GIF.
    Merge(cli::merge::MergeArgs),
}

fn main() -> ExitCode {
    // `mdsurf __read-frames ...`: the reader process that opens files with chemfiles.
    if let Some(code) = mdsurf::io::reader_main() {
        return exit_without_static_destructors(code);
    }
    quiet_vulkan_device_select();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) if !err.use_stderr() => {
            // --help and --version: print as clap formats them.
            let _ = err.print();
            return ExitCode::SUCCESS;
        }
        Err(err) => {
            eprintln!("{}", one_line_usage_error(&err.render().to_string()));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Some(Command::Surface(args)) => cli::surface::run(args),
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Bench(args)) => cli::bench::run(args),
        Some(Command::Select(args)) => cli::select::run(args),
        Some(Command::Merge(args)) => cli::merge::run(args),
        None => cli::view::run(cli.view),
    };
    let code = match result {
        Ok(()) => 0,
        Err(err) => {
            eprintln!("error: {}", error_line(&err));
            2
        }
    };
    exit_without_static_destructors(code)
}

/// Ends the process with `code` once our output is flushed, without running C++ static
/// destructors: after chemfiles' LAMMPS reader has thrown on some damaged files, destroying its
/// static tables at exit crashes (SIGSEGV after the one-line error was printed). Every file we
/// write is complete and closed by now, so nothing is lost by skipping them.
fn exit_without_static_destructors(code: i32) -> ExitCode {
    use std::io::Write;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    // SAFETY: `_exit` ends the process at once; no Rust state needs to outlive this point (all
    // outputs were written and closed before `run` returned, and stdout/stderr are flushed).
    unsafe { libc::_exit(code) }
}

/// A clap usage error squeezed onto one line: its text up to the usage hint, lines joined.
fn one_line_usage_error(text: &str) -> String {
    let parts: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let line = parts.join(" ");
    let line = line.strip_prefix("error: ").unwrap_or(&line);
    format!("error: {line} (see --help)")
}

/// Mesa's Vulkan device-select layer connects to a Wayland compositor to choose the default GPU
/// and, with no session (`XDG_RUNTIME_DIR` unset: SSH, CI, Xvfb), prints a two-line complaint on
/// stderr that would break our one-line errors. Without a session it has nothing to choose by,
/// so it is switched off there (`NODEVICE_SELECT`, Mesa's own switch).
/// One line: the error and its causes, outermost first, leaving out a cause whose text the
/// line already holds (our typed errors name their cause in their own message).
fn error_line(err: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

fn quiet_vulkan_device_select() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        // SAFETY: called first thing in `main`, before any other thread exists.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

#[cfg(test)]
mod tests {
    use super::error_line;

    #[test]
    fn causes_already_in_the_message_are_not_repeated() {
        let typed = mdsurf::scene::state_file::StateFileError::Read {
            path: "s.toml".into(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "gone"),
        };
        assert_eq!(
            error_line(&anyhow::Error::new(typed)),
            "cannot read state file s.toml: gone"
        );
        let with_context = anyhow::anyhow!("inner").context("outer");
        assert_eq!(error_line(&with_context), "outer: inner");
    }
}
