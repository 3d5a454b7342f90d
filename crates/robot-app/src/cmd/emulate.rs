//! `robot-app emulate`: under construction.

use clap::Args;

/// Arguments of `robot-app emulate`.
#[derive(Debug, Args)]
pub struct EmulateArgs {}

/// Runs `robot-app emulate`.
pub fn run(_args: EmulateArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app emulate' is not implemented yet")
}
