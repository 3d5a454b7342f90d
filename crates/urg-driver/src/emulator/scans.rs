//! Scan replies: values (mm or error codes, clustered) from the source's scan, injected
//! scan faults, and the encoded reply.

use scan_types::{LaserSource, RayStatus, Scan};

use super::control::Fault;
use super::machine::SensorCore;
use crate::codec::{DataKind, LF, ScanRequest, Status, encode_scan_body, encode_status_line};

impl<S: LaserSource> SensorCore<S> {
    /// Builds one scan reply from the source; returns false when a fault or source error
    /// ended the stream.
    pub(super) fn scan_reply(
        &mut self,
        echo: &[u8],
        req: &ScanRequest,
        status: Status,
        stamp_ms: u64,
    ) -> bool {
        let fault = {
            let mut c = self.control.lock();
            let pos = c
                .faults
                .iter()
                .position(|f| !matches!(f, Fault::Garbage(_)));
            pos.and_then(|i| c.faults.remove(i))
        };
        if let Some(Fault::HardwareStatus(s)) = fault {
            self.reply(echo, Status(s));
            return false;
        }
        let scan = match self.source.next_scan() {
            Ok(s) => s,
            Err(e) => {
                tracing::warn!("emulator source failed: {e}; answering with a hardware fault");
                self.reply(echo, Status(*b"50"));
                return false;
            }
        };
        let (ranges, intens) = self.values(&scan, req);
        let mut v = Vec::with_capacity(ranges.len() * 4 + 64);
        v.extend_from_slice(echo);
        v.push(LF);
        encode_status_line(status, &mut v);
        encode_scan_body(self.timer(stamp_ms), &ranges, &intens, req.kind, &mut v);
        v.push(LF);
        match fault {
            Some(Fault::CorruptChecksum) => {
                // The last data line's checksum character, changed.
                let at = v.len() - 3;
                v[at] = if v[at] == b'0' { b'1' } else { b'0' };
            }
            Some(Fault::TruncateReply) => v.truncate(v.len() / 2),
            _ => {}
        }
        self.begin_reply();
        self.out.extend(v);
        self.control.lock().scans_served += 1;
        true
    }

    /// Sensor values (mm or error codes) and intensities for a request.
    fn values(&self, scan: &Scan, req: &ScanRequest) -> (Vec<u32>, Vec<u32>) {
        let p = &self.profile.params;
        let value_of = |step: usize| -> (u32, u32) {
            let Some(i) = self.step_map.get(step).copied().flatten() else {
                return (19, 0);
            };
            let intensity = scan
                .intensities
                .as_ref()
                .and_then(|v| v.get(i))
                .map(|&x| x.max(0.0) as u32);
            match (scan.status.get(i), scan.ranges_m.get(i)) {
                (Some(RayStatus::Hit), Some(&r)) if r.is_finite() => {
                    let mm = (r * 1000.0)
                        .round()
                        .clamp(f64::from(p.dmin_mm), f64::from(p.dmax_mm - 1));
                    (mm as u32, intensity.unwrap_or(1000))
                }
                (Some(RayStatus::Error(c)), _) => (u32::from(*c).min(p.dmin_mm - 1), 0),
                // No return: code 0.
                _ => (0, intensity.unwrap_or(0)),
            }
        };
        let cluster = usize::from(req.cluster.max(1));
        let mut ranges = Vec::with_capacity(req.value_count());
        let mut intens = Vec::new();
        let mut s = usize::from(req.start_step);
        let end = usize::from(req.end_step);
        while s <= end {
            let group_end = (s + cluster - 1).min(end);
            let (first, first_i) = value_of(s);
            // A cluster reports its smallest valid distance, else the first step's code.
            let best = (s..=group_end)
                .map(value_of)
                .filter(|(v, _)| *v >= p.dmin_mm)
                .min_by_key(|(v, _)| *v)
                .unwrap_or((first, first_i));
            ranges.push(best.0);
            if req.kind == DataKind::RangeIntensity {
                intens.push(best.1);
            }
            s = group_end + 1;
        }
        (ranges, intens)
    }
}
