//! Casts one noise-free scan of the paper's world from the paper's start and prints it as
//! `bearing_deg,range_m` (every 20th ray).
//!
//! Run: `cargo run --example paper_scan`
#![allow(clippy::print_stdout)] // an example program prints its result

use rand::SeedableRng;
use sim_laser::{LaserNoise, SensorPreset, World, cast_scan, paper_start};

fn main() {
    let world = World::paper();
    let geometry = SensorPreset::Paper.geometry();
    // Noise off: the generator is never drawn from, but the caster takes one.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let scan = cast_scan(
        &world,
        &paper_start(),
        &geometry,
        &LaserNoise::off(),
        &mut rng,
        0.0,
    );
    println!("bearing_deg,range_m");
    for i in (0..scan.len()).step_by(20) {
        println!(
            "{:.2},{:.3}",
            geometry.bearing_rad(i).to_degrees(),
            scan.ranges_m[i]
        );
    }
    let hits = (0..scan.len()).filter(|&i| scan.is_hit(i)).count();
    println!(
        "# {} rays, {hits} hits, the rest at the 4 m maximum range",
        scan.len()
    );
}
