//! the viewer (to be written).

/// Arguments of the viewer.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {}

/// Runs the viewer.
pub fn run(_args: ViewArgs) -> anyhow::Result<()> {
    anyhow::bail!("the viewer is not written yet")
}
