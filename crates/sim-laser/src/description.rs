//! The native TOML world format and `WorldDescription`, the editable form of a vector world.

use std::path::Path;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::stage::bitmap_from_image;
use crate::world::{Bitmap, Obstacle, WorldParts};
use crate::{MAX_COORD_M, SimError, UnknownCells, World};

/// A vector world with its scenario: what the generator produces and the TOML format stores.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WorldDescription {
    /// A name for messages.
    pub name: String,
    /// The rectangle the world occupies (lower-left, upper-right), if given.
    pub bounds: Option<([f64; 2], [f64; 2])>,
    /// With `bounds`: enclose them with four zero-thickness walls.
    pub boundary: bool,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Suggested start pose `(x_m, y_m, theta_rad)`.
    pub start: Option<[f64; 3]>,
    /// Suggested target `(x_m, y_m)`.
    pub target: Option<[f64; 2]>,
}

impl WorldDescription {
    /// Builds the world (grid cell size chosen from the extent).
    pub fn to_world(&self) -> Result<World, SimError> {
        World::from_parts(WorldParts {
            name: self.name.clone(),
            bitmap: None,
            obstacles: self.all_obstacles(),
            cell_size_m: None,
        })
    }

    /// The obstacles plus the boundary walls, if any.
    pub fn all_obstacles(&self) -> Vec<Obstacle> {
        let mut v = self.obstacles.clone();
        if let (true, Some((l, h))) = (self.boundary, self.bounds) {
            let c = [[l[0], l[1]], [h[0], l[1]], [h[0], h[1]], [l[0], h[1]]];
            for i in 0..4 {
                v.push(Obstacle::Segment {
                    a: c[i],
                    b: c[(i + 1) % 4],
                });
            }
        }
        v
    }

    /// The TOML text of this description (the format `World::load` reads).
    pub fn to_toml(&self) -> String {
        let mut file = TomlWorld {
            name: Some(self.name.clone()),
            cell_size_m: None,
            bounds: self.bounds.map(|(min, max)| {
                Spanned::new(
                    0..0,
                    TomlBounds {
                        min,
                        max,
                        boundary: self.boundary,
                    },
                )
            }),
            start: self
                .start
                .map(|[x, y, t]| Spanned::new(0..0, [x, y, t.to_degrees()])),
            target: self.target,
            bitmap: None,
            map_server: None,
            r#box: Vec::new(),
            circle: Vec::new(),
            polygon: Vec::new(),
            wall: Vec::new(),
        };
        for o in &self.obstacles {
            match o {
                Obstacle::Box {
                    centre,
                    size,
                    angle_rad,
                } => file.r#box.push(Spanned::new(
                    0..0,
                    TomlBox {
                        centre: *centre,
                        size: *size,
                        angle_deg: angle_rad.to_degrees(),
                    },
                )),
                Obstacle::Circle { centre, radius } => file.circle.push(Spanned::new(
                    0..0,
                    TomlCircle {
                        centre: *centre,
                        radius: *radius,
                    },
                )),
                Obstacle::Polygon { points } => file.polygon.push(Spanned::new(
                    0..0,
                    TomlPolygon {
                        points: points.clone(),
                    },
                )),
                Obstacle::Segment { a, b } => file.wall.push(Spanned::new(
                    0..0,
                    TomlWall {
                        from: *a,
                        to: *b,
                        thickness: 0.0,
                    },
                )),
            }
        }
        let body = toml::to_string(&file).unwrap_or_default();
        format!("# goalseek world (TOML, see docs/sim-laser.md)\n{body}")
    }

    /// Writes the TOML form atomically.
    pub fn write_toml(&self, path: &Path) -> Result<(), SimError> {
        write_atomic(path, self.to_toml().as_bytes())
    }

    /// Rasterises the world at `resolution_m` over its bounds (or obstacle extent) and writes
    /// a ROS map_server pair: `path` (YAML) and the PGM beside it (same stem), atomically.
    pub fn write_map_server(&self, yaml_path: &Path, resolution_m: f64) -> Result<(), SimError> {
        let (bm, lo) = self.rasterise(resolution_m)?;
        let pgm_path = yaml_path.with_extension("pgm");
        let img = bitmap_to_gray(&bm);
        let mut pgm = format!("P5\n{} {}\n255\n", bm.width, bm.height).into_bytes();
        pgm.extend_from_slice(img.as_raw());
        write_atomic(&pgm_path, &pgm)?;
        let image_name = pgm_path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let yaml = format!(
            "image: {image_name}\nmode: trinary\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: {}\nfree_thresh: {}\n",
            scan_types::format_decimal(resolution_m),
            scan_types::format_decimal(lo[0]),
            scan_types::format_decimal(lo[1]),
            scan_types::MAP_OCCUPIED_THRESH,
            scan_types::MAP_FREE_THRESH,
        );
        write_atomic(yaml_path, yaml.as_bytes())
    }

    /// Rasterises the world at `resolution_m` per pixel and writes a Stage-style PNG atomically
    /// (dark = obstacle). Load it back with `World::load_stage_bitmap` and the bounds' size.
    pub fn write_png(&self, path: &Path, resolution_m: f64) -> Result<(), SimError> {
        let (bm, _) = self.rasterise(resolution_m)?;
        write_bitmap_png(&bm, path)
    }

    fn rasterise(&self, resolution_m: f64) -> Result<(Bitmap, [f64; 2]), SimError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(SimError::InvalidConfig {
                field: "resolution_m",
                message: format!("{resolution_m} must be finite and > 0"),
            });
        }
        let world = self.to_world()?;
        let (lo, hi) = match self.bounds {
            Some(b) => b,
            None => {
                let (l, h) = world.bounds();
                ([l.x_m(), l.y_m()], [h.x_m(), h.y_m()])
            }
        };
        let cells = ((hi[0] - lo[0]) / resolution_m) * ((hi[1] - lo[1]) / resolution_m);
        if cells > 1.0e8 {
            return Err(SimError::InvalidConfig {
                field: "resolution_m",
                message: format!("{resolution_m} m gives {cells:.0} pixels; too many"),
            });
        }
        Ok((world.rasterise(lo, hi, resolution_m), lo))
    }
}

/// Writes `bm` as a grey PNG at `path`, atomically.
fn write_bitmap_png(bm: &Bitmap, path: &Path) -> Result<(), SimError> {
    let mut bytes = Vec::new();
    bitmap_to_gray(bm)
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| SimError::Image {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    write_atomic(path, &bytes)
}

fn bitmap_to_gray(bm: &Bitmap) -> image::GrayImage {
    image::GrayImage::from_fn(bm.width as u32, bm.height as u32, |x, y| {
        let row = bm.height - 1 - y as usize;
        image::Luma([if bm.occupied[row * bm.width + x as usize] {
            0
        } else {
            254
        }])
    })
}

/// Writes `bytes` to `path` atomically ([`scan_types::write_atomic`]).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SimError> {
    scan_types::write_atomic(path, bytes).map_err(|source| SimError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlWorld {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cell_size_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    start: Option<Spanned<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bounds: Option<Spanned<TomlBounds>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bitmap: Option<Spanned<TomlBitmap>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    map_server: Option<Spanned<TomlMapServer>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    r#box: Vec<Spanned<TomlBox>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    circle: Vec<Spanned<TomlCircle>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    polygon: Vec<Spanned<TomlPolygon>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    wall: Vec<Spanned<TomlWall>>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlBounds {
    min: [f64; 2],
    max: [f64; 2],
    #[serde(default)]
    boundary: bool,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlBitmap {
    image: String,
    size: [f64; 2],
    #[serde(default)]
    centre: [f64; 2],
    #[serde(default)]
    boundary: bool,
    #[serde(default = "stage_dark_below")]
    dark_below: u16,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    free_region: Option<[f64; 2]>,
}

fn stage_dark_below() -> u16 {
    crate::stage::STAGE_DARK_BELOW
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlMapServer {
    yaml: String,
    #[serde(default)]
    unknown: UnknownCells,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlBox {
    centre: [f64; 2],
    size: [f64; 2],
    #[serde(default)]
    angle_deg: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlCircle {
    centre: [f64; 2],
    radius: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlPolygon {
    points: Vec<[f64; 2]>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlWall {
    from: [f64; 2],
    to: [f64; 2],
    #[serde(default)]
    thickness: f64,
}

/// 1-based line of byte offset `at` in `text`.
pub(crate) fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A parsed TOML world: the description plus an optional bitmap reference.
pub(crate) struct ParsedToml {
    pub desc: WorldDescription,
    pub cell_size_m: Option<f64>,
    pub bitmap: Option<Bitmap>,
}

/// The text and file of a TOML world being parsed, for errors that name a line and a field.
struct TomlSource<'a> {
    text: &'a str,
    path: &'a Path,
}

impl TomlSource<'_> {
    fn err(&self, line: Option<usize>, field: &str, message: String) -> SimError {
        SimError::Parse {
            path: self.path.to_path_buf(),
            line,
            field: field.to_string(),
            message,
        }
    }

    /// The line where `span` starts.
    fn line(&self, span: std::ops::Range<usize>) -> Option<usize> {
        Some(line_of(self.text, span.start))
    }
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Parses the TOML world text; `path` names the file in errors and anchors the bitmap path.
pub(crate) fn parse_toml(text: &str, path: &Path) -> Result<ParsedToml, SimError> {
    let src = TomlSource { text, path };
    let file: TomlWorld = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        src.err(line, "toml", e.message().trim().to_string())
    })?;
    let mut desc = toml_frame(&src, &file)?;
    toml_obstacles(&src, &file, &mut desc)?;
    let bitmap = toml_bitmap(&src, &file)?;
    if let Some(c) = file.cell_size_m
        && !(c.is_finite() && c > 0.0)
    {
        return Err(src.err(None, "cell_size_m", format!("{c} must be > 0")));
    }
    Ok(ParsedToml {
        desc,
        cell_size_m: file.cell_size_m,
        bitmap,
    })
}

/// The name, bounds, start and target of a TOML world (no obstacles yet).
fn toml_frame(src: &TomlSource, file: &TomlWorld) -> Result<WorldDescription, SimError> {
    let mut desc = WorldDescription {
        name: file.name.clone().unwrap_or_else(|| {
            src.path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        }),
        ..Default::default()
    };
    if let Some(b) = &file.bounds {
        let line = src.line(b.span());
        let b = b.get_ref();
        if !(finite(&b.min) && finite(&b.max) && b.max[0] > b.min[0] && b.max[1] > b.min[1]) {
            return Err(src.err(
                line,
                "bounds",
                "min and max must be finite with max > min".into(),
            ));
        }
        desc.bounds = Some((b.min, b.max));
        desc.boundary = b.boundary;
    }
    if let Some(s) = &file.start {
        let v = *s.get_ref();
        if !finite(&v) {
            return Err(src.err(
                src.line(s.span()),
                "start",
                "must be [x_m, y_m, theta_deg], finite".into(),
            ));
        }
        desc.start = Some([v[0], v[1], v[2].to_radians()]);
    }
    desc.target = file.target;
    Ok(desc)
}

/// Adds the boxes, circles, polygons and walls of a TOML world to `desc`, in that order; each
/// obstacle is checked as it is added, so an error names its line.
fn toml_obstacles(
    src: &TomlSource,
    file: &TomlWorld,
    desc: &mut WorldDescription,
) -> Result<(), SimError> {
    let mut push = |o: Obstacle, span: std::ops::Range<usize>, field: &str| {
        let idx = desc.obstacles.len();
        o.validate(idx).map_err(|e| {
            src.err(
                src.line(span),
                field,
                e.to_string()
                    .replace(&format!("invalid world: obstacle {idx}: "), ""),
            )
        })?;
        desc.obstacles.push(o);
        Ok::<(), SimError>(())
    };
    for b in &file.r#box {
        let v = b.get_ref();
        push(
            Obstacle::Box {
                centre: v.centre,
                size: v.size,
                angle_rad: v.angle_deg.to_radians(),
            },
            b.span(),
            "box",
        )?;
    }
    for c in &file.circle {
        let v = c.get_ref();
        push(
            Obstacle::Circle {
                centre: v.centre,
                radius: v.radius,
            },
            c.span(),
            "circle",
        )?;
    }
    for p in &file.polygon {
        push(
            Obstacle::Polygon {
                points: p.get_ref().points.clone(),
            },
            p.span(),
            "polygon",
        )?;
    }
    for w in &file.wall {
        let v = w.get_ref();
        if !(v.thickness.is_finite() && v.thickness >= 0.0) {
            return Err(src.err(
                src.line(w.span()),
                "wall.thickness",
                format!("{} must be finite and >= 0", v.thickness),
            ));
        }
        push(wall_obstacle(v), w.span(), "wall")?;
    }
    Ok(())
}

/// A wall as an obstacle: a thin box when it has a thickness, else a segment.
fn wall_obstacle(v: &TomlWall) -> Obstacle {
    if v.thickness > 0.0 {
        let d = [v.to[0] - v.from[0], v.to[1] - v.from[1]];
        Obstacle::Box {
            centre: [(v.from[0] + v.to[0]) / 2.0, (v.from[1] + v.to[1]) / 2.0],
            size: [d[0].hypot(d[1]).max(1e-9), v.thickness],
            angle_rad: d[1].atan2(d[0]),
        }
    } else {
        Obstacle::Segment { a: v.from, b: v.to }
    }
}

/// The bitmap a TOML world refers to (a Stage image or a map_server map, path relative to the
/// world file), if any.
fn toml_bitmap(src: &TomlSource, file: &TomlWorld) -> Result<Option<Bitmap>, SimError> {
    if let Some(m) = &file.map_server {
        let line = src.line(m.span());
        if file.bitmap.is_some() {
            return Err(src.err(
                line,
                "map_server",
                "a world has either [bitmap] or [map_server], not both".into(),
            ));
        }
        let m = m.get_ref();
        let yaml = src.path.parent().unwrap_or(Path::new(".")).join(&m.yaml);
        return crate::mapserver::map_server_bitmap(&yaml, m.unknown)
            .map(Some)
            .map_err(|e| src.err(line, "map_server.yaml", e.to_string()));
    }
    let Some(b) = &file.bitmap else {
        return Ok(None);
    };
    let line = src.line(b.span());
    let v = b.get_ref();
    // Within the limit, hence finite too.
    let near = |x: &[f64]| x.iter().all(|c| c.abs() <= MAX_COORD_M);
    if !(near(&v.size) && near(&v.centre) && v.size[0] > 0.0 && v.size[1] > 0.0) {
        return Err(src.err(
            line,
            "bitmap.size",
            format!("size must be > 0 and centre finite, both within {MAX_COORD_M:e} m"),
        ));
    }
    if !(1..=256).contains(&v.dark_below) {
        return Err(src.err(
            line,
            "bitmap.dark_below",
            format!(
                "{} is out of range: a grey level 1..=256 (pixels darker than it are obstacles)",
                v.dark_below
            ),
        ));
    }
    let img_path = src.path.parent().unwrap_or(Path::new(".")).join(&v.image);
    let img = std::fs::read(&img_path)
        .map_err(|e| e.to_string())
        .and_then(|bytes| crate::stage::decode_image(&bytes))
        .map_err(|e| src.err(line, "bitmap.image", format!("{}: {e}", img_path.display())))?
        .to_rgba8();
    let mut bitmap = bitmap_from_image(&img, v.size, v.centre, v.boundary, v.dark_below)
        .ok_or_else(|| src.err(line, "bitmap.image", "image is empty".into()))?;
    if let Some(at) = v.free_region
        && !(finite(&at) && bitmap.keep_region_at(at))
    {
        return Err(src.err(
            line,
            "bitmap.free_region",
            format!("{at:?} is not on a free cell of the bitmap"),
        ));
    }
    Ok(Some(bitmap))
}

impl World {
    /// Builds a world from the TOML text of the native format; `path` names it in errors.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<World, SimError> {
        let p = parse_toml(text, path)?;
        World::from_parts(WorldParts {
            name: p.desc.name.clone(),
            bitmap: p.bitmap,
            obstacles: p.desc.all_obstacles(),
            cell_size_m: p.cell_size_m,
        })
    }
}

impl World {
    /// Rasterises the world over its bounds at `cell_m` per pixel and writes it as a PNG
    /// atomically (obstacles 0, free space 254, north up).
    pub fn write_png(&self, path: &Path, cell_m: f64) -> Result<(), SimError> {
        let (lo, hi) = self.bounds();
        let bm = self.rasterise([lo.x_m(), lo.y_m()], [hi.x_m(), hi.y_m()], cell_m);
        write_bitmap_png(&bm, path)
    }
}

/// Reads a TOML world file as a description (bitmaps are not part of a description).
pub fn read_description(path: &Path) -> Result<WorldDescription, SimError> {
    let text = std::fs::read_to_string(path).map_err(|source| SimError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(parse_toml(&text, path)?.desc)
}
