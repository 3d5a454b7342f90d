//! Simulator setup shared by the commands: pose and point parsing, loading a world (or the
//! paper's), and building simulated lasers and simulations from command-line choices.
//!
//! `robot-app scan --sim` calls [`sim_scan_source`]; `robot-app emulate --sim` can serve the same
//! source; `robot-app sim` / `batch` use [`SimOptions::build`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use scan_types::{Pose2, WorldPoint};
use sim_laser::{
    LaserNoise, MotionNoise, SensorPreset, SimLaser, Simulation, World, read_description,
};

/// The paper's start pose: (-3.92, -4.26), heading 45 deg.
pub fn paper_start() -> Pose2 {
    Pose2::new(-3.92, -4.26, 45f64.to_radians())
}

/// The paper's target: (4, 4).
pub fn paper_target() -> WorldPoint {
    WorldPoint::new(4.0, 4.0)
}

fn parse_numbers(s: &str, n: usize, what: &str) -> anyhow::Result<Vec<f64>> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .with_context(|| format!("{what} {s:?}: {:?} is not a finite number", t.trim()))
        })
        .collect::<anyhow::Result<_>>()?;
    if v.len() != n {
        bail!(
            "{what} {s:?}: expected {n} comma-separated numbers, found {}",
            v.len()
        );
    }
    Ok(v)
}

/// Parses a pose written `X,Y,THETA_DEG` (metres, metres, degrees).
///
/// ```
/// let p = robot_app::simsetup::parse_pose("-3.92,-4.26,45").unwrap();
/// assert!((p.theta_rad - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
/// assert!(robot_app::simsetup::parse_pose("1,2").is_err());
/// ```
pub fn parse_pose(s: &str) -> anyhow::Result<Pose2> {
    let v = parse_numbers(s, 3, "pose")?;
    Ok(Pose2::new(v[0], v[1], v[2].to_radians()))
}

/// Parses a point written `X,Y` (metres).
pub fn parse_point(s: &str) -> anyhow::Result<WorldPoint> {
    let v = parse_numbers(s, 2, "point")?;
    Ok(WorldPoint::new(v[0], v[1]))
}

/// Parses a size written `W,H` (metres, both > 0).
pub fn parse_size(s: &str) -> anyhow::Result<(f64, f64)> {
    let v = parse_numbers(s, 2, "size")?;
    if v[0] <= 0.0 || v[1] <= 0.0 {
        bail!("size {s:?}: both must be > 0");
    }
    Ok((v[0], v[1]))
}

/// Parses a sensor preset name (`paper`, `urg-04lx`, `utm-30lx`).
pub fn parse_sensor(s: &str) -> anyhow::Result<SensorPreset> {
    Ok(s.parse::<SensorPreset>()?)
}

/// Loads the world at `path` (by extension: .toml, .yaml, .png), or the paper's world if `None`.
pub fn load_world(path: Option<&Path>) -> anyhow::Result<Arc<World>> {
    match path {
        None => Ok(Arc::new(World::paper())),
        Some(p) => {
            Ok(Arc::new(World::load(p).with_context(|| {
                format!("loading world {}", p.display())
            })?))
        }
    }
}

/// Loads a Stage bitmap scaled to `size` (metres), or any world by extension when `size` is `None`.
pub fn load_world_sized(
    path: Option<&Path>,
    size: Option<(f64, f64)>,
    boundary: bool,
) -> anyhow::Result<Arc<World>> {
    match (path, size) {
        (Some(p), Some((w, h))) => Ok(Arc::new(
            World::load_stage_bitmap(p, w, h, boundary)
                .with_context(|| format!("loading Stage bitmap {}", p.display()))?,
        )),
        _ => load_world(path),
    }
}

/// The start pose and target of a world: those stored in a TOML world, else the paper's.
pub fn scenario(path: Option<&Path>) -> anyhow::Result<(Pose2, WorldPoint)> {
    let (mut start, mut target) = (paper_start(), paper_target());
    if let Some(p) = path.filter(|p| p.extension().is_some_and(|e| e == "toml")) {
        let d = read_description(p)?;
        if let Some([x, y, t]) = d.start {
            start = Pose2::new(x, y, t);
        }
        if let Some([x, y]) = d.target {
            target = WorldPoint::new(x, y);
        }
    }
    Ok((start, target))
}

/// The laser noise of a preset, or none.
pub fn laser_noise(sensor: SensorPreset, noise: bool) -> LaserNoise {
    if noise {
        sensor.default_noise()
    } else {
        LaserNoise::off()
    }
}

/// A simulated laser at a fixed pose: the source behind `robot-app scan --sim`.
///
/// `world`: a world file or `None` for the paper's world; `sensor`: a preset name;
/// `noise`: the preset's default laser noise on or off. The robot never moves, so every scan is
/// taken at `pose` (noise differs from scan to scan, deterministically for a seed).
pub fn sim_scan_source(
    world: Option<&Path>,
    pose: Pose2,
    sensor: &str,
    seed: u64,
    noise: bool,
) -> anyhow::Result<SimLaser> {
    let preset = parse_sensor(sensor)?;
    let world = load_world(world)?;
    let (laser, _base, _truth) = Simulation::new(
        world,
        preset,
        laser_noise(preset, noise),
        MotionNoise::off(),
        0.3,
        pose,
        seed,
    )
    .split();
    Ok(laser)
}

/// Every choice that defines a simulation run.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// World file, or `None` for the paper's world.
    pub world: Option<PathBuf>,
    /// Laser preset.
    pub sensor: SensorPreset,
    /// Seed of all randomness.
    pub seed: u64,
    /// Laser noise (`None`: off).
    pub laser_noise: Option<LaserNoise>,
    /// Actuation noise.
    pub motion_noise: MotionNoise,
    /// Robot radius, metres.
    pub robot_radius_m: f64,
    /// Start pose.
    pub start: Pose2,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            world: None,
            sensor: SensorPreset::Paper,
            seed: 0,
            laser_noise: Some(SensorPreset::Paper.default_noise()),
            motion_noise: MotionNoise::default(),
            robot_radius_m: 0.3,
            start: paper_start(),
        }
    }
}

impl SimOptions {
    /// Loads the world and builds the simulation.
    pub fn build(&self) -> anyhow::Result<Simulation> {
        let world = load_world(self.world.as_deref())?;
        self.build_in(world)
    }

    /// Builds the simulation in an already loaded world (batches share one `Arc<World>`).
    pub fn build_in(&self, world: Arc<World>) -> anyhow::Result<Simulation> {
        if !(self.robot_radius_m.is_finite() && self.robot_radius_m >= 0.0) {
            bail!(
                "robot radius {} must be finite and >= 0",
                self.robot_radius_m
            );
        }
        let noise = self.laser_noise.unwrap_or_else(LaserNoise::off);
        noise.validate()?;
        Ok(Simulation::new(
            world,
            self.sensor,
            noise,
            self.motion_noise,
            self.robot_radius_m,
            self.start,
            self.seed,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan_types::{LaserSource, RayStatus};

    #[test]
    fn poses_points_and_sizes() {
        let p = parse_pose(" 1.5, -2 ,90").unwrap();
        assert_eq!((p.x_m, p.y_m), (1.5, -2.0));
        assert!((p.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(
            parse_pose("1,2,x")
                .unwrap_err()
                .to_string()
                .contains("\"x\"")
        );
        assert!(parse_pose("1,2,3,4").is_err());
        assert!(parse_pose("1,nan,3").is_err());
        assert_eq!(parse_point("4,4").unwrap(), WorldPoint::new(4.0, 4.0));
        assert!(parse_size("10,-1").is_err());
        assert!(parse_sensor("urg-04lx").is_ok());
        assert!(
            parse_sensor("lms200")
                .unwrap_err()
                .to_string()
                .contains("lms200")
        );
    }

    #[test]
    fn scan_source_in_the_paper_world() {
        let mut l = sim_scan_source(None, paper_start(), "paper", 1, false).unwrap();
        let s = l.next_scan().unwrap();
        assert_eq!(s.len(), 685);
        // Noise off: no dropouts, so no ray is an error.
        assert!(s.status.iter().all(|st| !matches!(st, RayStatus::Error(_))));
        assert!(
            sim_scan_source(
                Some(Path::new("/no/such.toml")),
                paper_start(),
                "paper",
                1,
                true
            )
            .is_err()
        );
    }
}
