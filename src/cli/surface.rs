//! `mdsurf surface` (to be written).

/// Arguments of `mdsurf surface`.
#[derive(clap::Args, Debug)]
pub struct SurfaceArgs {}

/// Runs `mdsurf surface`.
pub fn run(_args: SurfaceArgs) -> anyhow::Result<()> {
    anyhow::bail!("`mdsurf surface` is not written yet")
}
