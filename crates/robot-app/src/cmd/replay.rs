//! `robot-app replay`: under construction.

use clap::Args;

/// Arguments of `robot-app replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {}

/// Runs `robot-app replay`.
pub fn run(_args: ReplayArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app replay' is not implemented yet")
}
