//! `robot-app batch`: under construction.

use clap::Args;

/// Arguments of `robot-app batch`.
#[derive(Debug, Args)]
pub struct BatchArgs {}

/// Runs `robot-app batch`.
pub fn run(_args: BatchArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app batch' is not implemented yet")
}
