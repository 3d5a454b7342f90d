//! Every tuning parameter of the goal-seeking loop in one TOML-loadable struct.
//!
//! A run starts from a preset (`--method goalseek`, the default, or `--method paper`, the
//! paper as written) and a `--config FILE` overrides any subset of its keys. Unknown keys are
//! errors that name the key and its line. The defaults are documented in `docs/robot-app.md`.

use std::path::Path;
use std::str::FromStr;

use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};

/// Which variant of the method to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The paper as written: greedy ray choice, commanded heading, the paper's landmark rule.
    Paper,
    /// goalseek's default: map path, scan-measured rotation, stability rules, tight gate.
    #[default]
    Goalseek,
}

impl FromStr for Method {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Self> {
        match s {
            "paper" => Ok(Method::Paper),
            "goalseek" => Ok(Method::Goalseek),
            other => bail!("unknown method '{other}' (expected paper or goalseek)"),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Paper => "paper",
            Method::Goalseek => "goalseek",
        })
    }
}

/// How the next ray is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanRuleCfg {
    /// The paper: the safe ray whose clear stretch passes closest to the target.
    Greedy,
    /// goalseek: the safe ray with the shortest path to the target over the robot's own map.
    MapPath,
}

/// Where the heading after a rotation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadingRuleCfg {
    /// The paper: theta += commanded alpha.
    Commanded,
    /// The shift that best aligns the scans before and after the rotation.
    ScanMeasured,
    /// goalseek: the shift, refined by matching the two scans' surfaces (point-to-line ICP).
    ScanMatched,
}

/// The robot and the obstacle expansion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotCfg {
    /// Robot radius r, metres (the paper: 0.3).
    pub radius_m: f64,
    /// Extra margin added to r when expanding obstacles, metres.
    pub expansion_margin_m: f64,
}

/// Path selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerCfg {
    /// Ray choice rule.
    pub rule: PlanRuleCfg,
    /// Shortest clear stretch a ray needs to count as safe, metres.
    pub min_travel_m: f64,
    /// Longest leg driven without a landmark fix, metres.
    pub max_leg_m: f64,
    /// Cell size of the planner's own obstacle grid (map_path), metres.
    pub grid_resolution_m: f64,
    /// A ray's clearance is the smallest over the rays within this bearing of it, degrees
    /// (the robot's width; the same window checks the way ahead after the rotation). 0 = the
    /// ray alone (the paper).
    pub width_window_deg: f64,
    /// While the robot turns in place, hits seen earlier from the same spot that have left the
    /// field of view still cut the rays' clearance (the paper: no memory).
    pub remember_turned_away_hits: bool,
}

/// Where the distance driven on a leg comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TravelRuleCfg {
    /// The paper: the tracked landmark (OB minus its current distance ahead), else the command.
    Landmark,
    /// goalseek: the landmark's figure refined by matching the scan at the leg's end against
    /// the scans at its start (point-to-line ICP), which also measures the sideways drift.
    ScanMatched,
}

/// Landmark detection and selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkCfg {
    /// Neighbour offset n of the jump rule (ray x in A, ray x +/- n not in A).
    pub neighbour_n: usize,
    /// Landmarks count only within this bearing of the central ray, degrees (the paper: 90).
    pub max_bearing_deg: f64,
    /// Hits closer than this to the maximum range are not landmarks (range-limit artefacts), metres.
    pub range_limit_margin_m: f64,
    /// Also use occlusion edges (range jumps between two hits).
    pub occlusion_edges: bool,
    /// Also select corners (two straight arms meeting at an angle) as landmarks; the paper
    /// selects only max-range jumps. Tracking re-identifies every kind either way.
    pub corners: bool,
    /// Smallest range jump that makes an occlusion edge, metres.
    pub min_jump_m: f64,
    /// Smallest OB (distance to drive to B) for a landmark to be usable, metres.
    pub min_ob_m: f64,
    /// Smallest |CB| (distance of the landmark from the path), metres.
    pub min_cb_m: f64,
}

/// Tracking the landmark while driving to B.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackingCfg {
    /// Length of one forward step between scans, metres.
    pub step_m: f64,
    /// Re-identification gate around the predicted landmark point, metres.
    pub gate_m: f64,
    /// Scans in a row the landmark may be missed before it counts as lost.
    pub max_missed_scans: usize,
}

/// Localisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocaliserCfg {
    /// Heading update rule.
    pub heading_rule: HeadingRuleCfg,
    /// Half-width of the search around the commanded rotation, degrees.
    pub rotation_search_deg: f64,
    /// Travel rule of a leg.
    pub travel_rule: TravelRuleCfg,
    /// While driving, a new reference scan for matching every this many metres.
    pub keyframe_m: f64,
    /// Standard deviation of a drive's guessed end (landmark or command) at zero distance,
    /// metres: what scan matching weighs the data against.
    pub match_prior_m: f64,
    /// ... growing by this much per metre driven (the base's drive scale error).
    pub match_prior_per_m: f64,
    /// Occupancy grid cell size, metres.
    pub map_resolution_m: f64,
}

/// The loop itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NavigatorCfg {
    /// Most legs before the run gives up (reason leg_limit).
    pub max_legs: usize,
    /// The estimate within this of the target counts as arrival, metres.
    pub goal_tolerance_m: f64,
    /// Planning failures in a row (no safe ray, no progress) before the goal is unreachable.
    pub max_failed_tries: usize,
    /// Turn in place by this much when no safe ray exists, degrees.
    pub recovery_turn_deg: f64,
}

/// Every tuning parameter of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The preset these values started from.
    pub method: Method,
    /// Robot and expansion.
    pub robot: RobotCfg,
    /// Path selection.
    pub planner: PlannerCfg,
    /// Landmark detection and selection.
    pub landmarks: LandmarkCfg,
    /// Landmark tracking.
    pub tracking: TrackingCfg,
    /// Localisation and mapping.
    pub localiser: LocaliserCfg,
    /// The loop.
    pub navigator: NavigatorCfg,
}

impl Default for Config {
    fn default() -> Self {
        Self::preset(Method::Goalseek)
    }
}

impl Config {
    /// The preset of a method: goalseek's defaults, or the paper as written.
    pub fn preset(method: Method) -> Self {
        let goalseek = Config {
            method: Method::Goalseek,
            robot: RobotCfg {
                radius_m: 0.3,
                expansion_margin_m: 0.1,
            },
            planner: PlannerCfg {
                rule: PlanRuleCfg::MapPath,
                min_travel_m: 0.3,
                max_leg_m: 3.0,
                grid_resolution_m: 0.1,
                width_window_deg: 2.0,
                remember_turned_away_hits: true,
            },
            landmarks: LandmarkCfg {
                neighbour_n: 1,
                max_bearing_deg: 90.0,
                range_limit_margin_m: 0.15,
                occlusion_edges: false,
                corners: false,
                min_jump_m: 0.5,
                min_ob_m: 0.2,
                min_cb_m: 0.15,
            },
            tracking: TrackingCfg {
                step_m: 0.05,
                gate_m: 0.06,
                max_missed_scans: 3,
            },
            localiser: LocaliserCfg {
                heading_rule: HeadingRuleCfg::ScanMatched,
                rotation_search_deg: 6.0,
                travel_rule: TravelRuleCfg::ScanMatched,
                keyframe_m: 1.0,
                match_prior_m: 0.005,
                match_prior_per_m: 0.02,
                map_resolution_m: 0.05,
            },
            navigator: NavigatorCfg {
                max_legs: 60,
                goal_tolerance_m: 0.15,
                max_failed_tries: 8,
                recovery_turn_deg: 60.0,
            },
        };
        match method {
            Method::Goalseek => goalseek,
            Method::Paper => {
                let mut c = goalseek;
                c.method = Method::Paper;
                c.robot.expansion_margin_m = 0.0;
                c.planner.rule = PlanRuleCfg::Greedy;
                c.planner.width_window_deg = 0.0;
                c.planner.remember_turned_away_hits = false;
                c.landmarks.range_limit_margin_m = 0.0;
                c.tracking.gate_m = 0.2;
                c.localiser.heading_rule = HeadingRuleCfg::Commanded;
                c.localiser.travel_rule = TravelRuleCfg::Landmark;
                c
            }
        }
    }

    /// Loads a preset overridden by a TOML file. `method` on the command line wins over a
    /// `method` key in the file; without either the preset is goalseek.
    pub fn load(path: Option<&Path>, method: Option<Method>) -> anyhow::Result<Self> {
        match path {
            None => Ok(Self::preset(method.unwrap_or_default())),
            Some(p) => {
                let text = std::fs::read_to_string(p)
                    .with_context(|| format!("cannot read config {}", p.display()))?;
                Self::from_toml_str(&text, method)
                    .with_context(|| format!("config {}", p.display()))
            }
        }
    }

    /// Parses TOML text over the preset (see [`Config::load`]).
    pub fn from_toml_str(text: &str, method: Option<Method>) -> anyhow::Result<Self> {
        let user: toml::Table = toml::from_str(text)?;
        let file_method =
            match user.get("method") {
                None => None,
                Some(toml::Value::String(s)) => Some(s.parse::<Method>().with_context(|| {
                    format!("line {}: key 'method'", line_of(text, "", "method"))
                })?),
                Some(_) => bail!(
                    "line {}: key 'method' must be a string",
                    line_of(text, "", "method")
                ),
            };
        let preset = Self::preset(method.or(file_method).unwrap_or_default());
        let mut merged = toml::Table::try_from(&preset).context("serialising the preset")?;
        merge(&mut merged, &user, "", text)?;
        // The command line's method names the preset actually used.
        merged.insert(
            "method".into(),
            toml::Value::String(preset.method.to_string()),
        );
        let cfg: Config = merged
            .try_into()
            .context("config value of the wrong type")?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// The configuration as TOML text (what `--config` accepts).
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Checks ranges of values that would make the loop meaningless.
    pub fn validate(&self) -> anyhow::Result<()> {
        let pos = |name: &str, v: f64| -> anyhow::Result<()> {
            if !(v.is_finite() && v > 0.0) {
                bail!("{name} = {v} must be a positive number");
            }
            Ok(())
        };
        let nonneg = |name: &str, v: f64| -> anyhow::Result<()> {
            if !(v.is_finite() && v >= 0.0) {
                bail!("{name} = {v} must be a number >= 0");
            }
            Ok(())
        };
        pos("robot.radius_m", self.robot.radius_m)?;
        nonneg("robot.expansion_margin_m", self.robot.expansion_margin_m)?;
        pos("planner.min_travel_m", self.planner.min_travel_m)?;
        pos("planner.max_leg_m", self.planner.max_leg_m)?;
        pos("planner.grid_resolution_m", self.planner.grid_resolution_m)?;
        nonneg("planner.width_window_deg", self.planner.width_window_deg)?;
        pos("landmarks.max_bearing_deg", self.landmarks.max_bearing_deg)?;
        nonneg(
            "landmarks.range_limit_margin_m",
            self.landmarks.range_limit_margin_m,
        )?;
        nonneg("landmarks.min_ob_m", self.landmarks.min_ob_m)?;
        nonneg("landmarks.min_cb_m", self.landmarks.min_cb_m)?;
        pos("landmarks.min_jump_m", self.landmarks.min_jump_m)?;
        if self.landmarks.neighbour_n == 0 {
            bail!("landmarks.neighbour_n must be at least 1");
        }
        pos("tracking.step_m", self.tracking.step_m)?;
        pos("tracking.gate_m", self.tracking.gate_m)?;
        pos(
            "localiser.rotation_search_deg",
            self.localiser.rotation_search_deg,
        )?;
        pos("localiser.keyframe_m", self.localiser.keyframe_m)?;
        pos("localiser.match_prior_m", self.localiser.match_prior_m)?;
        nonneg(
            "localiser.match_prior_per_m",
            self.localiser.match_prior_per_m,
        )?;
        pos(
            "localiser.map_resolution_m",
            self.localiser.map_resolution_m,
        )?;
        pos(
            "navigator.goal_tolerance_m",
            self.navigator.goal_tolerance_m,
        )?;
        pos(
            "navigator.recovery_turn_deg",
            self.navigator.recovery_turn_deg,
        )?;
        if self.navigator.max_legs == 0 {
            bail!("navigator.max_legs must be at least 1");
        }
        Ok(())
    }
}

/// Overlays `user` onto `base`, refusing keys `base` does not have.
fn merge(
    base: &mut toml::Table,
    user: &toml::Table,
    prefix: &str,
    text: &str,
) -> anyhow::Result<()> {
    for (key, value) in user {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match (base.get_mut(key), value) {
            (None, _) => bail!("line {}: unknown key '{path}'", line_of(text, prefix, key)),
            (Some(toml::Value::Table(b)), toml::Value::Table(u)) => merge(b, u, &path, text)?,
            (Some(toml::Value::Table(_)), _) => bail!(
                "line {}: '{path}' must be a table ([{path}])",
                line_of(text, prefix, key)
            ),
            (Some(slot), v) => {
                if std::mem::discriminant(slot) != std::mem::discriminant(v)
                    && !matches!(
                        (&*slot, v),
                        (toml::Value::Float(_), toml::Value::Integer(_))
                    )
                {
                    bail!(
                        "line {}: '{path}' has the wrong type (expected {}, found {})",
                        line_of(text, prefix, key),
                        slot.type_str(),
                        v.type_str()
                    );
                }
                *slot = match (&*slot, v) {
                    (toml::Value::Float(_), toml::Value::Integer(i)) => {
                        toml::Value::Float(*i as f64)
                    }
                    _ => v.clone(),
                };
            }
        }
    }
    Ok(())
}

/// The 1-based line where `key` is set inside table `section` ("" = top level); 0 if not found.
fn line_of(text: &str, section: &str, key: &str) -> usize {
    let full = if section.is_empty() {
        key.to_string()
    } else {
        format!("{section}.{key}")
    };
    let mut current = String::new();
    for (n, line) in text.lines().enumerate() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix('[') {
            current = rest
                .trim_start_matches('[')
                .trim_end_matches(']')
                .trim()
                .to_string();
            if current == full {
                return n + 1;
            }
            continue;
        }
        let is_key = |k: &str| {
            t.strip_prefix(k)
                .is_some_and(|r| r.trim_start().starts_with('='))
        };
        if (current == section && is_key(key)) || (current.is_empty() && is_key(&full)) {
            return n + 1;
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_differ_where_the_paper_differs() {
        let p = Config::preset(Method::Paper);
        let g = Config::preset(Method::Goalseek);
        assert_eq!(p.planner.rule, PlanRuleCfg::Greedy);
        assert_eq!(g.planner.rule, PlanRuleCfg::MapPath);
        assert_eq!(p.localiser.heading_rule, HeadingRuleCfg::Commanded);
        assert_eq!(g.localiser.heading_rule, HeadingRuleCfg::ScanMatched);
        assert_eq!(p.robot.expansion_margin_m, 0.0);
        assert_eq!(g.robot.expansion_margin_m, 0.1);
        assert_eq!(g.navigator.max_legs, 60);
        assert_eq!(p.robot.radius_m, 0.3);
    }

    #[test]
    fn file_overrides_a_subset() {
        let c = Config::from_toml_str(
            "[tracking]\ngate_m = 0.1\n[navigator]\nmax_legs = 5\n",
            None,
        )
        .unwrap();
        assert_eq!(c.tracking.gate_m, 0.1);
        assert_eq!(c.navigator.max_legs, 5);
        assert_eq!(c.tracking.step_m, 0.05);
        assert_eq!(c.method, Method::Goalseek);
    }

    #[test]
    fn integer_accepted_for_float() {
        let c = Config::from_toml_str("[robot]\nradius_m = 1\n", None).unwrap();
        assert_eq!(c.robot.radius_m, 1.0);
    }

    #[test]
    fn method_from_file_and_command_line() {
        let c = Config::from_toml_str("method = \"paper\"\n", None).unwrap();
        assert_eq!(c.planner.rule, PlanRuleCfg::Greedy);
        let c = Config::from_toml_str("method = \"paper\"\n", Some(Method::Goalseek)).unwrap();
        assert_eq!(c.planner.rule, PlanRuleCfg::MapPath);
        assert_eq!(c.method, Method::Goalseek);
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let e = Config::from_toml_str("[tracking]\ngate_m = 0.1\ngait_m = 2\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("tracking.gait_m"), "{msg}");
        assert!(msg.contains("line 3"), "{msg}");
        let e = Config::from_toml_str("[trackin]\ngate_m = 0.1\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("'trackin'") && msg.contains("line 1"), "{msg}");
    }

    #[test]
    fn wrong_type_and_bad_values_are_errors() {
        let e = Config::from_toml_str("[tracking]\ngate_m = \"wide\"\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("tracking.gate_m") && msg.contains("line 2"),
            "{msg}"
        );
        let e = Config::from_toml_str("[planner]\nrule = \"astar\"\n", None).unwrap_err();
        assert!(format!("{e:#}").contains("astar"), "{e:#}");
        let e = Config::from_toml_str("[robot]\nradius_m = -1.0\n", None).unwrap_err();
        assert!(format!("{e:#}").contains("robot.radius_m"), "{e:#}");
        assert!(Config::from_toml_str("[robot\n", None).is_err());
    }

    #[test]
    fn round_trips_through_toml() {
        for m in [Method::Paper, Method::Goalseek] {
            let c = Config::preset(m);
            let back = Config::from_toml_str(&c.to_toml_string(), None).unwrap();
            assert_eq!(back, c);
        }
    }
}
