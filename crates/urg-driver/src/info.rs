//! The sensor's version (VV), parameters (PP) and state (II), and PP -> scan geometry.

use std::f64::consts::TAU;
use std::time::Duration;

use scan_types::{RayStatus, Scan, ScanGeometry};

use crate::UrgError;
use crate::codec::{RawScan, Reply, ScanRequest, info_lines};

fn collect(reply: &Reply<'_>) -> Result<Vec<(String, String)>, UrgError> {
    info_lines(reply)
        .map(|r| r.map(|(k, v)| (k.to_string(), v.to_string())))
        .collect()
}

fn find<'a>(pairs: &'a [(String, String)], key: &str) -> Option<&'a str> {
    pairs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// The VV reply: vendor, product, firmware, protocol and serial number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VersionInfo {
    /// `VEND`.
    pub vendor: String,
    /// `PROD`.
    pub product: String,
    /// `FIRM`.
    pub firmware: String,
    /// `PROT`.
    pub protocol: String,
    /// `SERI`.
    pub serial: String,
    /// Every line as sent, in order (including any extra keys).
    pub lines: Vec<(String, String)>,
}

impl VersionInfo {
    /// Reads a VV reply body.
    pub fn from_reply(reply: &Reply<'_>) -> Result<Self, UrgError> {
        let lines = collect(reply)?;
        let get = |k: &str| find(&lines, k).unwrap_or_default().to_string();
        Ok(VersionInfo {
            vendor: get("VEND"),
            product: get("PROD"),
            firmware: get("FIRM"),
            protocol: get("PROT"),
            serial: get("SERI"),
            lines: lines.clone(),
        })
    }
}

/// The PP reply: the sensor's range limits, angular resolution and step layout.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SensorParams {
    /// `MODL`: model name.
    pub model: String,
    /// `DMIN`: smallest distance, mm; smaller values are error codes.
    pub dmin_mm: u32,
    /// `DMAX`: largest distance, mm.
    pub dmax_mm: u32,
    /// `ARES`: steps per full turn.
    pub ares: u32,
    /// `AMIN`: first measurable step.
    pub amin: u16,
    /// `AMAX`: last measurable step.
    pub amax: u16,
    /// `AFRT`: the step that points straight ahead.
    pub afrt: u16,
    /// `SCAN`: motor speed, revolutions per minute.
    pub scan_rpm: u32,
}

impl SensorParams {
    /// Reads a PP reply body; every numeric key must be present and sane.
    pub fn from_reply(reply: &Reply<'_>) -> Result<Self, UrgError> {
        let lines = collect(reply)?;
        let num = |k: &str| -> Result<u32, UrgError> {
            let v = find(&lines, k).ok_or_else(|| UrgError::Info {
                key: k.into(),
                why: "missing from the PP reply".into(),
            })?;
            v.trim().parse::<u32>().map_err(|_| UrgError::Info {
                key: k.into(),
                why: format!("{v:?} is not a whole number"),
            })
        };
        let step = |k: &str| -> Result<u16, UrgError> {
            u16::try_from(num(k)?).map_err(|_| UrgError::Info {
                key: k.into(),
                why: "step beyond 65535".into(),
            })
        };
        let p = SensorParams {
            model: find(&lines, "MODL").unwrap_or_default().to_string(),
            dmin_mm: num("DMIN")?,
            dmax_mm: num("DMAX")?,
            ares: num("ARES")?,
            amin: step("AMIN")?,
            amax: step("AMAX")?,
            afrt: step("AFRT")?,
            scan_rpm: num("SCAN")?,
        };
        let bad = |key: &str, why: &str| {
            Err(UrgError::Info {
                key: key.into(),
                why: why.into(),
            })
        };
        if p.ares == 0 {
            return bad("ARES", "must be positive");
        }
        if p.amax < p.amin {
            return bad("AMAX", "smaller than AMIN");
        }
        if p.dmax_mm <= p.dmin_mm {
            return bad("DMAX", "not above DMIN");
        }
        if p.scan_rpm == 0 {
            return bad("SCAN", "must be positive");
        }
        Ok(p)
    }

    /// The URG-04LX's parameters as its PP reports them.
    pub fn urg_04lx() -> Self {
        SensorParams {
            model: "URG-04LX(Hokuyo Automatic Co.,Ltd.)".into(),
            dmin_mm: 20,
            dmax_mm: 5600,
            ares: 1024,
            amin: 44,
            amax: 725,
            afrt: 384,
            scan_rpm: 600,
        }
    }

    /// The UTM-30LX's parameters as its PP reports them.
    pub fn utm_30lx() -> Self {
        SensorParams {
            model: "UTM-30LX(Hokuyo Automatic Co.,Ltd.)".into(),
            dmin_mm: 23,
            dmax_mm: 60000,
            ares: 1440,
            amin: 0,
            amax: 1080,
            afrt: 540,
            scan_rpm: 2400,
        }
    }

    /// The UST-10LX's parameters: 1081 steps over 270 deg (step 540 ahead, 1440 per turn),
    /// 2400 rpm (25 ms), DMIN 20 mm and DMAX 30000 mm (UST-10LX data sheet: 0.06 to 10 m
    /// guaranteed, 30 m the largest distance reported).
    pub fn ust_10lx() -> Self {
        SensorParams {
            model: "UST-10LX".into(),
            dmin_mm: 20,
            dmax_mm: 30000,
            ares: 1440,
            amin: 0,
            amax: 1080,
            afrt: 540,
            scan_rpm: 2400,
        }
    }

    /// Bearing of step `step`: `(step - AFRT) * 2 pi / ARES`, radians.
    pub fn step_bearing_rad(&self, step: f64) -> f64 {
        (step - f64::from(self.afrt)) * TAU / f64::from(self.ares)
    }

    /// The time of one revolution.
    pub fn scan_period(&self) -> Duration {
        Duration::from_micros(60_000_000 / u64::from(self.scan_rpm))
    }

    /// The request for every measurable step, cluster 1.
    pub fn full_request(&self, kind: crate::codec::DataKind) -> ScanRequest {
        ScanRequest {
            kind,
            start_step: self.amin,
            end_step: self.amax,
            cluster: 1,
        }
    }

    /// The geometry of every measurable step (AMIN..=AMAX): step s at (s - AFRT) * 2 pi / ARES.
    pub fn geometry(&self) -> ScanGeometry {
        self.geometry_for(&self.full_request(crate::codec::DataKind::Range3))
            .expect("PP values were checked when read")
    }

    /// The geometry of the values a request returns. A cluster's bearing is the mean of its
    /// steps' bearings (its first step plus half the cluster width minus a half step).
    pub fn geometry_for(&self, req: &ScanRequest) -> Result<ScanGeometry, UrgError> {
        let cluster = f64::from(req.cluster.max(1));
        let inc = TAU / f64::from(self.ares);
        let first = self.step_bearing_rad(f64::from(req.start_step) + (cluster - 1.0) / 2.0);
        ScanGeometry::new(
            first,
            inc * cluster,
            req.value_count(),
            f64::from(self.dmin_mm) / 1000.0,
            f64::from(self.dmax_mm) / 1000.0,
        )
        .map_err(|e| UrgError::InvalidValue(format!("scan request gives no geometry: {e}")))
    }

    /// What a value from the sensor means: values below DMIN are error codes (code 0, "no
    /// return", is nothing within range), values at or above DMAX are beyond range.
    pub fn classify_mm(&self, value: u32) -> (f64, RayStatus) {
        let max_m = f64::from(self.dmax_mm) / 1000.0;
        if value < self.dmin_mm {
            if value == 0 {
                (max_m, RayStatus::MaxRange)
            } else {
                (f64::NAN, RayStatus::Error(value as u16))
            }
        } else if value >= self.dmax_mm {
            (max_m, RayStatus::MaxRange)
        } else {
            (f64::from(value) / 1000.0, RayStatus::Hit)
        }
    }

    /// Converts a decoded scan to a `Scan` in metres.
    pub fn to_scan(&self, raw: &RawScan, sensor_time_ms: Option<u64>, host_time_s: f64) -> Scan {
        let mut ranges_m = Vec::with_capacity(raw.ranges_mm.len());
        let mut status = Vec::with_capacity(raw.ranges_mm.len());
        for &v in &raw.ranges_mm {
            let (r, s) = self.classify_mm(v);
            ranges_m.push(r);
            status.push(s);
        }
        let intensities = (!raw.intensities.is_empty())
            .then(|| raw.intensities.iter().map(|&i| i as f32).collect());
        Scan {
            ranges_m,
            status,
            intensities,
            sensor_time_ms,
            host_time_s,
        }
    }
}

/// The II reply: the sensor's current state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateInfo {
    /// `MODL`.
    pub model: String,
    /// `LASR` is `ON`.
    pub laser_on: bool,
    /// `SCSP`: motor speed text.
    pub motor_speed: String,
    /// `MESM`: measurement mode.
    pub measure_mode: String,
    /// `SBPS`: bit rate text.
    pub bit_rate: String,
    /// `TIME`: the timer value, when it reads as 6 hex digits (URG-04LX style).
    pub time_ms: Option<u32>,
    /// `STAT`: the sensor's own diagnosis.
    pub status: String,
    /// Every line as sent, in order.
    pub lines: Vec<(String, String)>,
}

impl StateInfo {
    /// Reads an II reply body.
    pub fn from_reply(reply: &Reply<'_>) -> Result<Self, UrgError> {
        let lines = collect(reply)?;
        let get = |k: &str| find(&lines, k).unwrap_or_default().to_string();
        let time = get("TIME");
        Ok(StateInfo {
            model: get("MODL"),
            laser_on: get("LASR").eq_ignore_ascii_case("ON"),
            motor_speed: get("SCSP"),
            measure_mode: get("MESM"),
            bit_rate: get("SBPS"),
            time_ms: (time.len() == 6)
                .then(|| u32::from_str_radix(&time, 16).ok())
                .flatten(),
            status: get("STAT"),
            lines: lines.clone(),
        })
    }
}

impl std::fmt::Display for VersionInfo {
    /// Every line of the reply as `  KEY  value`, one per line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.lines
            .iter()
            .try_for_each(|(k, v)| writeln!(f, "  {k}  {v}"))
    }
}

impl std::fmt::Display for SensorParams {
    /// Every parameter as `  KEY  value` with its meaning (degrees, milliseconds), then the
    /// scan geometry it gives; one per line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let deg = |step: u16| self.step_bearing_rad(f64::from(step)).to_degrees();
        writeln!(f, "  MODL  {}", self.model)?;
        writeln!(
            f,
            "  DMIN  {} mm (smaller values are error codes)",
            self.dmin_mm
        )?;
        writeln!(f, "  DMAX  {} mm", self.dmax_mm)?;
        writeln!(
            f,
            "  ARES  {} steps per turn ({:.7} deg per step)",
            self.ares,
            360.0 / f64::from(self.ares)
        )?;
        writeln!(f, "  AMIN  step {} ({:.3} deg)", self.amin, deg(self.amin))?;
        writeln!(f, "  AMAX  step {} ({:.3} deg)", self.amax, deg(self.amax))?;
        writeln!(f, "  AFRT  step {} (straight ahead)", self.afrt)?;
        writeln!(
            f,
            "  SCAN  {} rpm ({} ms per scan)",
            self.scan_rpm,
            self.scan_period().as_secs_f64() * 1000.0
        )?;
        let g = self.geometry();
        writeln!(
            f,
            "  geometry: {} rays from {:.3} to {:.3} deg, ranges {} to {} m",
            g.ray_count,
            g.first_bearing_rad.to_degrees(),
            g.last_bearing_rad().to_degrees(),
            g.min_range_m,
            g.max_range_m
        )
    }
}

impl std::fmt::Display for StateInfo {
    /// Every line of the reply as `  KEY  value`, `TIME` with its value in milliseconds.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (k, v) in &self.lines {
            match self.time_ms {
                Some(ms) if k == "TIME" => writeln!(f, "  {k}  {v} ({ms} ms on the sensor clock)")?,
                _ => writeln!(f, "  {k}  {v}")?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn urg_04lx_geometry_from_pp() {
        let p = SensorParams::urg_04lx();
        let g = p.geometry();
        assert_eq!(g.ray_count, 682);
        // Index 340 is step 384 = AFRT: straight ahead.
        assert_abs_diff_eq!(g.bearing_rad(340), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(g.first_bearing_rad.to_degrees(), -119.53125, epsilon = 1e-9);
        assert_abs_diff_eq!(g.increment_rad.to_degrees(), 0.3515625, epsilon = 1e-12);
        assert_eq!(p.scan_period(), Duration::from_millis(100));
        let c = p
            .geometry_for(&ScanRequest {
                cluster: 2,
                ..p.full_request(crate::codec::DataKind::Range3)
            })
            .unwrap();
        assert_eq!(c.ray_count, 341);
        // Steps 44 and 45 averaged.
        assert_abs_diff_eq!(
            c.first_bearing_rad,
            p.step_bearing_rad(44.5),
            epsilon = 1e-12
        );
    }

    #[test]
    fn pp_text_gives_steps_in_degrees() {
        // Step s of the URG-04LX is at (s - 384) * 360 / 1024 deg; 600 rpm is 100 ms a turn.
        let text = SensorParams::urg_04lx().to_string();
        for line in [
            "  DMIN  20 mm (smaller values are error codes)\n",
            "  ARES  1024 steps per turn (0.3515625 deg per step)\n",
            "  AMIN  step 44 (-119.531 deg)\n",
            "  AMAX  step 725 (119.883 deg)\n",
            "  SCAN  600 rpm (100 ms per scan)\n",
            "  geometry: 682 rays from -119.531 to 119.883 deg, ranges 0.02 to 5.6 m\n",
        ] {
            assert!(text.contains(line), "{line:?} not in {text}");
        }
    }

    #[test]
    fn classify_keeps_error_codes() {
        let p = SensorParams::urg_04lx();
        assert_eq!(p.classify_mm(0), (5.6, RayStatus::MaxRange));
        assert!(p.classify_mm(7).0.is_nan());
        assert_eq!(p.classify_mm(7).1, RayStatus::Error(7));
        assert_eq!(p.classify_mm(19).1, RayStatus::Error(19));
        assert_eq!(p.classify_mm(20), (0.02, RayStatus::Hit));
        assert_eq!(p.classify_mm(4152), (4.152, RayStatus::Hit));
        assert_eq!(p.classify_mm(5600).1, RayStatus::MaxRange);
    }
}
