//! TEMPORARY stand-in for `mdsurf::gpu::table1` (the GPU branch has only a placeholder module so
//! far), written against the agreed interface so `mdsurf bench --table1` compiles meanwhile.
//! It fails with a clear error; this file is deleted when the real function is merged.

use anyhow::{Result, bail};

/// Stand-in for `mdsurf::gpu::table1`.
pub fn table1() -> Result<String> {
    bail!("--table1: the GPU engine's Table 1 runner is not merged into this build yet")
}
