//! Waiting that a stop request can cut short.

use std::time::{Duration, Instant};

/// Waits `duration` in naps of at most 50 ms; false when `stop` returned true first.
pub fn sleep_unless(duration: Duration, stop: impl Fn() -> bool) -> bool {
    let until = Instant::now() + duration;
    loop {
        if stop() {
            return false;
        }
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return true;
        }
        std::thread::sleep(left.min(Duration::from_millis(50)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_cuts_the_wait_short() {
        let t = Instant::now();
        assert!(!sleep_unless(Duration::from_secs(10), || true));
        assert!(t.elapsed() < Duration::from_secs(1));
        assert!(sleep_unless(Duration::from_millis(20), || false));
        assert!(t.elapsed() >= Duration::from_millis(20));
    }
}
