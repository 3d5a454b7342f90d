//! The emulated models and what each reports (VV/PP/II text) and supports.

use std::str::FromStr;

use crate::info::SensorParams;

/// The emulated sensor model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    /// Hokuyo URG-04LX (firmware 3.1.04, as in the shared capture).
    Urg04lx,
    /// Hokuyo UTM-30LX (firmware 1.05, as in the shared capture), with intensities.
    Utm30lx,
    /// Hokuyo UST-10LX, an Ethernet model (SCIP 2.0 over TCP, port 10940), with intensities.
    Ust10lx,
}

impl Model {
    /// The model's name as [`Model::from_str`] reads it: `urg-04lx`, `utm-30lx` or `ust-10lx`.
    pub fn name(self) -> &'static str {
        match self {
            Model::Urg04lx => "urg-04lx",
            Model::Utm30lx => "utm-30lx",
            Model::Ust10lx => "ust-10lx",
        }
    }
}

impl FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "urg-04lx" | "urg04lx" => Ok(Model::Urg04lx),
            "utm-30lx" | "utm30lx" => Ok(Model::Utm30lx),
            "ust-10lx" | "ust10lx" => Ok(Model::Ust10lx),
            _ => Err(format!(
                "unknown sensor model {s:?}: expected urg-04lx, utm-30lx or ust-10lx"
            )),
        }
    }
}

/// What an emulated model reports and supports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Profile {
    /// PP values.
    pub params: SensorParams,
    /// VV lines, in order.
    pub version: Vec<(String, String)>,
    /// `SBPS` text of II.
    pub bit_rate_text: String,
    /// `SCSP` text of II at the default speed.
    pub motor_text: String,
    /// Whether GE/ME (range + intensity) exist.
    pub intensity: bool,
    /// Whether SS/CR are supported (URG-04LX) or answer `04` (UTM-30LX).
    pub serial_settings: bool,
    /// Whether the sensor powers up in SCIP 1.1 (a factory URG-04LX does).
    pub scip1_at_power_up: bool,
}

impl Profile {
    /// The profile of `model`, with VV/PP/II text as the real captures show it.
    pub fn of(model: Model) -> Profile {
        let kv = |a: &str, b: &str| (a.to_string(), b.to_string());
        match model {
            Model::Urg04lx => Profile {
                params: SensorParams::urg_04lx(),
                version: vec![
                    kv("VEND", "Hokuyo Automatic Co.,Ltd."),
                    kv("PROD", "SOKUIKI Sensor URG-04LX"),
                    kv("FIRM", "3.1.04(02/Aug./2007)"),
                    kv("PROT", "SCIP 2.0"),
                    kv("SERI", "H0706400"),
                ],
                bit_rate_text: "19200[bps]<-Default setting by user".into(),
                motor_text: "Initial(600[rpm])<-Default setting by user".into(),
                intensity: false,
                serial_settings: true,
                scip1_at_power_up: false,
            },
            Model::Utm30lx => Profile {
                params: SensorParams::utm_30lx(),
                version: vec![
                    kv("VEND", "Hokuyo Automatic Co.,Ltd."),
                    kv("PROD", "SOKUIKI Sensor TOP-URG UTM-30LX"),
                    kv("FIRM", "P.1.05(17/Apr./2009)"),
                    kv("PROT", "SCIP 2.0"),
                    kv("SERI", "00903971"),
                ],
                bit_rate_text: "USB Full Speed".into(),
                motor_text: "Initial(2400[rpm])<-Default setting by user".into(),
                intensity: true,
                serial_settings: false,
                scip1_at_power_up: false,
            },
            // No capture of a UST-10LX is at hand: PP follows its data sheet, the VV text
            // is ours (Ethernet, no serial settings).
            Model::Ust10lx => Profile {
                params: SensorParams::ust_10lx(),
                version: vec![
                    kv("VEND", "Hokuyo Automatic Co.,Ltd."),
                    kv("PROD", "SOKUIKI Sensor UST-10LX"),
                    kv("FIRM", "1.0.0(emulated)"),
                    kv("PROT", "SCIP 2.0"),
                    kv("SERI", "EMU10LX01"),
                ],
                bit_rate_text: "Ethernet 100[Mbps]".into(),
                motor_text: "Initial(2400[rpm])<-Default setting by user".into(),
                intensity: true,
                serial_settings: false,
                scip1_at_power_up: false,
            },
        }
    }
}

/// The bearing of `step` of `model` (radians), handy for building sources.
pub fn step_bearing_rad(model: Model, step: u16) -> f64 {
    Profile::of(model).params.step_bearing_rad(f64::from(step))
}
