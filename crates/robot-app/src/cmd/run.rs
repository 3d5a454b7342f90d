//! `robot-app run`: under construction.

use clap::Args;

/// Arguments of `robot-app run`.
#[derive(Debug, Args)]
pub struct RunArgs {}

/// Runs `robot-app run`.
pub fn run(_args: RunArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app run' is not implemented yet")
}
