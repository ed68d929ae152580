//! `mdsurf bench` (to be written).

/// Arguments of `mdsurf bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {}

/// Runs `mdsurf bench`.
pub fn run(_args: BenchArgs) -> anyhow::Result<()> {
    anyhow::bail!("`mdsurf bench` is not written yet")
}
