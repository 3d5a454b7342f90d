//! The simulator: worlds (Stage bitmaps, ROS map_server maps, a TOML vector format),
//! exact ray casting with sensor presets and noise, and a disc robot that implements `MotionBase`.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
