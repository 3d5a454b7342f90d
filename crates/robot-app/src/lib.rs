//! The goalseek program as a library: the goal-seeking loop and the commands of `robot-app`.

pub mod cmd;
pub mod logging;
pub mod scan_csv;
