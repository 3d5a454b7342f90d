//! One module per `robot-app` command: its arguments and its `run`.

pub mod batch;
pub mod emulate;
pub mod expand;
pub mod info;
pub mod landmarks;
pub mod map;
pub mod replay;
pub mod run;
pub mod scan;
pub mod sim;
pub mod world;
