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

fn parse_num_list(v: &str) -> Option<Vec<f64>> {
    let inner = v.trim().strip_prefix('[')?.strip_suffix(']')?;
    inner
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok())
        .collect()
}

fn yaml_err(path: &Path, line: Option<usize>, field: &str, message: String) -> SimError {
    SimError::Parse {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    }
}

/// The keys of a map_server YAML read so far (defaults for the optional ones).
struct YamlKeys {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<[f64; 3]>,
    negate: bool,
    occ: f64,
    free: f64,
    mode: MapMode,
}

/// Parses map_server YAML text (flat `key: value` lines); errors name the line and key.
pub fn parse_map_yaml(text: &str, path: &Path) -> Result<MapServerYaml, SimError> {
    let err =
        |line: Option<usize>, field: &str, message: String| yaml_err(path, line, field, message);
    let mut keys = YamlKeys {
        image: None,
        resolution: None,
        origin: None,
        negate: false,
        occ: 0.65,
        free: 0.196,
        mode: MapMode::Trinary,
    };
    for (n, raw) in text.lines().enumerate() {
        let line = Some(n + 1);
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let Some((key, value)) = content.split_once(':') else {
            return Err(err(
                line,
                "yaml",
                format!("expected 'key: value', found {content:?}"),
            ));
        };
        let key = key.trim();
        let value = value.trim().trim_matches('"').trim_matches('\'');
        keys.set(key, value, line, path)?;
    }
    let (occ, free) = (keys.occ, keys.free);
    if !(0.0..=1.0).contains(&occ) || !(0.0..=1.0).contains(&free) || free > occ {
        return Err(err(
            None,
            "occupied_thresh",
            format!("need 0 <= free_thresh ({free}) <= occupied_thresh ({occ}) <= 1"),
        ));
    }
    Ok(MapServerYaml {
        image: keys
            .image
            .ok_or_else(|| err(None, "image", "missing".into()))?,
        resolution_m: keys
            .resolution
            .ok_or_else(|| err(None, "resolution", "missing".into()))?,
        origin: keys
            .origin
            .ok_or_else(|| err(None, "origin", "missing".into()))?,
        negate: keys.negate,
        occupied_thresh: occ,
        free_thresh: free,
        mode: keys.mode,
    })
}

impl YamlKeys {
    /// Reads `key: value` of line `line`; unknown keys are ignored (logged).
    fn set(
        &mut self,
        key: &str,
        value: &str,
        line: Option<usize>,
        path: &Path,
    ) -> Result<(), SimError> {
        let err = |message: String| yaml_err(path, line, key, message);
        let num = |v: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| err(format!("{v:?} is not a number")))
        };
        match key {
            "image" => self.image = Some(value.to_string()),
            "resolution" => {
                let r = num(value)?;
                if r <= 0.0 {
                    return Err(err(format!("{r} must be > 0")));
                }
                self.resolution = Some(r);
            }
            "origin" => {
                let v = parse_num_list(value)
                    .filter(|v| v.len() == 3 && v.iter().all(|x| x.is_finite()))
                    .ok_or_else(|| err(format!("{value:?} is not [x, y, yaw]")))?;
                if v[2] != 0.0 {
                    tracing::warn!(file = %path.display(), yaw = v[2], "map origin yaw ignored");
                }
                self.origin = Some([v[0], v[1], v[2]]);
            }
            "negate" => {
                self.negate = match value {
                    "0" | "false" | "False" => false,
                    "1" | "true" | "True" => true,
                    _ => return Err(err(format!("{value:?} is not 0 or 1"))),
                }
            }
            "occupied_thresh" => self.occ = num(value)?,
            "free_thresh" => self.free = num(value)?,
            "mode" => {
                self.mode = match value {
                    "trinary" => MapMode::Trinary,
                    "scale" => MapMode::Scale,
                    "raw" => MapMode::Raw,
                    _ => return Err(err(format!("{value:?} is not trinary, scale or raw"))),
                }
            }
            _ => tracing::debug!(file = %path.display(), key, "unknown map_server key ignored"),
        }
        Ok(())
    }
}

impl MapServerYaml {
    /// True when a pixel of mean channel value `v` (0..=255) is an obstacle.
    pub fn is_occupied(&self, v: f64) -> bool {
        match self.mode {
            MapMode::Raw => (v > self.occupied_thresh * 100.0) && v <= 100.0,
            MapMode::Trinary | MapMode::Scale => {
                let p = if self.negate {
                    v / 255.0
                } else {
                    (255.0 - v) / 255.0
                };
                p > self.occupied_thresh
            }
        }
    }
}

impl World {
    /// Loads a ROS map_server map: the YAML file and the image it names. Occupied pixels are
    /// obstacles; free and unknown pixels are free space.
    pub fn load_map_server(yaml_path: impl AsRef<Path>) -> Result<World, SimError> {
        let path = yaml_path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SimError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let y = parse_map_yaml(&text, path)?;
        let img_path = path.parent().unwrap_or(Path::new(".")).join(&y.image);
        let img = image::open(&img_path)
            .map_err(|e| SimError::Image {
                path: img_path.clone(),
                message: e.to_string(),
            })?
            .to_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let mut occupied = vec![false; w * h];
        for (x, yy, p) in img.enumerate_pixels() {
            let v = (p.0[0] as f64 + p.0[1] as f64 + p.0[2] as f64) / 3.0;
            let row = h - 1 - yy as usize;
            occupied[row * w + x as usize] = y.is_occupied(v);
        }
        World::from_parts(WorldParts {
            name: path.display().to_string(),
            bitmap: Some(Bitmap {
                width: w,
                height: h,
                cell_w_m: y.resolution_m,
                cell_h_m: y.resolution_m,
                origin: [y.origin[0], y.origin[1]],
                occupied,
            }),
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
                let img = image::load_from_memory(&bytes)
                    .map_err(|e| SimError::Image {
                        path: path.to_path_buf(),
                        message: e.to_string(),
                    })?
                    .to_rgba8();
                let probe = crate::stage::bitmap_from_image(&img, [1.0, 1.0], [0.0, 0.0], false)
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
