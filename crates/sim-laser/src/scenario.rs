//! The paper's scenario and the setup of one simulated run: world, sensor, noise, robot, start.

use std::path::Path;
use std::sync::Arc;

use scan_types::{Pose2, WorldPoint};

use crate::{LaserNoise, MotionNoise, SensorPreset, SimError, Simulation, World, read_description};

/// The paper's start pose: (-3.92, -4.26), heading 45 deg.
pub fn paper_start() -> Pose2 {
    Pose2::new(-3.92, -4.26, 45f64.to_radians())
}

/// The paper's target: (4, 4).
pub fn paper_target() -> WorldPoint {
    WorldPoint::new(4.0, 4.0)
}

/// The start pose and target of a world: those stored in a TOML world, else the paper's.
pub fn file_scenario(path: Option<&Path>) -> Result<(Pose2, WorldPoint), SimError> {
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

/// Every choice that defines a simulation: world, sensor, seed, noise, robot size and start.
#[derive(Debug, Clone)]
pub struct SimSetup {
    /// The world (batches share one).
    pub world: Arc<World>,
    /// A name for the world in reports.
    pub world_name: String,
    /// Laser preset.
    pub sensor: SensorPreset,
    /// Seed of all randomness.
    pub seed: u64,
    /// Noise on: the preset's laser noise and the default actuation noise; off: none.
    pub noise: bool,
    /// Robot radius, metres.
    pub robot_radius_m: f64,
    /// Start pose.
    pub start: Pose2,
}

impl SimSetup {
    /// `world` named `world_name` with the paper's sensor, noise on, a 0.3 m robot at the
    /// paper's start, seed 0.
    pub fn new(world: Arc<World>, world_name: impl Into<String>) -> Self {
        Self {
            world,
            world_name: world_name.into(),
            sensor: SensorPreset::Paper,
            seed: 0,
            noise: true,
            robot_radius_m: 0.3,
            start: paper_start(),
        }
    }

    /// The paper's scenario (its world, sensor and start, noise on) with a seed.
    ///
    /// ```
    /// use scan_types::LaserSource;
    /// let (mut laser, _base, truth) = sim_laser::SimSetup::paper(7).build().unwrap().split();
    /// assert_eq!(laser.next_scan().unwrap().len(), 685);
    /// assert_eq!(truth.pose(), sim_laser::paper_start());
    /// ```
    pub fn paper(seed: u64) -> Self {
        Self {
            seed,
            ..Self::new(Arc::new(World::paper()), "paper")
        }
    }

    /// The world at `path` (by extension: .toml, .yaml, .png) named by its file stem, or the
    /// paper's world if `None`, with the defaults of [`SimSetup::new`].
    pub fn load(path: Option<&Path>) -> Result<Self, SimError> {
        match path {
            None => Ok(Self::new(Arc::new(World::paper()), "paper")),
            Some(p) => {
                let world = World::load(p)?;
                let name = p
                    .file_stem()
                    .map_or_else(|| "world".into(), |s| s.to_string_lossy().into_owned());
                Ok(Self::new(Arc::new(world), name))
            }
        }
    }

    /// The laser noise of the run.
    pub fn laser_noise(&self) -> LaserNoise {
        if self.noise {
            self.sensor.default_noise()
        } else {
            LaserNoise::off()
        }
    }

    /// The actuation noise of the run.
    pub fn motion_noise(&self) -> MotionNoise {
        if self.noise {
            MotionNoise::default()
        } else {
            MotionNoise::off()
        }
    }

    /// Builds the simulation (the world is shared, not copied).
    pub fn build(&self) -> Result<Simulation, SimError> {
        if !(self.robot_radius_m.is_finite() && self.robot_radius_m >= 0.0) {
            return Err(SimError::InvalidConfig {
                field: "robot_radius_m",
                message: format!("{} must be finite and >= 0", self.robot_radius_m),
            });
        }
        let laser_noise = self.laser_noise();
        laser_noise.validate()?;
        Ok(Simulation::new(
            self.world.clone(),
            self.sensor,
            laser_noise,
            self.motion_noise(),
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
    fn noise_off_means_no_dropouts_and_bad_radius_is_refused() {
        let mut s = SimSetup::paper(1);
        s.noise = false;
        let (mut l, _b, _t) = s.build().unwrap().split();
        let scan = l.next_scan().unwrap();
        assert!(
            scan.status
                .iter()
                .all(|st| !matches!(st, RayStatus::Error(_)))
        );
        s.robot_radius_m = f64::NAN;
        assert!(s.build().is_err());
        assert!(SimSetup::load(Some(Path::new("/no/such.toml"))).is_err());
        assert_eq!(SimSetup::load(None).unwrap().world_name, "paper");
    }

    #[test]
    fn scenario_of_a_non_toml_world_is_the_papers() {
        let (s, t) = file_scenario(Some(Path::new("/no/such.png"))).unwrap();
        assert_eq!((s, t), (paper_start(), paper_target()));
        assert!(file_scenario(Some(Path::new("/no/such.toml"))).is_err());
    }
}
