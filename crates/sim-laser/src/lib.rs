//! The simulator: worlds (Stage bitmaps, ROS map_server maps, a TOML vector format), exact ray
//! casting with sensor presets and noise, and a disc robot that implements `MotionBase`.
//!
//! A [`Simulation`] splits into a [`SimLaser`] (a `LaserSource`), a [`SimBase`] (a `MotionBase`)
//! and a [`TruthHandle`] (the true pose and collisions, for evaluation only). Everything random is
//! drawn from one seed, so a run is reproducible.
//!
//! ```
//! use std::sync::Arc;
//! use sim_laser::{SensorPreset, Simulation, World};
//! use scan_types::{LaserSource, Pose2, RayStatus};
//! let world = Arc::new(World::paper());
//! let start = Pose2::new(-3.92, -4.26, 45f64.to_radians());
//! let (mut laser, _base, truth) =
//!     Simulation::with_preset(world, SensorPreset::Paper, start, 1).split();
//! let scan = laser.next_scan().unwrap();
//! assert_eq!(scan.len(), 685);
//! assert!(scan.status.iter().any(|s| *s == RayStatus::MaxRange));
//! assert_eq!(truth.scans_taken(), 1);
//! ```

mod description;
mod error;
mod generate;
mod geodesic;
mod mapserver;
mod sampling;
mod scenario;
mod sensor;
mod sim;
mod stage;
mod world;

pub use description::{WorldDescription, read_description};
pub use error::SimError;
pub use generate::{CLUTTER_END_M, GenParams, generate_world};
pub use geodesic::{GEODESIC_CELL_M, GEODESIC_MAX_CELLS, GEODESIC_SNAP_M, GeodesicMap, geodesic_m};
pub use mapserver::{MapMode, MapServerYaml, UnknownCells, parse_map_yaml};
pub use sampling::{
    FreeSpace, PAIR_CELL_M, PairSampler, WorldKind, clutter_world_params, corridor_world_params,
    generated_world, pair_salt, random_world_params,
};
pub use scenario::{SimSetup, file_scenario, paper_start, paper_target, stored_scenario};
pub use sensor::{
    DROPOUT_CODE, LaserNoise, SensorPreset, SigmaCombine, TOO_NEAR_CODE, cast_scan, true_scan,
};
pub use sim::{
    BaseGains, Collision, MotionNoise, SimBase, SimLaser, SimSpeeds, Simulation, TruthHandle,
};
pub use stage::stage_world_from_bytes;
pub use world::{Bitmap, MAX_COORD_M, Obstacle, World, WorldParts};
