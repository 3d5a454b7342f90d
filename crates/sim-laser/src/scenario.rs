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
    let (start, target) = stored_scenario(path)?;
    Ok((
        start.unwrap_or_else(paper_start),
        target.unwrap_or_else(paper_target),
    ))
}

/// The start pose and target a world file stores (only a TOML world can); none for no file.
pub fn stored_scenario(
    path: Option<&Path>,
) -> Result<(Option<Pose2>, Option<WorldPoint>), SimError> {
    let Some(p) = path.filter(|p| p.extension().is_some_and(|e| e == "toml")) else {
        return Ok((None, None));
    };
    let d = read_description(p)?;
    Ok((
        d.start.map(|[x, y, t]| Pose2::new(x, y, t)),
        d.target.map(|[x, y]| WorldPoint::new(x, y)),
    ))
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

    /// Checks that the robot can start at `start` and that `target` lies in the world's free
    /// space, before the robot moves.
    pub fn check_scenario(&self, target: WorldPoint) -> Result<(), SimError> {
        let s = self.start;
        if !s.theta_rad.is_finite() {
            return Err(
                self.scenario_error("start", format!("heading {} is not finite", s.theta_rad))
            );
        }
        self.check_point("start", s.position(), Some(self.robot_radius_m))?;
        self.check_point("target", target, None)
    }

    /// `p` is finite, inside the world's bounds and clear of obstacles (a disc of `radius`
    /// around it, or the point itself).
    fn check_point(
        &self,
        what: &'static str,
        p: WorldPoint,
        radius: Option<f64>,
    ) -> Result<(), SimError> {
        // Far coordinates in exponent form, so that a typo stays readable.
        let m = |v: f64| {
            if v.abs() < 1e6 {
                format!("{v:.2}")
            } else {
                format!("{v:.3e}")
            }
        };
        let (x, y) = (p.x_m(), p.y_m());
        if !(x.is_finite() && y.is_finite()) {
            return Err(self.scenario_error(what, format!("({x}, {y}) is not finite")));
        }
        let (lo, hi) = self.world.bounds();
        if !(x >= lo.x_m() && x <= hi.x_m() && y >= lo.y_m() && y <= hi.y_m()) {
            let message = format!(
                "({}, {}) lies outside the world (x {:.2}..{:.2} m, y {:.2}..{:.2} m)",
                m(x),
                m(y),
                lo.x_m(),
                hi.x_m(),
                lo.y_m(),
                hi.y_m()
            );
            return Err(self.scenario_error(what, message));
        }
        let blocked = match radius {
            Some(r) => self.world.disc_collides(p, r),
            None => self.world.is_occupied(p),
        };
        if blocked {
            let message = match radius {
                Some(r) => format!(
                    "({}, {}) puts the robot (radius {r} m) into an obstacle",
                    m(x),
                    m(y)
                ),
                None => format!("({}, {}) lies inside an obstacle", m(x), m(y)),
            };
            return Err(self.scenario_error(what, message));
        }
        Ok(())
    }

    fn scenario_error(&self, what: &'static str, message: String) -> SimError {
        SimError::Scenario {
            world: self.world_name.clone(),
            what,
            message,
        }
    }

    /// Builds the simulation (the world is shared, not copied).
    pub fn build(&self) -> Result<Simulation, SimError> {
        if !(self.robot_radius_m.is_finite()
            && self.robot_radius_m >= 0.0
            && self.robot_radius_m <= 5.0)
        {
            return Err(SimError::InvalidConfig {
                field: "robot_radius_m",
                message: format!(
                    "{} must be finite, at least 0 and at most 5",
                    self.robot_radius_m
                ),
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

    #[test]
    fn impossible_scenarios_are_refused_before_the_robot_moves() {
        let s = SimSetup::paper(0);
        s.check_scenario(paper_target()).unwrap();
        let e = s
            .check_scenario(WorldPoint::new(1000.0, 1000.0))
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("target (1000.00, 1000.00) lies outside"),
            "{e}"
        );
        let e = s
            .check_scenario(WorldPoint::new(f64::NAN, 0.0))
            .unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        // The first wall due east of the start: a robot centred on it overlaps it.
        let start = paper_start();
        let d = s.world.raycast(start.position(), 0.0, 20.0).unwrap();
        let mut on_wall = SimSetup::paper(0);
        on_wall.start = Pose2::new(start.x_m + d, start.y_m, 0.0);
        let e = on_wall.check_scenario(paper_target()).unwrap_err();
        assert!(e.to_string().contains("into an obstacle"), "{e}");
        let mut outside = SimSetup::paper(0);
        outside.start = Pose2::new(-500.0, 0.0, 0.0);
        assert!(outside.check_scenario(paper_target()).is_err());
    }
}
