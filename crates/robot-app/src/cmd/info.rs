//! `robot-app info`: under construction.

use clap::Args;

/// Arguments of `robot-app info`.
#[derive(Debug, Args)]
pub struct InfoArgs {}

/// Runs `robot-app info`.
pub fn run(_args: InfoArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app info' is not implemented yet")
}
