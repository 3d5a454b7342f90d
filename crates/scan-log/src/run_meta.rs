//! The metadata a recording of a simulated run carries: the run's settings, so a replay through
//! the loop can repeat it, and the legs it drove, so the replay can be compared with them.
//! Values are JSON text (floats round-trip exactly) in MCAP metadata records.

use std::collections::BTreeMap;
use std::path::Path;

use scan_types::{Pose2, WorldPoint};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::{LogError, read_mcap_metadata};

/// Name of the MCAP metadata record with the settings of a recorded simulated run.
pub const RUN_METADATA: &str = "goalseek.run";
/// Name of the MCAP metadata record with the legs a recorded run drove.
pub const LEGS_METADATA: &str = "goalseek.legs";

/// The settings of a recorded run, `C` being the loop's tuning: what a replay needs to repeat it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings<C> {
    /// Start pose (the estimate's origin).
    pub start: Pose2,
    /// Target.
    pub goal: WorldPoint,
    /// Tuning of the loop.
    pub config: C,
    /// World name (information only).
    pub world: String,
    /// Sensor preset name (information only).
    pub sensor: String,
    /// Noise seed (information only).
    pub seed: u64,
    /// Noise on (information only).
    pub noise: bool,
}

/// A pose in metadata: `{x_m, y_m, heading_rad}` (recordings before the unit names: `[x, y, theta]`).
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
enum PoseJson {
    Named {
        x_m: f64,
        y_m: f64,
        heading_rad: f64,
    },
    Bare([f64; 3]),
}

impl PoseJson {
    fn of([x_m, y_m, heading_rad]: [f64; 3]) -> Self {
        Self::Named {
            x_m,
            y_m,
            heading_rad,
        }
    }

    fn get(self) -> [f64; 3] {
        match self {
            Self::Named {
                x_m,
                y_m,
                heading_rad,
            } => [x_m, y_m, heading_rad],
            Self::Bare(p) => p,
        }
    }
}

/// A point in metadata: `{x_m, y_m}` (recordings before the unit names: `[x, y]`).
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
enum PointJson {
    Named { x_m: f64, y_m: f64 },
    Bare([f64; 2]),
}

impl PointJson {
    fn of([x_m, y_m]: [f64; 2]) -> Self {
        Self::Named { x_m, y_m }
    }

    fn get(self) -> [f64; 2] {
        match self {
            Self::Named { x_m, y_m } => [x_m, y_m],
            Self::Bare(p) => p,
        }
    }
}

/// Serde of a `[x, y, heading rad]` field as [`PoseJson`].
mod pose_field {
    pub fn serialize<S: serde::Serializer>(p: &[f64; 3], s: S) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(&super::PoseJson::of(*p), s)
    }
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
        <super::PoseJson as serde::Deserialize>::deserialize(d).map(super::PoseJson::get)
    }
}

/// Serde of an optional `[x, y]` field as [`PointJson`] or `null`.
mod point_field {
    pub fn serialize<S: serde::Serializer>(p: &Option<[f64; 2]>, s: S) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(&p.map(super::PointJson::of), s)
    }
    pub fn deserialize<'de, D: serde::Deserializer<'de>>(
        d: D,
    ) -> Result<Option<[f64; 2]>, D::Error> {
        <Option<super::PointJson> as serde::Deserialize>::deserialize(d)
            .map(|p| p.map(super::PointJson::get))
    }
}

fn json_of<T: Serialize>(v: &T) -> String {
    serde_json::to_string(v).expect("plain data serialises")
}

fn json_field<T: DeserializeOwned>(m: &BTreeMap<String, String>, key: &str) -> Result<T, LogError> {
    let text = m.get(key).ok_or_else(|| LogError::Metadata {
        context: format!("metadata '{RUN_METADATA}' has no '{key}'"),
        source: None,
    })?;
    serde_json::from_str(text).map_err(|e| LogError::Metadata {
        context: format!("metadata '{RUN_METADATA}': '{key}' = {text:?}"),
        source: Some(e),
    })
}

/// The first metadata record of the recording at `path` named `name`, if any.
fn find_metadata(path: &Path, name: &str) -> Result<Option<BTreeMap<String, String>>, LogError> {
    let meta = read_mcap_metadata(path)?;
    Ok(meta.into_iter().find(|(n, _)| n == name).map(|(_, m)| m))
}

/// `error` with `path` in front of its context.
fn at(path: &Path, error: LogError) -> LogError {
    match error {
        LogError::Metadata { context, source } => LogError::Metadata {
            context: format!("{}: {context}", path.display()),
            source,
        },
        other => other,
    }
}

impl<C: Serialize + DeserializeOwned> RunSettings<C> {
    /// The settings as MCAP metadata ([`RUN_METADATA`]).
    pub fn to_metadata(&self) -> BTreeMap<String, String> {
        let p = self.start;
        BTreeMap::from([
            (
                "start".into(),
                json_of(&PoseJson::of([p.x_m, p.y_m, p.theta_rad])),
            ),
            (
                "goal".into(),
                json_of(&PointJson::of([self.goal.x_m(), self.goal.y_m()])),
            ),
            ("config".into(), json_of(&self.config)),
            ("world".into(), json_of(&self.world)),
            ("sensor".into(), json_of(&self.sensor)),
            ("seed".into(), json_of(&self.seed)),
            ("noise".into(), json_of(&self.noise)),
        ])
    }

    /// Reads the settings back from [`RunSettings::to_metadata`] (the tuning unvalidated).
    pub fn from_metadata(m: &BTreeMap<String, String>) -> Result<Self, LogError> {
        let [x_m, y_m, theta_rad] = json_field::<PoseJson>(m, "start")?.get();
        let [gx, gy] = json_field::<PointJson>(m, "goal")?.get();
        Ok(Self {
            start: Pose2 {
                x_m,
                y_m,
                theta_rad,
            },
            goal: WorldPoint::new(gx, gy),
            config: json_field(m, "config")?,
            world: json_field(m, "world")?,
            sensor: json_field(m, "sensor")?,
            seed: json_field(m, "seed")?,
            noise: json_field(m, "noise")?,
        })
    }

    /// The settings stored in the recording at `path`.
    pub fn read(path: &Path) -> Result<Self, LogError> {
        let m = find_metadata(path, RUN_METADATA)?.ok_or_else(|| LogError::Metadata {
            context: format!(
                "{}: no '{RUN_METADATA}' metadata (not a recording of `robot-app sim --record`)",
                path.display()
            ),
            source: None,
        })?;
        Self::from_metadata(&m).map_err(|e| at(path, e))
    }
}

/// One leg as a run recorded it: where it ended by the estimate, its landmark and point B.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LegSummary {
    /// Leg number (0 = start).
    pub leg: usize,
    /// Estimate at the end of the leg: x, y (m), heading (rad); `{x_m, y_m, heading_rad}` in
    /// the metadata.
    #[serde(with = "pose_field")]
    pub estimate: [f64; 3],
    /// The landmark the leg localised on (world frame by the estimate), `{x_m, y_m}`.
    #[serde(with = "point_field")]
    pub landmark: Option<[f64; 2]>,
    /// Point B of the leg, `{x_m, y_m}`.
    #[serde(with = "point_field")]
    pub point_b: Option<[f64; 2]>,
}

/// The [`LEGS_METADATA`] record of a run that drove `legs` and ended for `reason`.
pub fn legs_metadata(legs: &[LegSummary], reason: &str) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("legs".to_string(), json_of(&legs)),
        ("reason".to_string(), json_of(&reason)),
    ])
}

impl std::fmt::Display for LegSummary {
    /// `leg 3: estimate (x, y, theta rad), landmark (x, y), point B (x, y)`, every number
    /// written in full (shortest form that reads back to the same bits), `none` where absent.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let point =
            |p: Option<[f64; 2]>| p.map_or("none".to_string(), |[x, y]| format!("({x}, {y})"));
        let [x, y, theta] = self.estimate;
        write!(
            f,
            "leg {}: estimate ({x}, {y}, {theta} rad), landmark {}, point B {}",
            self.leg,
            point(self.landmark),
            point(self.point_b)
        )
    }
}

/// The first row where the `replayed` legs differ from the `recorded` ones, as
/// `row I: recorded LEG; replayed LEG` (`nothing (N rows in all)` past a list's end), or
/// `None` when they are the same.
pub fn leg_difference(recorded: &[LegSummary], replayed: &[LegSummary]) -> Option<String> {
    let i = recorded
        .iter()
        .zip(replayed)
        .position(|(a, b)| a != b)
        .or_else(|| {
            (recorded.len() != replayed.len()).then(|| recorded.len().min(replayed.len()))
        })?;
    let row = |legs: &[LegSummary], what: &str| {
        legs.get(i).map_or_else(
            || format!("{what} nothing ({} rows in all)", legs.len()),
            |l| format!("{what} {l}"),
        )
    };
    Some(format!(
        "row {i}: {}; {}",
        row(recorded, "recorded"),
        row(replayed, "replayed")
    ))
}

impl crate::McapRecorder {
    /// Writes the legs of a finished run that ended for `reason` ([`LEGS_METADATA`]).
    pub fn write_legs(&mut self, legs: &[LegSummary], reason: &str) -> Result<(), LogError> {
        self.write_metadata(LEGS_METADATA, &legs_metadata(legs, reason))
    }
}

/// The end reason and the legs stored in the recording at `path`, if it stores them.
pub fn read_recorded_legs(path: &Path) -> Result<Option<(String, Vec<LegSummary>)>, LogError> {
    let Some(m) = find_metadata(path, LEGS_METADATA)? else {
        return Ok(None);
    };
    let legs = m.get("legs").ok_or_else(|| LogError::Metadata {
        context: format!("{}: '{LEGS_METADATA}' without 'legs'", path.display()),
        source: None,
    })?;
    let legs = serde_json::from_str(legs).map_err(|e| LogError::Metadata {
        context: format!("{}: '{LEGS_METADATA}' legs", path.display()),
        source: Some(e),
    })?;
    // JSON text; recordings before it was quoted hold the bare word.
    let reason = m.get("reason").map_or_else(String::new, |r| {
        serde_json::from_str::<String>(r).unwrap_or_else(|_| r.clone())
    });
    Ok(Some((reason, legs)))
}
