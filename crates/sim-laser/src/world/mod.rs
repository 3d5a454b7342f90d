//! The world: obstacles as grid cells (from bitmaps) and exact shapes (segments, circles,
//! polygons), with a uniform-grid index, a chessboard distance field and per-quadrant empty squares
//! for fast exact ray casts.

mod build;
mod distance;
mod geometry;
mod obstacle;
mod query;
mod raycast;

use scan_types::WorldPoint;

pub use build::MAX_COORD_M;
pub(crate) use obstacle::flood_edges;
pub use obstacle::{Bitmap, Obstacle};

/// Primitive the ray caster tests exactly.
#[derive(Debug, Clone, Copy)]
enum Prim {
    Segment { a: [f64; 2], b: [f64; 2], poly: u32 },
    Circle { c: [f64; 2], r: f64 },
}

const NO_POLY: u32 = u32::MAX;

const EMPTY: u32 = 0;

const SOLID: u32 = 1;

/// Plane value of a cell holding shapes.
const LIST: u8 = 255;

/// A lane of the ray caster with no ray.
const IDLE: usize = usize::MAX;

/// The simulated world: where obstacles are. Cheap to share with `Arc`.
///
/// ```
/// use sim_laser::World;
/// use scan_types::WorldPoint;
/// let w = World::paper();
/// let (lo, hi) = w.bounds();
/// assert!((lo.x_m() + 5.0).abs() < 1e-9 && (hi.y_m() - 5.0).abs() < 1e-9);
/// // From the paper's start, straight down, the boundary wall's inner face is 0.72 m away.
/// let r = w.raycast(WorldPoint::new(-3.92, -4.26), -std::f64::consts::FRAC_PI_2, 4.0).unwrap();
/// assert!((r - 0.72).abs() < 1e-9, "{r}");
/// ```
#[derive(Debug, Clone)]
pub struct World {
    name: String,
    x0: f64,
    y0: f64,
    rx: f64,
    ry: f64,
    nx: usize,
    ny: usize,
    cells: Vec<u32>,
    list_start: Vec<u32>,
    list_items: Vec<u32>,
    dist: Vec<u16>,
    /// For the ray caster, one plane per quadrant of travel `q` (bit 0: +x, bit 1: +y), indexed in
    /// that quadrant's mirrored cell coordinates (see `Ray` in `raycast`): the side, in cells, of the largest
    /// empty square with this cell at its corner extending toward the quadrant (at most 254);
    /// 0 for a solid cell, [`LIST`] for a cell holding shapes.
    planes: [Vec<u8>; 4],
    /// 1 / cell width and 1 / cell height.
    irx: f64,
    iry: f64,
    prims: Vec<Prim>,
    polygons: Vec<Vec<[f64; 2]>>,
    obstacle_count: usize,
    bounds: ([f64; 2], [f64; 2]),
}

/// Everything needed to build a [`World`]: an optional bitmap and vector obstacles.
#[derive(Debug, Clone, Default)]
pub struct WorldParts {
    /// A name for messages.
    pub name: String,
    /// Occupied cells of a bitmap, if any.
    pub bitmap: Option<Bitmap>,
    /// Vector obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Grid cell size for vector-only worlds (metres); `None` picks one from the extent.
    pub cell_size_m: Option<f64>,
}

impl World {
    /// The world's name (file stem or "paper").
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of vector obstacles (0 for a pure bitmap world).
    pub fn obstacle_count(&self) -> usize {
        self.obstacle_count
    }

    /// Lower-left and upper-right corners of the box holding every obstacle.
    pub fn bounds(&self) -> (WorldPoint, WorldPoint) {
        let (l, h) = self.bounds;
        (WorldPoint::new(l[0], l[1]), WorldPoint::new(h[0], h[1]))
    }

    fn list(&self, cell: u32) -> &[u32] {
        let l = (cell - 2) as usize;
        &self.list_items[self.list_start[l] as usize..self.list_start[l + 1] as usize]
    }

    fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.x0) / self.rx).floor() as i64,
            ((y - self.y0) / self.ry).floor() as i64,
        )
    }
}
