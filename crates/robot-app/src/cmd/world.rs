//! `robot-app world`: under construction.

use clap::Args;

/// Arguments of `robot-app world`.
#[derive(Debug, Args)]
pub struct WorldArgs {}

/// Runs `robot-app world`.
pub fn run(_args: WorldArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app world' is not implemented yet")
}
