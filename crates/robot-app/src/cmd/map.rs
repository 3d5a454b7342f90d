//! `robot-app map`: under construction.

use clap::Args;

/// Arguments of `robot-app map`.
#[derive(Debug, Args)]
pub struct MapArgs {}

/// Runs `robot-app map`.
pub fn run(_args: MapArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app map' is not implemented yet")
}
