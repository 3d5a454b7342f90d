//! The command handler: what the emulated sensor does with each SCIP command line.

use scan_types::LaserSource;

use super::machine::{GetJob, SensorCore, StreamJob};
use crate::codec::{self, Command, DataKind, ScanRequest, Status, StreamRequest, TimeCode};

impl<S: LaserSource> SensorCore<S> {
    pub(super) fn execute(&mut self, line: &[u8], now_ms: u64) {
        self.control
            .lock()
            .commands
            .push(String::from_utf8_lossy(line).into_owned());
        if self.scip1 {
            return self.execute_scip1(line);
        }
        let (cmd, _tag) = match Command::parse(line) {
            Ok(c) => c,
            Err(status) => return self.reply(line, status),
        };
        if self.time_adjust && !matches!(cmd, Command::Time(_)) {
            // In time-adjust mode every other command is refused as undefined.
            return self.reply(line, Status::UNDEFINED);
        }
        let st = |s: &[u8; 2]| Status(*s);
        match cmd {
            Command::Scip2 => self.reply(line, Status::UNDEFINED),
            Command::Version => {
                let v = self.profile.version.clone();
                self.info_reply(line, &v);
            }
            Command::Parameters => self.parameters_reply(line),
            Command::State => self.state_reply(line, now_ms),
            Command::LaserOn => {
                let s = if self.laser_on { st(b"02") } else { Status::OK };
                self.laser_on = true;
                self.reply(line, s);
            }
            Command::LaserOff => {
                self.laser_on = false;
                self.stream = None;
                self.reply(line, Status::OK);
            }
            Command::Reset => {
                self.laser_on = false;
                self.stream = None;
                self.motor_code = 0;
                self.bit_rate = 19_200;
                self.timer_origin_ms = now_ms;
                self.reply(line, Status::OK);
            }
            Command::Time(code) => self.time_command(line, code, now_ms),
            Command::BitRate(b) => {
                let s = self.bit_rate_status(b);
                self.reply(line, s);
            }
            Command::MotorSpeed(c) => {
                let s = self.motor_speed_status(c);
                self.reply(line, s);
            }
            // Neither emulated firmware has high-sensitivity mode.
            Command::HighSensitivity(_) => self.reply(line, Status::UNDEFINED),
            Command::Get(req) => self.get_command(line, req, now_ms),
            Command::Stream(req) => self.stream_command(line, req, now_ms),
        }
    }

    /// A sensor still in SCIP 1.1 only understands the switch to SCIP 2.0.
    fn execute_scip1(&mut self, line: &[u8]) {
        if line == b"SCIP2.0" {
            self.scip1 = false;
            self.begin_reply();
            self.out.extend(b"SCIP2.0\n0\n\n");
        } else {
            // SCIP 1.1 answers SCIP 2.0 commands with a one-character error status.
            self.begin_reply();
            self.out.extend(line);
            self.out.extend(b"\nE\n\n");
        }
    }

    /// PP: the sensor parameters.
    fn parameters_reply(&mut self, line: &[u8]) {
        let p = self.profile.params.clone();
        let kv = |k: &str, v: String| (k.to_string(), v);
        let lines = vec![
            kv("MODL", p.model.clone()),
            kv("DMIN", p.dmin_mm.to_string()),
            kv("DMAX", p.dmax_mm.to_string()),
            kv("ARES", p.ares.to_string()),
            kv("AMIN", p.amin.to_string()),
            kv("AMAX", p.amax.to_string()),
            kv("AFRT", p.afrt.to_string()),
            kv("SCAN", p.scan_rpm.to_string()),
        ];
        self.info_reply(line, &lines);
    }

    /// II: the sensor state at `now_ms`.
    fn state_reply(&mut self, line: &[u8], now_ms: u64) {
        let p = self.profile.params.clone();
        let kv = |k: &str, v: String| (k.to_string(), v);
        let motor = if self.motor_code == 0 {
            self.profile.motor_text.clone()
        } else {
            format!("Level {}", self.motor_code)
        };
        let lines = vec![
            kv("MODL", p.model.clone()),
            kv("LASR", if self.laser_on { "ON" } else { "OFF" }.into()),
            kv("SCSP", motor),
            kv("MESM", "CLASSIC".into()),
            kv("SBPS", self.profile.bit_rate_text.clone()),
            kv("TIME", format!("{:06X}", self.timer(now_ms))),
            kv("STAT", "Sensor works well.".into()),
        ];
        self.info_reply(line, &lines);
    }

    /// TM0/TM1/TM2: entering, reading and leaving time-adjust mode.
    fn time_command(&mut self, line: &[u8], code: TimeCode, now_ms: u64) {
        let st = |s: &[u8; 2]| Status(*s);
        match (code, self.time_adjust) {
            (TimeCode::Enter, true) => self.reply(line, st(b"02")),
            (TimeCode::Enter, false) => {
                self.time_adjust = true;
                self.laser_on = false;
                self.stream = None;
                self.reply(line, Status::OK);
            }
            (TimeCode::Read, false) => self.reply(line, st(b"04")),
            (TimeCode::Read, true) => {
                self.reply_no_blank(line, Status::OK);
                let mut v = Vec::with_capacity(8);
                let t = self.timer(now_ms);
                codec::encode_value(t, 4, &mut v).expect("24-bit timer fits 4 chars");
                let sum = codec::checksum(&v);
                v.push(sum);
                v.extend_from_slice(b"\n\n");
                self.out.extend(v);
            }
            (TimeCode::Leave, false) => self.reply(line, st(b"03")),
            (TimeCode::Leave, true) => {
                self.time_adjust = false;
                self.reply(line, Status::OK);
            }
        }
    }

    /// SS: the status of a bit-rate change (made when it is OK).
    fn bit_rate_status(&mut self, b: u32) -> Status {
        let st = |s: &[u8; 2]| Status(*s);
        if !self.profile.serial_settings {
            st(b"04")
        } else if ![19_200, 38_400, 57_600, 115_200, 250_000, 500_000, 750_000].contains(&b) {
            st(b"02")
        } else if b == self.bit_rate {
            st(b"03")
        } else {
            self.bit_rate = b;
            Status::OK
        }
    }

    /// CR: the status of a motor-speed change (made when it is OK).
    fn motor_speed_status(&mut self, c: u8) -> Status {
        let st = |s: &[u8; 2]| Status(*s);
        if !self.profile.serial_settings {
            st(b"04")
        } else if c == 99 {
            self.motor_code = 0;
            Status::OK
        } else if c > 10 {
            st(b"02")
        } else if c == self.motor_code {
            st(b"03")
        } else {
            self.motor_code = c;
            Status::OK
        }
    }

    /// GD/GS/GE: one scan, stamped with a fresh scan time and answered when that scan is done.
    fn get_command(&mut self, line: &[u8], req: ScanRequest, now_ms: u64) {
        let st = |s: &[u8; 2]| Status(*s);
        if let Some(s) = self.check_request(&req) {
            return self.reply(line, s);
        }
        if !self.laser_on {
            return self.reply(line, st(b"10"));
        }
        let period = self.profile.params.scan_period().as_millis().max(1) as u64;
        // Each GD takes a fresh scan from the source, so it gets a fresh scan time: the latest
        // scan start, or the next one if that was already served, which the reply waits for.
        let mut stamp = now_ms - now_ms % period;
        if let Some(last) = self.last_get_stamp_ms
            && stamp <= last
        {
            stamp = last + period;
        }
        self.last_get_stamp_ms = Some(stamp);
        if stamp <= now_ms {
            self.scan_reply(line, &req, Status::OK, stamp);
        } else {
            self.get = Some(GetJob {
                echo: line.to_vec(),
                req,
                due_ms: stamp,
            });
        }
    }

    /// MD/MS/ME: starts streaming from the next scan start.
    fn stream_command(&mut self, line: &[u8], req: StreamRequest, now_ms: u64) {
        if let Some(s) = self.check_request(&req.scan) {
            return self.reply(line, s);
        }
        self.laser_on = true;
        self.reply(line, Status::OK);
        let period = self.profile.params.scan_period().as_millis().max(1) as u64;
        self.stream = Some(StreamJob {
            req,
            echo: line.to_vec(),
            remaining: (req.count > 0).then_some(u32::from(req.count)),
            next_due_ms: now_ms - now_ms % period + period,
            interval_ms: period * (u64::from(req.skip) + 1),
        });
    }

    fn check_request(&self, req: &ScanRequest) -> Option<Status> {
        let p = &self.profile.params;
        if req.kind == DataKind::RangeIntensity && !self.profile.intensity {
            return Some(Status::UNDEFINED);
        }
        if req.start_step < p.amin || req.start_step > p.amax {
            return Some(Status(*b"04"));
        }
        if req.end_step > p.amax {
            return Some(Status(*b"04"));
        }
        if req.end_step < req.start_step {
            return Some(Status(*b"05"));
        }
        None
    }
}
