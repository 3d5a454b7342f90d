//! Tracing setup shared by every command.

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// Installs a stderr tracing subscriber (colours only on a terminal); `RUST_LOG` overrides the
/// -v/-q level.
pub fn init(verbose: u8, quiet: u8) {
    let level = match (i16::from(verbose) - i16::from(quiet)).clamp(-2, 2) {
        -2 => "off",
        -1 => "error",
        0 => "info",
        1 => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(level));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_target(false)
        .try_init();
}
