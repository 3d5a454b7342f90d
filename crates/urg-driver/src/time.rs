//! Sensor time: unwrapping the 24-bit millisecond timer and mapping it to host time.

/// The sensor timer wraps after this many milliseconds (2^24, about 4.66 h).
pub const TIMER_WRAP_MS: u64 = 1 << 24;

/// Turns 24-bit timer readings into a monotonic millisecond count.
///
/// A reading more than half a wrap below the previous one is a wrap; a smaller step back
/// (jitter) is kept as it is.
///
/// ```
/// use urg_driver::time::TimestampUnwrapper;
/// let mut u = TimestampUnwrapper::default();
/// assert_eq!(u.unwrap(16_777_200), 16_777_200);
/// assert_eq!(u.unwrap(5), 16_777_216 + 5);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TimestampUnwrapper {
    last: Option<u32>,
    wraps: u64,
}

impl TimestampUnwrapper {
    /// The unwrapped value of a new 24-bit reading.
    pub fn unwrap(&mut self, raw: u32) -> u64 {
        let raw = raw & 0xFF_FFFF;
        if let Some(last) = self.last
            && raw < last
            && last - raw > (1 << 23)
        {
            self.wraps += 1;
        }
        self.last = Some(raw);
        self.wraps * TIMER_WRAP_MS + u64::from(raw)
    }

    /// Forgets the history (after `RS`, which resets the sensor's timer).
    pub fn reset(&mut self) {
        *self = Self::default();
    }
}

/// One TM1 round trip: host send and receive times (seconds) and the sensor reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSample {
    /// Host time when `TM1` was sent, seconds.
    pub host_send_s: f64,
    /// Host time when the reply arrived, seconds.
    pub host_recv_s: f64,
    /// The sensor's 24-bit timer, milliseconds.
    pub sensor_ms: u32,
}

/// Median of `host_mid - sensor` over the samples (seconds): add it to a sensor time in
/// seconds to get host time. `None` without samples.
///
/// ```
/// use urg_driver::time::{TimeSample, median_offset_s};
/// let s = |send, recv, ms| TimeSample { host_send_s: send, host_recv_s: recv, sensor_ms: ms };
/// // Offsets 99.0, 99.5 (a slow round trip) and 99.0: the median is 99.0.
/// let off = median_offset_s(&[s(100.0, 100.0, 1000), s(101.0, 102.0, 2000), s(103.0, 103.0, 4000)]);
/// assert_eq!(off, Some(99.0));
/// ```
pub fn median_offset_s(samples: &[TimeSample]) -> Option<f64> {
    let mut offs: Vec<f64> = samples
        .iter()
        .map(|s| (s.host_send_s + s.host_recv_s) / 2.0 - f64::from(s.sensor_ms) / 1000.0)
        .filter(|o| o.is_finite())
        .collect();
    if offs.is_empty() {
        return None;
    }
    offs.sort_by(f64::total_cmp);
    let n = offs.len();
    Some(if n % 2 == 1 {
        offs[n / 2]
    } else {
        (offs[n / 2 - 1] + offs[n / 2]) / 2.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwraps_across_several_wraps_and_ignores_jitter() {
        let mut u = TimestampUnwrapper::default();
        let mut expected = 16_777_000u64;
        assert_eq!(u.unwrap(16_777_000), expected);
        for _ in 0..5 {
            expected += 100;
            let raw = (expected % TIMER_WRAP_MS) as u32;
            assert_eq!(u.unwrap(raw), expected);
        }
        // A small step back is jitter, not a wrap.
        let back = u.unwrap(((expected - 3) % TIMER_WRAP_MS) as u32);
        assert_eq!(back, expected - 3);
        // Two more full wraps, one reading per 2^23 - 1 ms.
        let mut t = expected;
        for _ in 0..4 {
            t += (1 << 23) - 1;
            assert_eq!(u.unwrap((t % TIMER_WRAP_MS) as u32), t);
        }
        u.reset();
        assert_eq!(u.unwrap(10), 10);
    }

    #[test]
    fn median_ignores_one_slow_round_trip() {
        let s = |send, recv, ms| TimeSample {
            host_send_s: send,
            host_recv_s: recv,
            sensor_ms: ms,
        };
        let samples = [
            s(10.000, 10.002, 5001),
            s(10.010, 10.012, 5011),
            s(10.020, 10.520, 5021), // stalled reply
            s(10.530, 10.532, 5531),
        ];
        let off = median_offset_s(&samples).unwrap();
        assert!((off - 5.0).abs() < 1e-9, "{off}");
        assert_eq!(median_offset_s(&[]), None);
    }
}
