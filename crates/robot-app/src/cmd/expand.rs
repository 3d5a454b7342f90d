//! `robot-app expand`: under construction.

use clap::Args;

/// Arguments of `robot-app expand`.
#[derive(Debug, Args)]
pub struct ExpandArgs {}

/// Runs `robot-app expand`.
pub fn run(_args: ExpandArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app expand' is not implemented yet")
}
