//! goalseek: goal seeking, localisation and mapping with nothing but a 2D laser range finder.
//!
//! This root package owns the end-to-end tests (`tests/`) and the criterion benches
//! (`benches/`); the code lives in the crates under `crates/`, re-exported here.

pub use expansion;
pub use landmarks;
pub use localiser;
pub use navigator;
pub use planner;
pub use robot_base;
pub use scan_log;
pub use scan_types;
pub use sim_laser;
pub use urg_driver;
