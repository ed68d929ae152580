//! Fuzz target: the input as a `.cif` file, read whole by mdsurf (see `mdsurf_fuzz::read_as`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| mdsurf_fuzz::read_as("cif", data));
