//! Captures chemfiles' warnings (which it would otherwise print to stderr, once per odd line of a
//! file) into a small bounded buffer that the application may show or drop.

use std::sync::Mutex;

/// At most this many warnings are kept; later ones only bump the dropped counter.
const MAX_KEPT: usize = 64;

/// Distinct warnings seen since the last [`take_warnings`], and how many did not fit.
static BUFFER: Mutex<(Vec<String>, usize)> = Mutex::new((Vec::new(), 0));
#[cfg(feature = "chemfiles")]
static INSTALL: std::sync::Once = std::sync::Once::new();

/// Routes chemfiles' warnings into the buffer. Idempotent and thread-safe; every reader calls it
/// before touching chemfiles.
#[cfg(feature = "chemfiles")]
pub(crate) fn install() {
    INSTALL.call_once(|| {
        chemfiles::set_warning_callback(push);
    });
}

/// Keeps `message` (once) in the buffer: a chemfiles warning, here or in a reader process.
#[cfg_attr(not(feature = "chemfiles"), allow(dead_code))]
pub(crate) fn push(message: &str) {
    if let Ok(mut buffer) = BUFFER.lock() {
        if buffer.0.iter().any(|kept| kept == message) {
            // Parsers repeat a warning once per odd line: keep it once.
        } else if buffer.0.len() < MAX_KEPT {
            buffer.0.push(message.to_string());
        } else {
            buffer.1 += 1;
        }
    }
}

/// Returns and clears the chemfiles warnings collected so far (at most 64) and how many more
/// were dropped.
pub fn take_warnings() -> (Vec<String>, usize) {
    match BUFFER.lock() {
        Ok(mut buffer) => (std::mem::take(&mut buffer.0), std::mem::take(&mut buffer.1)),
        Err(_) => (Vec::new(), 0),
    }
}
