//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong in the simulator: loading worlds, configuring sensors, moving.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A file could not be read or written.
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// An image could not be decoded or encoded.
    #[error("{}: image: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// What the image library said.
        message: String,
    },
    /// A world file has a bad line or field.
    #[error("{}{}: {field}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// The field (key) at fault.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A world description is inconsistent (bad shape, bad size).
    #[error("invalid world: {0}")]
    InvalidWorld(String),
    /// A sensor or noise parameter is out of its domain.
    #[error("invalid {field}: {message}")]
    InvalidConfig {
        /// The parameter.
        field: &'static str,
        /// What it must satisfy.
        message: String,
    },
    /// A motion command was not a finite number.
    #[error("invalid motion command: {what} = {value}")]
    InvalidMotion {
        /// Which command.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// An unknown sensor preset name.
    #[error("unknown sensor preset {0:?} (expected paper, urg-04lx, utm-30lx or ust-10lx)")]
    UnknownPreset(String),
    /// A start or target the robot cannot have in this world.
    #[error("impossible scenario in world {world}: the {what} {message}")]
    Scenario {
        /// The world's name.
        world: String,
        /// `start` or `target`.
        what: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A world too large for an evaluation grid (the geodesic).
    #[error(
        "world {world} is {width_m:.1} m x {height_m:.1} m: more than {max_cells} cells of {cell_m} m for the geodesic"
    )]
    WorldTooLarge {
        /// The world's name.
        world: String,
        /// Its width, metres.
        width_m: f64,
        /// Its height, metres.
        height_m: f64,
        /// The grid cell, metres.
        cell_m: f64,
        /// The most cells allowed.
        max_cells: usize,
    },
}
