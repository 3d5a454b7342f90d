//! ROS map_server maps (YAML + PGM/PNG) and `World::load`.

use std::path::Path;

use crate::world::{Bitmap, WorldParts};
use crate::{SimError, World};

/// How map_server turns pixel values into occupancy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    /// Occupied above `occupied_thresh`, free below `free_thresh`, unknown between.
    Trinary,
    /// As trinary for obstacles (the simulator has no partial occupancy).
    Scale,
    /// Pixel values are occupancy percentages (0..=100); others unknown.
    Raw,
}

/// What the simulator makes of a map_server map's unknown cells (neither free nor occupied).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UnknownCells {
    /// Unknown is free space (map_server's maps as the simulator read them before this switch).
    #[default]
    Free,
    /// Unknown is an obstacle: for maps built by SLAM, whose outside is unknown.
    Obstacle,
}

/// The fields of a map_server YAML file.
#[derive(Debug, Clone, PartialEq)]
pub struct MapServerYaml {
    /// Image path, relative to the YAML file.
    pub image: String,
    /// Metres per pixel.
    pub resolution_m: f64,
    /// World pose of the lower-left pixel: x, y, yaw (yaw is ignored, as most of ROS does).
    pub origin: [f64; 3],
    /// Swap white and black.
    pub negate: bool,
    /// Occupancy probability above which a pixel is an obstacle.
    pub occupied_thresh: f64,
    /// Occupancy probability below which a pixel is free.
    pub free_thresh: f64,
    /// Interpretation mode.
    pub mode: MapMode,
}

fn yaml_err(path: &Path, line: Option<usize>, field: &str, message: String) -> SimError {
    SimError::Parse {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    }
}

/// A map_server YAML file as written (any YAML style: flow or block lists, quoted or not);
/// unknown keys are ignored, as map_server does.
#[derive(Debug, serde::Deserialize)]
struct RawYaml {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<Vec<f64>>,
    negate: Option<serde_norway::Value>,
    occupied_thresh: Option<f64>,
    free_thresh: Option<f64>,
    mode: Option<String>,
}

/// Parses map_server YAML text; errors name the line (where the YAML parser knows it) and key.
pub fn parse_map_yaml(text: &str, path: &Path) -> Result<MapServerYaml, SimError> {
    // The line of a key, for errors found after parsing.
    let line_of = |key: &str| {
        text.lines()
            .position(|l| {
                l.trim_start()
                    .strip_prefix(key)
                    .is_some_and(|r| r.trim_start().starts_with(':'))
            })
            .map(|n| n + 1)
    };
    let err = |field: &str, message: String| yaml_err(path, line_of(field), field, message);
    let raw: RawYaml = serde_norway::from_str(text).map_err(|e| {
        let line = e.location().map(|l| l.line());
        // "resolution: invalid type ..." names its key first.
        let text = e.to_string();
        match text.split_once(": ") {
            Some((key, rest)) if !key.contains(' ') => yaml_err(path, line, key, rest.to_string()),
            _ => yaml_err(path, line, "yaml", text),
        }
    })?;
    let finite = |field: &str, v: Option<f64>| match v {
        Some(x) if !x.is_finite() => Err(err(field, format!("{x} is not a finite number"))),
        other => Ok(other),
    };
    let resolution_m =
        finite("resolution", raw.resolution)?.ok_or_else(|| err("resolution", "missing".into()))?;
    if resolution_m <= 0.0 {
        return Err(err("resolution", format!("{resolution_m} must be > 0")));
    }
    let origin = match raw.origin {
        Some(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => [v[0], v[1], v[2]],
        Some(v) => return Err(err("origin", format!("{v:?} is not [x, y, yaw]"))),
        None => return Err(err("origin", "missing".into())),
    };
    if origin[2] != 0.0 {
        tracing::warn!(file = %path.display(), yaw = origin[2], "map origin yaw ignored");
    }
    let negate = match &raw.negate {
        None => false,
        Some(serde_norway::Value::Bool(b)) => *b,
        Some(serde_norway::Value::Number(n)) if n.as_u64() == Some(0) => false,
        Some(serde_norway::Value::Number(n)) if n.as_u64() == Some(1) => true,
        Some(v) => return Err(err("negate", format!("{v:?} is not 0 or 1"))),
    };
    let mode = match raw.mode.as_deref() {
        None | Some("trinary") => MapMode::Trinary,
        Some("scale") => MapMode::Scale,
        Some("raw") => MapMode::Raw,
        Some(m) => return Err(err("mode", format!("{m:?} is not trinary, scale or raw"))),
    };
    let occ =
        finite("occupied_thresh", raw.occupied_thresh)?.unwrap_or(scan_types::MAP_OCCUPIED_THRESH);
    let free = finite("free_thresh", raw.free_thresh)?.unwrap_or(scan_types::MAP_FREE_THRESH);
    if !(0.0..=1.0).contains(&occ) || !(0.0..=1.0).contains(&free) || free > occ {
        return Err(err(
            "occupied_thresh",
            format!("need 0 <= free_thresh ({free}) <= occupied_thresh ({occ}) <= 1"),
        ));
    }
    Ok(MapServerYaml {
        image: raw.image.ok_or_else(|| err("image", "missing".into()))?,
        resolution_m,
        origin,
        negate,
        occupied_thresh: occ,
        free_thresh: free,
        mode,
    })
}

impl MapServerYaml {
    /// The occupancy probability map_server gives a pixel of mean channel value `v` (0..=255).
    fn probability(&self, v: f64) -> f64 {
        if self.negate {
            v / 255.0
        } else {
            (255.0 - v) / 255.0
        }
    }

    /// True when a pixel of mean channel value `v` (0..=255) is an obstacle.
    pub fn is_occupied(&self, v: f64) -> bool {
        match self.mode {
            MapMode::Raw => (v > self.occupied_thresh * 100.0) && v <= 100.0,
            MapMode::Trinary | MapMode::Scale => self.probability(v) > self.occupied_thresh,
        }
    }

    /// True when a pixel of mean channel value `v` (0..=255) is unknown: neither occupied nor
    /// free (trinary and scale: between the thresholds; raw: above 100).
    pub fn is_unknown(&self, v: f64) -> bool {
        match self.mode {
            MapMode::Raw => v > 100.0,
            MapMode::Trinary | MapMode::Scale => {
                let p = self.probability(v);
                p >= self.free_thresh && p <= self.occupied_thresh
            }
        }
    }
}

impl World {
    /// Loads a ROS map_server map: the YAML file and the image it names. Occupied pixels are
    /// obstacles; free and unknown pixels are free space.
    pub fn load_map_server(yaml_path: impl AsRef<Path>) -> Result<World, SimError> {
        World::load_map_server_with(yaml_path, UnknownCells::Free)
    }

    /// Loads a ROS map_server map with its unknown pixels read as `unknown` says.
    pub fn load_map_server_with(
        yaml_path: impl AsRef<Path>,
        unknown: UnknownCells,
    ) -> Result<World, SimError> {
        let path = yaml_path.as_ref();
        World::from_parts(WorldParts {
            name: path.display().to_string(),
            bitmap: Some(map_server_bitmap(path, unknown)?),
            ..Default::default()
        })
    }

    /// Loads a world by its extension: `.toml` (native), `.yaml`/`.yml` (map_server), or an image
    /// (`.png`, `.pgm`, ...: a Stage bitmap at 0.02 m per pixel of its dark-pixel bounding box,
    /// centred on the origin, no boundary; use [`World::load_stage_bitmap`] to give a size).
    pub fn load(path: impl AsRef<Path>) -> Result<World, SimError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "toml" => {
                let text = std::fs::read_to_string(path).map_err(|source| SimError::Io {
                    path: path.to_path_buf(),
                    source,
                })?;
                World::from_toml_str(&text, path)
            }
            "yaml" | "yml" => World::load_map_server(path),
            "png" | "pgm" | "bmp" | "jpg" | "jpeg" | "pnm" => {
                let bytes = std::fs::read(path).map_err(|source| SimError::Io {
                    path: path.to_path_buf(),
                    source,
                })?;
                let img = crate::stage::decode_image(&bytes)
                    .map_err(|message| SimError::Image {
                        path: path.to_path_buf(),
                        message,
                    })?
                    .to_rgba8();
                let probe = crate::stage::bitmap_from_image(
                    &img,
                    [1.0, 1.0],
                    [0.0, 0.0],
                    false,
                    crate::stage::STAGE_DARK_BELOW,
                )
                .ok_or_else(|| SimError::Image {
                    path: path.to_path_buf(),
                    message: "image has no pixels".into(),
                })?;
                let size = [probe.width as f64 * 0.02, probe.height as f64 * 0.02];
                crate::stage_world_from_bytes(
                    &bytes,
                    &path.display().to_string(),
                    size,
                    [0.0, 0.0],
                    false,
                )
            }
            _ => Err(SimError::Parse {
                path: path.to_path_buf(),
                line: None,
                field: "extension".into(),
                message: "expected .toml, .yaml/.yml or an image (.png, .pgm)".into(),
            }),
        }
    }
}

/// The bitmap of a map_server map: occupied pixels, and unknown ones if `unknown` says so.
pub(crate) fn map_server_bitmap(path: &Path, unknown: UnknownCells) -> Result<Bitmap, SimError> {
    let text = std::fs::read_to_string(path).map_err(|source| SimError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let y = parse_map_yaml(&text, path)?;
    let img_path = path.parent().unwrap_or(Path::new(".")).join(&y.image);
    let img = std::fs::read(&img_path)
        .map_err(|e| e.to_string())
        .and_then(|bytes| crate::stage::decode_image(&bytes))
        .map_err(|message| SimError::Image {
            path: img_path.clone(),
            message,
        })?
        .to_rgb8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let mut occupied = vec![false; w * h];
    for (x, yy, p) in img.enumerate_pixels() {
        let v = (p.0[0] as f64 + p.0[1] as f64 + p.0[2] as f64) / 3.0;
        let row = h - 1 - yy as usize;
        occupied[row * w + x as usize] =
            y.is_occupied(v) || (unknown == UnknownCells::Obstacle && y.is_unknown(v));
    }
    Ok(Bitmap {
        width: w,
        height: h,
        cell_w_m: y.resolution_m,
        cell_h_m: y.resolution_m,
        origin: [y.origin[0], y.origin[1]],
        occupied,
    })
}
