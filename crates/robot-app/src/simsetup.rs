//! The simulated laser behind `robot-app scan --sim` and `robot-app emulate --sim`: a robot
//! that never moves, taking every scan at one pose. Runs that move use
//! [`sim_laser::SimSetup`] through [`crate::cmd::sim::SimSpec`].

use std::path::Path;

use anyhow::Context;
use scan_types::Pose2;
use sim_laser::{SensorPreset, SimLaser, SimSetup};

pub use sim_laser::{paper_start, paper_target};

/// Parses the `--pose` option, written `X,Y,THETA_DEG` (metres, metres, degrees).
///
/// ```
/// let p = robot_app::simsetup::parse_pose("-3.92,-4.26,45").unwrap();
/// assert_eq!(p, robot_app::simsetup::paper_start());
/// assert!(robot_app::simsetup::parse_pose("1,2").is_err());
/// ```
pub fn parse_pose(s: &str) -> anyhow::Result<Pose2> {
    scan_types::parse_pose_deg(s).context("--pose")
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
    let sensor = sensor.parse::<SensorPreset>()?;
    let mut setup = match world {
        None => SimSetup::load(None)?,
        Some(p) => {
            SimSetup::load(Some(p)).with_context(|| format!("loading world {}", p.display()))?
        }
    };
    setup.sensor = sensor;
    setup.start = pose;
    setup.seed = seed;
    // Noise on also turns actuation noise on, which a robot that never moves never draws.
    setup.noise = noise;
    let (laser, _base, _truth) = setup.build()?.split();
    Ok(laser)
}
