//! The window tests' X server: their `xvfb-run -a` runs go one at a time.

use std::process::Command;
use std::sync::{Mutex, MutexGuard};

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// `xvfb-run -a` with a 1280x800 screen, and a guard to hold until it has finished. `-a` takes
/// the first free display number, and two runs started at once took the same one: one window
/// then failed to reach its X server ("Failed to open connection to X server") when the window
/// tests ran in parallel.
pub fn xvfb_run() -> (MutexGuard<'static, ()>, Command) {
    let guard = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut command = Command::new("xvfb-run");
    command.args(["-a", "-s", "-screen 0 1280x800x24"]);
    (guard, command)
}
