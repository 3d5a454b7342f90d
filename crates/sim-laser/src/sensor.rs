//! Sensor presets, the laser noise model and scan synthesis.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::{SimError, World};

/// Error code of a ray dropped by the dropout model.
pub const DROPOUT_CODE: u16 = 0;
/// Error code of a ray whose target is nearer than the sensor's minimum range.
pub const TOO_NEAR_CODE: u16 = 1;

/// The laser scanners the simulator knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SensorPreset {
    /// The paper's sensor: 685 rays over 240 deg, 0..4.0 m, sigma 0.01 m.
    Paper,
    /// Hokuyo URG-04LX as its PP reports: steps 44..=725 of 1024 around step 384, 0.02..5.6 m.
    Urg04lx,
    /// Hokuyo UTM-30LX: 1081 rays over 270 deg, 0.1..30 m.
    Utm30lx,
    /// Hokuyo UST-10LX: 1081 rays over 270 deg, 0.02..30 m as its PP reports (UST-10LX data
    /// sheet: 0.06 to 10 m guaranteed, 30 m the largest distance reported).
    Ust10lx,
}

impl SensorPreset {
    /// All presets, in their documented order.
    pub const ALL: [SensorPreset; 4] = [Self::Paper, Self::Urg04lx, Self::Utm30lx, Self::Ust10lx];

    /// The preset's scan geometry.
    ///
    /// ```
    /// use sim_laser::SensorPreset;
    /// let g = SensorPreset::Urg04lx.geometry();
    /// assert_eq!(g.ray_count, 682);
    /// assert!(g.bearing_rad(340).abs() < 1e-12);
    /// ```
    pub fn geometry(&self) -> ScanGeometry {
        match self {
            Self::Paper => ScanGeometry::paper(),
            Self::Urg04lx => {
                let inc = 2.0 * PI / 1024.0;
                ScanGeometry::new((44.0 - 384.0) * inc, inc, 725 - 44 + 1, 0.02, 5.6)
                    .expect("constant geometry")
            }
            Self::Utm30lx => {
                let inc = 2.0 * PI / 1440.0;
                ScanGeometry::new((0.0 - 540.0) * inc, inc, 1081, 0.1, 30.0)
                    .expect("constant geometry")
            }
            Self::Ust10lx => {
                let inc = 2.0 * PI / 1440.0;
                ScanGeometry::new((0.0 - 540.0) * inc, inc, 1081, 0.02, 30.0)
                    .expect("constant geometry")
            }
        }
    }

    /// The preset's default noise.
    pub fn default_noise(&self) -> LaserNoise {
        match self {
            Self::Paper => LaserNoise::gaussian(0.01),
            // Measured on the real URG-04LX logs exp1 and exp2 (docs/sim-laser.md): 3 mm, 0.3 %
            // of the range beyond 1 m; the datasheet's +-10 mm / 1 % bounds the accuracy.
            Self::Urg04lx => LaserNoise {
                range_sigma_m: 0.003,
                range_sigma_prop: 0.003,
                combine: SigmaCombine::Max,
                ..LaserNoise::off()
            },
            // Datasheet repeatability: sigma 10 mm below 10 m, 30 mm up to 30 m.
            Self::Utm30lx => LaserNoise {
                range_sigma_m: 0.01,
                range_sigma_prop: 0.001,
                combine: SigmaCombine::Max,
                ..LaserNoise::off()
            },
            // UST-10LX data sheet: accuracy +-40 mm; a constant sigma of 40 mm.
            Self::Ust10lx => LaserNoise::gaussian(0.04),
        }
    }

    /// Time between scans, seconds.
    pub fn scan_period_s(&self) -> f64 {
        match self {
            Self::Paper | Self::Urg04lx => 0.1,
            Self::Utm30lx | Self::Ust10lx => 0.025,
        }
    }

    /// The preset's command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Urg04lx => "urg-04lx",
            Self::Utm30lx => "utm-30lx",
            Self::Ust10lx => "ust-10lx",
        }
    }
}

impl From<SensorPreset> for ScanGeometry {
    fn from(p: SensorPreset) -> ScanGeometry {
        p.geometry()
    }
}

impl fmt::Display for SensorPreset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SensorPreset {
    type Err = SimError;
    fn from_str(s: &str) -> Result<Self, SimError> {
        match s.to_ascii_lowercase().replace('_', "-").as_str() {
            "paper" => Ok(Self::Paper),
            "urg-04lx" | "urg04lx" | "urg" => Ok(Self::Urg04lx),
            "utm-30lx" | "utm30lx" | "utm" => Ok(Self::Utm30lx),
            "ust-10lx" | "ust10lx" | "ust" => Ok(Self::Ust10lx),
            _ => Err(SimError::UnknownPreset(s.to_string())),
        }
    }
}

/// How the constant and proportional range sigmas combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SigmaCombine {
    /// One Gaussian of sigma `max(range_sigma_m, range_sigma_prop * range)` (datasheet style).
    Max,
    /// Two independent Gaussians, sigma `range_sigma_m` and `range_sigma_prop * range` (Stage's
    /// `noise [range_const range_prop angular]`).
    Sum,
}

/// Noise of the simulated laser. Misses are never perturbed: they read exactly the maximum range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserNoise {
    /// Constant range sigma, metres.
    pub range_sigma_m: f64,
    /// Range sigma as a fraction of the true range.
    pub range_sigma_prop: f64,
    /// How the two sigmas combine.
    pub combine: SigmaCombine,
    /// Sigma of the bearing error of each ray, radians (the ray is cast along the perturbed bearing).
    pub angular_sigma_rad: f64,
    /// Probability that a ray reads as invalid (`RayStatus::Error(DROPOUT_CODE)`).
    pub dropout_prob: f64,
}

impl LaserNoise {
    /// No noise at all: ranges are the exact distances.
    pub fn off() -> Self {
        Self {
            range_sigma_m: 0.0,
            range_sigma_prop: 0.0,
            combine: SigmaCombine::Max,
            angular_sigma_rad: 0.0,
            dropout_prob: 0.0,
        }
    }

    /// A constant Gaussian range error of `sigma_m` on hits.
    pub fn gaussian(sigma_m: f64) -> Self {
        Self {
            range_sigma_m: sigma_m,
            ..Self::off()
        }
    }

    /// Stage's `noise [range_const range_prop angular]` (the angle in degrees, as Stage writes it).
    pub fn stage(range_const_m: f64, range_prop: f64, angular_deg: f64) -> Self {
        Self {
            range_sigma_m: range_const_m,
            range_sigma_prop: range_prop,
            combine: SigmaCombine::Sum,
            angular_sigma_rad: angular_deg.to_radians(),
            dropout_prob: 0.0,
        }
    }

    /// The same noise with a dropout probability.
    pub fn with_dropout(self, dropout_prob: f64) -> Self {
        Self {
            dropout_prob,
            ..self
        }
    }

    /// True when the model adds nothing.
    pub fn is_off(&self) -> bool {
        self.range_sigma_m == 0.0
            && self.range_sigma_prop == 0.0
            && self.angular_sigma_rad == 0.0
            && self.dropout_prob == 0.0
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), SimError> {
        let check = |field: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(SimError::InvalidConfig {
                    field,
                    message: format!("{v} must be finite and >= 0"),
                })
            }
        };
        check("range_sigma_m", self.range_sigma_m)?;
        check("range_sigma_prop", self.range_sigma_prop)?;
        check("angular_sigma_rad", self.angular_sigma_rad)?;
        check("dropout_prob", self.dropout_prob)?;
        if self.dropout_prob > 1.0 {
            return Err(SimError::InvalidConfig {
                field: "dropout_prob",
                message: format!("{} must be <= 1", self.dropout_prob),
            });
        }
        Ok(())
    }
}

fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// Casts one scan from `pose` into `world`, applying `noise` with `rng`.
///
/// A ray that hits nothing within `max_range_m` reads exactly `max_range_m` (`MaxRange`); a hit
/// nearer than `min_range_m` reads as `Error(TOO_NEAR_CODE)`; a noisy hit that lands at or beyond
/// the maximum range reads as `MaxRange`; a noisy range below the minimum is clamped to it.
pub fn cast_scan<R: Rng + ?Sized>(
    world: &World,
    pose: &Pose2,
    geometry: &ScanGeometry,
    noise: &LaserNoise,
    rng: &mut R,
    host_time_s: f64,
) -> Scan {
    let n = geometry.ray_count;
    let o = [pose.x_m, pose.y_m];
    let max = geometry.max_range_m;
    let angular = noise.angular_sigma_rad > 0.0;
    // Without angular noise the directions need no random draws, so every ray is cast first
    // (several at once); with it, each ray's draws come in ray order as before.
    let mut ranges_m = vec![f64::INFINITY; n];
    if !angular {
        cast_every_ray(world, pose, geometry, &mut ranges_m);
    }
    let status = if noise.is_off() {
        classify_noiseless(geometry, &mut ranges_m)
    } else {
        let mut status = Vec::with_capacity(n);
        for (i, range) in ranges_m.iter_mut().enumerate() {
            let hit = if angular {
                let a = pose.theta_rad
                    + geometry.bearing_rad(i)
                    + noise.angular_sigma_rad * normal(rng);
                let (s, c) = a.sin_cos();
                world.raycast_dir(o, [c, s], max).unwrap_or(f64::INFINITY)
            } else {
                *range
            };
            let (r, st) = noisy_reading(hit, geometry, noise, rng);
            *range = r;
            status.push(st);
        }
        status
    };
    Scan {
        ranges_m,
        status,
        intensities: None,
        sensor_time_ms: Some((host_time_s * 1000.0).round().max(0.0) as u64),
        host_time_s,
    }
}

/// Casts every ray of `geometry` from `pose` without noise into `ranges_m` (infinite where
/// nothing is hit within the maximum range).
fn cast_every_ray(world: &World, pose: &Pose2, geometry: &ScanGeometry, ranges_m: &mut [f64]) {
    let (inc_s, inc_c) = geometry.increment_rad.sin_cos();
    let mut step_dir = [1.0, 0.0];
    let dir = |i: usize| {
        // Exact every 32 rays, rotated by the increment in between (error below 1e-14).
        step_dir = if i.is_multiple_of(32) {
            let (s, c) = (pose.theta_rad + geometry.bearing_rad(i)).sin_cos();
            [c, s]
        } else {
            [
                step_dir[0] * inc_c - step_dir[1] * inc_s,
                step_dir[0] * inc_s + step_dir[1] * inc_c,
            ]
        };
        step_dir
    };
    world.raycast_many([pose.x_m, pose.y_m], dir, geometry.max_range_m, ranges_m);
}

/// The readings of noise-free hits: what [`noisy_reading`] gives without noise, minus its
/// branches; `ranges_m` become the ranges read.
fn classify_noiseless(geometry: &ScanGeometry, ranges_m: &mut [f64]) -> Vec<RayStatus> {
    let (min, max) = (geometry.min_range_m, geometry.max_range_m);
    ranges_m
        .iter_mut()
        .map(|range| {
            let (r, st) = if *range >= max {
                (max, RayStatus::MaxRange)
            } else if *range < min {
                (f64::NAN, RayStatus::Error(TOO_NEAR_CODE))
            } else {
                (*range, RayStatus::Hit)
            };
            *range = r;
            st
        })
        .collect()
}

/// The reading of a ray whose true hit is at `hit` (infinite: none), with range noise and
/// dropouts drawn from `rng` in that order.
fn noisy_reading<R: Rng + ?Sized>(
    hit: f64,
    geometry: &ScanGeometry,
    noise: &LaserNoise,
    rng: &mut R,
) -> (f64, RayStatus) {
    let max = geometry.max_range_m;
    let (mut r, mut st) = if hit < max {
        (hit, RayStatus::Hit)
    } else {
        (max, RayStatus::MaxRange)
    };
    if st == RayStatus::Hit {
        if r < geometry.min_range_m {
            st = RayStatus::Error(TOO_NEAR_CODE);
            r = f64::NAN;
        } else {
            r = (r + range_error(noise, r, rng)).max(geometry.min_range_m);
            if r >= max {
                r = max;
                st = RayStatus::MaxRange;
            }
        }
    }
    if noise.dropout_prob > 0.0 && rng.random::<f64>() < noise.dropout_prob {
        st = RayStatus::Error(DROPOUT_CODE);
        r = f64::NAN;
    }
    (r, st)
}

/// The range error of a hit at `r`, drawn from `rng` as `noise` combines its sigmas.
fn range_error<R: Rng + ?Sized>(noise: &LaserNoise, r: f64, rng: &mut R) -> f64 {
    match noise.combine {
        SigmaCombine::Max => {
            let sigma = noise.range_sigma_m.max(noise.range_sigma_prop * r);
            if sigma > 0.0 {
                sigma * normal(rng)
            } else {
                0.0
            }
        }
        SigmaCombine::Sum => {
            let mut e = 0.0;
            if noise.range_sigma_m > 0.0 {
                e += noise.range_sigma_m * normal(rng);
            }
            if noise.range_sigma_prop > 0.0 {
                e += noise.range_sigma_prop * r * normal(rng);
            }
            e
        }
    }
}

/// The noise-free scan of `geometry` from `pose`.
pub fn true_scan(world: &World, pose: &Pose2, geometry: &ScanGeometry) -> Scan {
    // No noise draws are made, so any generator will do.
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0);
    cast_scan(world, pose, geometry, &LaserNoise::off(), &mut rng, 0.0)
}
