//! Ctrl-C, SIGTERM and SIGHUP: the first asks the running command to stop cleanly (stop the
//! base, finish the recording, write every output with reason `interrupted`); the program
//! then exits with [`EXIT_CODE`].

use std::sync::atomic::{AtomicBool, Ordering};

/// Exit status of an interrupted command (128 + SIGINT), as shells expect.
pub const EXIT_CODE: u8 = 130;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler; a second signal while stopping is only logged, so that the base
/// still gets its `stop`.
pub fn install() {
    let installed = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            tracing::warn!(
                "already stopping: the outputs are being written (and a base told to stop)"
            );
        } else {
            tracing::warn!("interrupted: stopping cleanly");
        }
    });
    if let Err(e) = installed {
        tracing::warn!("Ctrl-C will not stop runs cleanly: {e}");
    }
}

/// True once a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// [`Interrupted`] once a stop was asked for, for a command that keeps nothing of its work.
pub fn check() -> anyhow::Result<()> {
    if requested() {
        return Err(Interrupted.into());
    }
    Ok(())
}

/// Waits `duration` in naps of at most 50 ms; false when a stop request ended the wait.
pub fn sleep(duration: std::time::Duration) -> bool {
    scan_types::sleep_unless(duration, requested)
}

/// The error a command returns when it stopped because of a signal, after writing its
/// outputs; `main` turns it into [`EXIT_CODE`].
#[derive(Debug)]
pub struct Interrupted;

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("interrupted")
    }
}

impl std::error::Error for Interrupted {}
