//! The simulated robot: a disc with a laser, split into the laser, the base and the truth handle.

use std::convert::Infallible;
use std::sync::{Arc, Mutex, MutexGuard};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use scan_types::{LaserSource, MotionBase, Pose2, Scan, ScanGeometry, WorldPoint};

use crate::{LaserNoise, SimError, World, cast_scan};

/// Actuation noise of the simulated base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionNoise {
    /// Sigma of the error added to each commanded rotation, radians (default 1 deg).
    pub rotation_sigma_rad: f64,
    /// Sigma of the scale factor (mean 1) applied to each drive (default 0.02). A drive is a run
    /// of consecutive `forward` calls with no `rotate` in between: they share one factor.
    pub drive_scale_sigma: f64,
}

impl Default for MotionNoise {
    fn default() -> Self {
        Self {
            rotation_sigma_rad: 1f64.to_radians(),
            drive_scale_sigma: 0.02,
        }
    }
}

impl MotionNoise {
    /// Perfect actuation.
    pub fn off() -> Self {
        Self {
            rotation_sigma_rad: 0.0,
            drive_scale_sigma: 0.0,
        }
    }
}

/// Systematic actuation faults of the simulated base: the share of each command it carries out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseGains {
    /// Share of each commanded drive driven (1: as commanded; 0: a stalled base; 0.5: 50 %
    /// wheel slip).
    pub drive: f64,
    /// Share of each commanded rotation turned (0.8: turns 20 % short).
    pub turn: f64,
}

impl Default for BaseGains {
    fn default() -> Self {
        Self {
            drive: 1.0,
            turn: 1.0,
        }
    }
}

/// One contact of the robot's disc with the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// True pose where the robot stopped.
    pub pose: Pose2,
    /// Distance the base was asked to drive in the command that collided, metres (after noise).
    pub commanded_m: f64,
    /// Distance it drove before stopping, metres.
    pub achieved_m: f64,
    /// Simulated time of the contact, seconds.
    pub time_s: f64,
}

/// Speeds used to advance the simulated clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimSpeeds {
    /// Driving speed, m/s.
    pub linear_m_s: f64,
    /// Turning speed, rad/s.
    pub angular_rad_s: f64,
    /// Time between scans, seconds.
    pub scan_period_s: f64,
}

impl Default for SimSpeeds {
    fn default() -> Self {
        Self {
            linear_m_s: 0.3,
            angular_rad_s: 45f64.to_radians(),
            scan_period_s: 0.1,
        }
    }
}

#[derive(Debug)]
struct State {
    world: Arc<World>,
    geometry: ScanGeometry,
    laser_noise: LaserNoise,
    motion_noise: MotionNoise,
    gains: BaseGains,
    radius_m: f64,
    speeds: SimSpeeds,
    pose: Pose2,
    laser_rng: ChaCha8Rng,
    motion_rng: ChaCha8Rng,
    drive_factor: Option<f64>,
    collisions: Vec<Collision>,
    scans_taken: u64,
    clock_s: f64,
    last_scan_s: Option<f64>,
    travelled_m: f64,
    rotations: u64,
}

/// A simulation before it is split into its three handles.
///
/// ```
/// use std::sync::Arc;
/// use sim_laser::{LaserNoise, MotionNoise, SensorPreset, Simulation, World};
/// use scan_types::{LaserSource, MotionBase, Pose2};
/// let sim = Simulation::new(Arc::new(World::paper()), SensorPreset::Paper, LaserNoise::off(),
///     MotionNoise::off(), 0.3, Pose2::new(-3.92, -4.26, 45f64.to_radians()), 7);
/// let (mut laser, mut base, truth) = sim.split();
/// let scan = laser.next_scan().unwrap();
/// assert_eq!(scan.len(), 685);
/// base.forward(0.5).unwrap();
/// assert!((truth.pose().x_m - (-3.92 + 0.5 * 45f64.to_radians().cos())).abs() < 1e-9);
/// ```
#[derive(Debug)]
pub struct Simulation {
    state: State,
}

impl Simulation {
    /// A simulation of `world` with a laser of `geometry` (or a [`crate::SensorPreset`]), the given
    /// noises, a disc robot of `robot_radius_m` at `start`, and all randomness drawn from `seed`.
    pub fn new(
        world: Arc<World>,
        geometry: impl Into<ScanGeometry>,
        laser_noise: LaserNoise,
        motion_noise: MotionNoise,
        robot_radius_m: f64,
        start: Pose2,
        seed: u64,
    ) -> Simulation {
        let mut laser_rng = ChaCha8Rng::seed_from_u64(seed);
        laser_rng.set_stream(1);
        let mut motion_rng = ChaCha8Rng::seed_from_u64(seed);
        motion_rng.set_stream(2);
        Simulation {
            state: State {
                world,
                geometry: geometry.into(),
                laser_noise,
                motion_noise,
                gains: BaseGains::default(),
                radius_m: robot_radius_m.max(0.0),
                speeds: SimSpeeds::default(),
                pose: start,
                laser_rng,
                motion_rng,
                drive_factor: None,
                collisions: Vec::new(),
                scans_taken: 0,
                clock_s: 0.0,
                last_scan_s: None,
                travelled_m: 0.0,
                rotations: 0,
            },
        }
    }

    /// The preset's geometry and default noises, radius 0.3 m.
    pub fn with_preset(
        world: Arc<World>,
        preset: crate::SensorPreset,
        start: Pose2,
        seed: u64,
    ) -> Simulation {
        let mut s = Self::new(
            world,
            preset,
            preset.default_noise(),
            MotionNoise::default(),
            0.3,
            start,
            seed,
        );
        s.state.speeds.scan_period_s = preset.scan_period_s();
        s
    }

    /// Makes the base carry out only a share of each command (a stall, slip, short turns).
    pub fn with_base_gains(mut self, gains: BaseGains) -> Simulation {
        self.state.gains = gains;
        self
    }

    /// Replaces the clock speeds.
    pub fn with_speeds(mut self, speeds: SimSpeeds) -> Simulation {
        self.state.speeds = speeds;
        self
    }

    /// Splits into the laser and the base (for the algorithm) and the truth handle (for evaluation).
    pub fn split(self) -> (SimLaser, SimBase, TruthHandle) {
        let geometry = self.state.geometry;
        let shared = Arc::new(Mutex::new(self.state));
        (
            SimLaser {
                shared: shared.clone(),
                geometry,
            },
            SimBase {
                shared: shared.clone(),
            },
            TruthHandle { shared },
        )
    }
}

fn lock(m: &Mutex<State>) -> MutexGuard<'_, State> {
    // A panic while holding the lock cannot leave the state half-updated in a harmful way.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The simulated laser: scans at the robot's current true pose.
#[derive(Debug, Clone)]
pub struct SimLaser {
    shared: Arc<Mutex<State>>,
    geometry: ScanGeometry,
}

impl LaserSource for SimLaser {
    type Error = Infallible;
    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }
    fn next_scan(&mut self) -> Result<Scan, Infallible> {
        let mut guard = lock(&self.shared);
        let st = &mut *guard;
        let t = match st.last_scan_s {
            Some(last) => st.clock_s.max(last + st.speeds.scan_period_s),
            None => st.clock_s,
        };
        st.clock_s = t;
        st.last_scan_s = Some(t);
        st.scans_taken += 1;
        Ok(cast_scan(
            &st.world,
            &st.pose,
            &st.geometry,
            &st.laser_noise,
            &mut st.laser_rng,
            t,
        ))
    }
}

/// The simulated base: rotate in place and drive straight, with actuation noise and collisions.
#[derive(Debug, Clone)]
pub struct SimBase {
    shared: Arc<Mutex<State>>,
}

/// Largest internal step of a drive, metres.
const DRIVE_STEP_M: f64 = 0.01;

impl MotionBase for SimBase {
    type Error = SimError;

    fn rotate(&mut self, angle_rad: f64) -> Result<(), SimError> {
        if !angle_rad.is_finite() {
            return Err(SimError::InvalidMotion {
                what: "rotate angle_rad",
                value: angle_rad,
            });
        }
        let mut guard = lock(&self.shared);
        let st = &mut *guard;
        st.drive_factor = None;
        if angle_rad == 0.0 {
            return Ok(());
        }
        let sigma = st.motion_noise.rotation_sigma_rad;
        let err = if sigma > 0.0 {
            sigma * gauss(&mut st.motion_rng)
        } else {
            0.0
        };
        let actual = angle_rad * st.gains.turn + err;
        st.pose = st.pose.rotated(actual);
        st.rotations += 1;
        if st.speeds.angular_rad_s > 0.0 {
            st.clock_s += actual.abs() / st.speeds.angular_rad_s;
        }
        Ok(())
    }

    fn forward(&mut self, distance_m: f64) -> Result<(), SimError> {
        if !distance_m.is_finite() {
            return Err(SimError::InvalidMotion {
                what: "forward distance_m",
                value: distance_m,
            });
        }
        let mut guard = lock(&self.shared);
        let st = &mut *guard;
        let sigma = st.motion_noise.drive_scale_sigma;
        let factor = match st.drive_factor {
            Some(f) => f,
            None => {
                let f = if sigma > 0.0 {
                    1.0 + sigma * gauss(&mut st.motion_rng)
                } else {
                    1.0
                };
                st.drive_factor = Some(f);
                f
            }
        };
        let target = distance_m * factor * st.gains.drive;
        let achieved = drive(&st.world, st.pose, st.radius_m, target);
        st.pose = st.pose.advanced(achieved);
        st.travelled_m += achieved.abs();
        if st.speeds.linear_m_s > 0.0 {
            st.clock_s += achieved.abs() / st.speeds.linear_m_s;
        }
        if achieved.abs() < target.abs() {
            let c = Collision {
                pose: st.pose,
                commanded_m: target,
                achieved_m: achieved,
                time_s: st.clock_s,
            };
            tracing::debug!(?c, "simulated robot collided");
            st.collisions.push(c);
        }
        Ok(())
    }

    fn stop(&mut self) -> Result<(), SimError> {
        Ok(())
    }
}

/// Drives from `pose` up to `target_m` along the heading and returns the distance achieved:
/// the robot stops (within 0.1 mm) where its disc first touches the world. A robot that starts
/// overlapping an obstacle may move only where its clearance does not shrink.
fn drive(world: &World, pose: Pose2, radius_m: f64, target_m: f64) -> f64 {
    if target_m == 0.0 {
        return 0.0;
    }
    let dir = target_m.signum();
    let total = target_m.abs();
    let search = radius_m + DRIVE_STEP_M + 1e-3;
    let clear_at = |s: f64| world.clearance(pose.advanced(dir * s).position(), search);
    let blocked = |prev_clear: f64, s: f64| {
        let c = clear_at(s);
        (c < radius_m && c < prev_clear, c)
    };
    let mut s = 0.0;
    let mut clear = clear_at(0.0);
    while s < total {
        let next = (s + DRIVE_STEP_M).min(total);
        let (hit, c) = blocked(clear, next);
        if !hit {
            s = next;
            clear = c;
            continue;
        }
        // Bisect between s (free) and next (blocked).
        let (mut lo, mut hi) = (s, next);
        while hi - lo > 1e-4 {
            let mid = 0.5 * (lo + hi);
            if blocked(clear, mid).0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        return dir * lo;
    }
    dir * total
}

/// Evaluation-only view of the simulation's truth: the algorithm never receives it.
#[derive(Debug, Clone)]
pub struct TruthHandle {
    shared: Arc<Mutex<State>>,
}

impl TruthHandle {
    /// The robot's true pose.
    pub fn pose(&self) -> Pose2 {
        lock(&self.shared).pose
    }
    /// Number of collisions so far.
    pub fn collisions(&self) -> usize {
        lock(&self.shared).collisions.len()
    }
    /// Every collision so far.
    pub fn collision_log(&self) -> Vec<Collision> {
        lock(&self.shared).collisions.clone()
    }
    /// Number of scans the laser has produced.
    pub fn scans_taken(&self) -> u64 {
        lock(&self.shared).scans_taken
    }
    /// Number of rotations performed (zero-angle commands excluded).
    pub fn rotations(&self) -> u64 {
        lock(&self.shared).rotations
    }
    /// Total distance driven, metres.
    pub fn travelled_m(&self) -> f64 {
        lock(&self.shared).travelled_m
    }
    /// Simulated time, seconds.
    pub fn clock_s(&self) -> f64 {
        lock(&self.shared).clock_s
    }
    /// The robot's radius, metres.
    pub fn robot_radius_m(&self) -> f64 {
        lock(&self.shared).radius_m
    }
    /// The world.
    pub fn world(&self) -> Arc<World> {
        lock(&self.shared).world.clone()
    }
    /// True when the robot's disc currently overlaps the world.
    pub fn in_collision(&self) -> bool {
        let st = lock(&self.shared);
        st.world.disc_collides(st.pose.position(), st.radius_m)
    }
    /// Distance from the robot's centre to `p`, metres.
    pub fn distance_to(&self, p: WorldPoint) -> f64 {
        self.pose().position().distance_m(&p)
    }
    /// Moves the robot (tests and scenario setup only).
    pub fn teleport(&self, pose: Pose2) {
        let mut st = lock(&self.shared);
        st.pose = pose;
        st.drive_factor = None;
    }
}

impl scan_types::GroundTruth for TruthHandle {
    fn true_pose(&self) -> Pose2 {
        self.pose()
    }
    fn collisions(&self) -> usize {
        TruthHandle::collisions(self)
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let v: f64 = StandardNormal.sample(rng);
    v
}
