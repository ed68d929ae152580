//! `mdsurf render` (to be written).

/// Arguments of `mdsurf render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {}

/// Runs `mdsurf render`.
pub fn run(_args: RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("`mdsurf render` is not written yet")
}
