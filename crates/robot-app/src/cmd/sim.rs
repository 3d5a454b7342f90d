//! `robot-app sim`: under construction.

use clap::Args;

/// Arguments of `robot-app sim`.
#[derive(Debug, Args)]
pub struct SimArgs {}

/// Runs `robot-app sim`.
pub fn run(_args: SimArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app sim' is not implemented yet")
}
