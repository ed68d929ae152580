//! Turning a panic inside a third-party reader (pdbtbx, or chemfiles' Rust binding on text that
//! is not UTF-8) into an error without printing the panic message: a user's file must give one
//! line of error, never a panic report. A last resort behind the input checks, not the design.

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

thread_local! {
    static SILENT: Cell<bool> = const { Cell::new(false) };
}
static INSTALL: Once = Once::new();

/// Installs (once) a panic hook that stays quiet inside [`silenced`] and defers to the previous
/// hook elsewhere.
pub(crate) fn install() {
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !SILENT.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

/// Calls `f`, turning a panic into `Err(())` without printing it.
pub(crate) fn silenced<T>(f: impl FnOnce() -> T) -> Result<T, ()> {
    install();
    let was = SILENT.with(|s| s.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    SILENT.with(|s| s.set(was));
    result.map_err(|_| ())
}
