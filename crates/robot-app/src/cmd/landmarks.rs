//! `robot-app landmarks`: under construction.

use clap::Args;

/// Arguments of `robot-app landmarks`.
#[derive(Debug, Args)]
pub struct LandmarksArgs {}

/// Runs `robot-app landmarks`.
pub fn run(_args: LandmarksArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app landmarks' is not implemented yet")
}
