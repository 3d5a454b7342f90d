//! `robot-app scan`: under construction.

use clap::Args;

/// Arguments of `robot-app scan`.
#[derive(Debug, Args)]
pub struct ScanArgs {}

/// Runs `robot-app scan`.
pub fn run(_args: ScanArgs) -> anyhow::Result<()> {
    anyhow::bail!("'robot-app scan' is not implemented yet")
}
