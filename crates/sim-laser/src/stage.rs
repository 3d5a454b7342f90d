//! Stage-style bitmaps: dark pixels are obstacles; the dark pixels' bounding box is scaled to a
//! size in metres and centred on a point; an optional boundary wall encloses it.

use std::path::Path;

use crate::world::{Bitmap, WorldParts};
use crate::{SimError, World};

/// The paper's world: Stage's cave.png (GPL-2.0, from rtv/Stage; see `sim/README.md`).
static CAVE_PNG: &[u8] = include_bytes!("../../../sim/cave.png");

/// Stage's threshold: a pixel whose mean grey is below it is an obstacle.
pub const STAGE_DARK_BELOW: u16 = 128;

/// True for an obstacle pixel: mean of RGB below `dark_below` (Stage: 128) and not transparent.
fn is_dark(p: &image::Rgba<u8>, dark_below: u16) -> bool {
    let [r, g, b, a] = p.0;
    a >= 128 && (r as u32 + g as u32 + b as u32) < 3 * dark_below as u32
}

/// Turns a decoded image into a bitmap: dark-pixel bounding box scaled to `size_m`, centred on
/// `centre`; with `boundary`, the outermost ring of cells is made solid. A pixel whose mean grey
/// is below `dark_below` is dark.
pub(crate) fn bitmap_from_image(
    img: &image::RgbaImage,
    size_m: [f64; 2],
    centre: [f64; 2],
    boundary: bool,
    dark_below: u16,
) -> Option<Bitmap> {
    let (w, h) = img.dimensions();
    let (mut c0, mut c1, mut r0, mut r1) = (u32::MAX, 0u32, u32::MAX, 0u32);
    for (x, y, p) in img.enumerate_pixels() {
        if is_dark(p, dark_below) {
            c0 = c0.min(x);
            c1 = c1.max(x);
            r0 = r0.min(y);
            r1 = r1.max(y);
        }
    }
    if c0 == u32::MAX {
        // No dark pixel: use the whole image.
        (c0, c1, r0, r1) = (0, w.checked_sub(1)?, 0, h.checked_sub(1)?);
    }
    let bw = (c1 - c0 + 1) as usize;
    let bh = (r1 - r0 + 1) as usize;
    let mut occupied = vec![false; bw * bh];
    for row in 0..bh {
        // Row 0 of the bitmap is the bottom: image row r1.
        let y = r1 - row as u32;
        for col in 0..bw {
            let x = c0 + col as u32;
            let on_ring = boundary && (row == 0 || col == 0 || row + 1 == bh || col + 1 == bw);
            occupied[row * bw + col] = on_ring || is_dark(img.get_pixel(x, y), dark_below);
        }
    }
    Some(Bitmap {
        width: bw,
        height: bh,
        cell_w_m: size_m[0] / bw as f64,
        cell_h_m: size_m[1] / bh as f64,
        origin: [centre[0] - size_m[0] / 2.0, centre[1] - size_m[1] / 2.0],
        occupied,
    })
}

fn check_size(path: &Path, size_m: [f64; 2]) -> Result<(), SimError> {
    if size_m.iter().all(|s| s.is_finite() && *s > 0.0) {
        Ok(())
    } else {
        Err(SimError::Parse {
            path: path.to_path_buf(),
            line: None,
            field: "size".into(),
            message: format!("{size_m:?} must be two finite sizes > 0 metres"),
        })
    }
}

/// Builds a world from PNG (or other image) bytes the way Stage's `floorplan` does.
pub fn stage_world_from_bytes(
    bytes: &[u8],
    name: &str,
    size_m: [f64; 2],
    centre: [f64; 2],
    boundary: bool,
) -> Result<World, SimError> {
    let path = Path::new(name);
    check_size(path, size_m)?;
    let img = decode_image(bytes)
        .map_err(|message| SimError::Image {
            path: path.to_path_buf(),
            message,
        })?
        .to_rgba8();
    let bitmap =
        bitmap_from_image(&img, size_m, centre, boundary, STAGE_DARK_BELOW).ok_or_else(|| {
            SimError::Image {
                path: path.to_path_buf(),
                message: "image has no pixels".into(),
            }
        })?;
    World::from_parts(WorldParts {
        name: name.to_string(),
        bitmap: Some(bitmap),
        ..Default::default()
    })
}

impl World {
    /// The paper's world: Stage's cave.png at 10 m x 10 m centred on the origin, with a boundary
    /// wall (image row 0 at y = +5 m).
    pub fn paper() -> World {
        stage_world_from_bytes(CAVE_PNG, "paper", [10.0, 10.0], [0.0, 0.0], true)
            .expect("embedded cave.png is valid")
    }

    /// Loads a Stage bitmap scaled to `width_m` x `height_m`, centred on the origin.
    pub fn load_stage_bitmap(
        path: impl AsRef<Path>,
        width_m: f64,
        height_m: f64,
        boundary: bool,
    ) -> Result<World, SimError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| SimError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        stage_world_from_bytes(
            &bytes,
            &path.display().to_string(),
            [width_m, height_m],
            [0.0, 0.0],
            boundary,
        )
    }
}

/// Most pixels of a world's image (as many as a world's grid may have cells).
pub(crate) const MAX_IMAGE_PIXELS: u64 = 64_000_000;

/// Decodes an image file's `bytes`, refusing one of more than [`MAX_IMAGE_PIXELS`] from its
/// header, before decoding it.
pub(crate) fn decode_image(bytes: &[u8]) -> Result<image::DynamicImage, String> {
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    if u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS {
        return Err(format!(
            "{w} x {h} pixels; at most {MAX_IMAGE_PIXELS} pixels"
        ));
    }
    reader()?.decode().map_err(|e| e.to_string())
}
