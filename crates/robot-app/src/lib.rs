//! The goalseek program as a library: the goal-seeking loop and the commands of `robot-app`.

pub mod cmd;
pub mod config;
pub mod interrupt;
pub mod live;
pub mod logging;
pub mod outputs;
pub mod plot;
pub mod record;
pub mod runloop;
pub mod simsetup;
