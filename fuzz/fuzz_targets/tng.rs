//! Fuzz target: the input as a TNG file's bytes through mdsurf's structural check of the block
//! chain (`src/io/tng.rs`: sizes, MD5s, the atom count against the particle blocks), which runs
//! before the TNG library opens a file. The library itself is C inside chemfiles, outside this
//! sanitizer build. Besides no panic, the check holds its own promise: a copy it keeps (the
//! frame sets before the damage) passes the check as sound.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(Some(kept)) = mdsurf::io::check_tng_chain(data) {
        // Not shorter in every case: a chain cut at a block boundary keeps every byte and
        // only clears the index's pointers to the missing frame sets.
        assert!(kept.len() <= data.len(), "the kept copy is longer");
        assert_eq!(
            mdsurf::io::check_tng_chain(&kept),
            Ok(None),
            "the kept copy fails the check"
        );
    }
});
