//! The navigator driven through its step API in the simulator: the paper's scenario.
//!
//! Run: `cargo run --release --example navigate_sim`
#![allow(clippy::print_stdout)] // an example program prints its result

use std::sync::Arc;

use navigator::{Action, Navigator, Params};
use scan_types::{LaserSource, MotionBase};
use sim_laser::{SensorPreset, Simulation, World, paper_start, paper_target};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sim = Simulation::with_preset(
        Arc::new(World::paper()),
        SensorPreset::Paper,
        paper_start(),
        0,
    );
    let (mut laser, mut base, truth) = sim.split();
    let mut nav = Navigator::new(
        Params::goalseek(),
        *laser.geometry(),
        paper_start(),
        paper_target(),
    )?;
    // Answer each action until the navigator finishes.
    let mut action = nav.pending();
    while !matches!(action, Action::Finish(_)) {
        action = match action {
            Action::Scan => nav.on_scan(&laser.next_scan()?),
            Action::Rotate { angle_rad } => {
                base.rotate(angle_rad)?;
                nav.on_motion_done()
            }
            Action::Forward { distance_m } => {
                base.forward(distance_m)?;
                nav.on_motion_done()
            }
            Action::Finish(_) => break,
        };
    }
    base.stop()?;
    let outcome = nav.into_outcome();
    let truth_to_goal = truth.pose().position().distance_m(&paper_target());
    println!(
        "{} after {} legs and {} scans; the robot is truly {truth_to_goal:.3} m from the target",
        outcome.reason, outcome.legs_driven, outcome.scans
    );
    Ok(())
}
