//! Generated worlds for batches and seeded random start/target pairs that a disc robot can
//! drive between (free space with room for the robot, in one connected region).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_types::{Pose2, WorldPoint};
use serde::Serialize;

use crate::world::flood_edges;
use crate::{GenParams, SimError, World, generate_world};

/// What kind of world a run is in (batch rows and groups carry it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WorldKind {
    /// The paper's world.
    Paper,
    /// A generated rooms-and-corridor world ([`random_world_params`]).
    Random,
    /// A generated wide-corridor world ([`corridor_world_params`]).
    Corridor,
    /// A generated clutter-only open world ([`clutter_world_params`]).
    Clutter,
    /// A world loaded from a file.
    File,
}

impl std::fmt::Display for WorldKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // `pad` so that table widths apply.
        f.pad(match self {
            Self::Paper => "paper",
            Self::Random => "random",
            Self::Corridor => "corridor",
            Self::Clutter => "clutter",
            Self::File => "file",
        })
    }
}

/// Generator parameters of the random worlds: sim-laser's defaults (16 m x 10 m, three rooms
/// on each side of a 1.6 m corridor, doors, 8 boxes and 6 discs of clutter).
pub fn random_world_params() -> GenParams {
    GenParams::default()
}

/// Generator parameters of the wide-corridor worlds: 24 m x 12 m, a 4 m wide corridor with
/// nothing in it between four rooms on each side (the case the paper warns about: long
/// parallel walls with few range jumps).
pub fn corridor_world_params() -> GenParams {
    GenParams {
        width_m: 24.0,
        height_m: 12.0,
        rooms_per_side: 4,
        corridor_width_m: 4.0,
        ..GenParams::default()
    }
}

/// Generator parameters of the clutter-only worlds: a 20 m x 12 m walled open area with 5
/// boxes and 5 discs (0.2 to 0.6 m) and nothing else, so that for much of the way from a start
/// 1.5 m from the left wall to a target 1.5 m from the right wall few surfaces lie within the
/// laser's 4 m.
pub fn clutter_world_params() -> GenParams {
    GenParams {
        width_m: 20.0,
        height_m: 12.0,
        rooms_per_side: 0,
        boxes: 5,
        circles: 5,
        ..GenParams::default()
    }
}

/// A generated world of `kind` (`Random`, `Corridor` or `Clutter`) from seed `k`, with its own
/// start and target.
pub fn generated_world(kind: WorldKind, k: u64) -> Result<(World, Pose2, WorldPoint), SimError> {
    let params = match kind {
        WorldKind::Corridor => corridor_world_params(),
        WorldKind::Clutter => clutter_world_params(),
        _ => random_world_params(),
    };
    let d = generate_world(k, &params)?;
    let world = d.to_world()?;
    let [sx, sy, st] = d.start.unwrap_or([0.0; 3]);
    let [tx, ty] = d.target.unwrap_or([0.0; 2]);
    Ok((world, Pose2::new(sx, sy, st), WorldPoint::new(tx, ty)))
}

/// Free cells (robot centre positions with room for the robot) of `world` on a grid, with
/// the connected component each belongs to.
pub struct FreeSpace {
    lo: WorldPoint,
    cell_m: f64,
    nx: usize,
    ny: usize,
    component: Vec<u32>,
}

/// Most cells a [`FreeSpace`] rasterises (16 million: 200 m x 200 m at 0.05 m).
pub const MAX_FREE_CELLS: usize = 16_000_000;

impl FreeSpace {
    /// Rasterises `world` at `cell_m` (coarser when that would take more than
    /// `MAX_FREE_CELLS` (16 million) cells), keeping cells at least `room_m` from any obstacle.
    pub fn new(world: &World, room_m: f64, cell_m: f64) -> Self {
        let (lo, hi) = world.bounds();
        let area = (hi.x_m() - lo.x_m()) * (hi.y_m() - lo.y_m());
        let fine = area / (cell_m * cell_m);
        let cell_m = if fine > MAX_FREE_CELLS as f64 {
            let coarse = (area / MAX_FREE_CELLS as f64).sqrt() * 1.01;
            tracing::warn!(
                world = world.name(),
                cell_m,
                coarse_m = coarse,
                "world too large to rasterise at the cell size asked for; coarser cells"
            );
            coarse
        } else {
            cell_m
        };
        let nx = ((hi.x_m() - lo.x_m()) / cell_m).ceil().max(1.0) as usize;
        let ny = ((hi.y_m() - lo.y_m()) / cell_m).ceil().max(1.0) as usize;
        let centre = |ix: usize, iy: usize| {
            WorldPoint::new(
                lo.x_m() + (ix as f64 + 0.5) * cell_m,
                lo.y_m() + (iy as f64 + 0.5) * cell_m,
            )
        };
        let free: Vec<bool> = (0..nx * ny)
            .map(|k| {
                let p = centre(k % nx, k / nx);
                !world.is_occupied(p) && world.clearance(p, room_m + 0.01) >= room_m
            })
            .collect();
        let mut component = vec![0u32; nx * ny];
        let mut next = 1u32;
        for startk in 0..nx * ny {
            if !free[startk] || component[startk] != 0 {
                continue;
            }
            component[startk] = next;
            flood_edges(nx, ny, startk, |k| {
                let enter = free[k] && component[k] == 0;
                if enter {
                    component[k] = next;
                }
                enter
            });
            next += 1;
        }
        Self {
            lo,
            cell_m,
            nx,
            ny,
            component,
        }
    }

    /// A random start pose and target in one connected free region, at least `min_m` apart.
    pub fn random_pair(&self, rng: &mut ChaCha8Rng, min_m: f64) -> Option<(Pose2, WorldPoint)> {
        self.random_pair_where(rng, min_m, |_| true)
    }

    /// Grid size in cells (columns, rows).
    pub(crate) fn dims(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The grid's lower-left corner.
    pub(crate) fn origin(&self) -> WorldPoint {
        self.lo
    }

    /// Cell side, metres.
    pub(crate) fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Whether cell `k` (row-major) is free.
    pub(crate) fn is_free(&self, k: usize) -> bool {
        self.component.get(k).is_some_and(|&c| c != 0)
    }

    /// The connected region of cell `k` (0: not free).
    pub(crate) fn region(&self, k: usize) -> u32 {
        self.component.get(k).copied().unwrap_or(0)
    }

    /// The centre of cell `k`.
    pub(crate) fn centre(&self, k: usize) -> WorldPoint {
        WorldPoint::new(
            self.lo.x_m() + ((k % self.nx) as f64 + 0.5) * self.cell_m,
            self.lo.y_m() + ((k / self.nx) as f64 + 0.5) * self.cell_m,
        )
    }

    /// Free cells (centres) in connected region order.
    pub fn free_cells(&self) -> impl Iterator<Item = WorldPoint> + '_ {
        (0..self.component.len())
            .filter(|&k| self.component[k] != 0)
            .map(|k| self.centre(k))
    }

    /// Whether `p` is a free cell, and its region.
    pub fn region_of(&self, p: WorldPoint) -> Option<u32> {
        let fx = (p.x_m() - self.lo.x_m()) / self.cell_m;
        let fy = (p.y_m() - self.lo.y_m()) / self.cell_m;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (ix, iy) = (fx as usize, fy as usize);
        if ix >= self.nx || iy >= self.ny {
            return None;
        }
        Some(self.component[iy * self.nx + ix]).filter(|&c| c != 0)
    }

    /// A seeded random pose (cell centre, heading) in the largest connected free region: where
    /// an exploration of an unknown world starts when none is given.
    pub fn random_start(&self, seed: u64) -> Option<Pose2> {
        let mut sizes = std::collections::HashMap::<u32, usize>::new();
        for &c in self.component.iter().filter(|&&c| c != 0) {
            *sizes.entry(c).or_default() += 1;
        }
        let (&largest, _) = sizes
            .iter()
            .max_by_key(|&(c, n)| (*n, std::cmp::Reverse(*c)))?;
        let cells: Vec<usize> = (0..self.component.len())
            .filter(|&k| self.component[k] == largest)
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xe0_0000_0000);
        let p = self.centre(cells[rng.random_range(0..cells.len())]);
        let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        Some(Pose2::new(p.x_m(), p.y_m(), heading))
    }

    /// As [`FreeSpace::random_pair`], with both ends where `keep` holds.
    pub fn random_pair_where(
        &self,
        rng: &mut ChaCha8Rng,
        min_m: f64,
        keep: impl Fn(WorldPoint) -> bool,
    ) -> Option<(Pose2, WorldPoint)> {
        let cells: Vec<usize> = (0..self.component.len())
            .filter(|&k| self.component[k] != 0 && keep(self.centre(k)))
            .collect();
        if cells.is_empty() {
            return None;
        }
        let centre = |k: usize| self.centre(k);
        for _ in 0..10_000 {
            let a = cells[rng.random_range(0..cells.len())];
            let b = cells[rng.random_range(0..cells.len())];
            if self.component[a] != self.component[b] {
                continue;
            }
            let (pa, pb) = (centre(a), centre(b));
            if pa.distance_m(&pb) < min_m {
                continue;
            }
            let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            return Some((Pose2::new(pa.x_m(), pa.y_m(), heading), pb));
        }
        None
    }
}

/// Grid cell of the free space random pairs are drawn from, metres.
pub const PAIR_CELL_M: f64 = 0.1;

/// Salt of the pair generator of world `k` of `kind` (0 for the paper world and files), so
/// generated worlds get pairs of their own for the same seed.
pub fn pair_salt(kind: WorldKind, k: u64) -> u64 {
    match kind {
        WorldKind::Random | WorldKind::Corridor | WorldKind::Clutter => {
            (k + 1) << 32
                | match kind {
                    WorldKind::Corridor => 1 << 31,
                    WorldKind::Clutter => 1 << 30,
                    _ => 0,
                }
        }
        WorldKind::Paper | WorldKind::File => 0,
    }
}

/// Seeded random start/target pairs in one world (in a corridor world: inside the corridor).
pub struct PairSampler {
    free: FreeSpace,
    salt: u64,
    corridor_half_m: Option<f64>,
}

impl PairSampler {
    /// Pairs in `world`, world `k` of `kind`, with both ends at least `room_m` from any obstacle.
    pub fn new(world: &World, kind: WorldKind, k: u64, room_m: f64) -> Self {
        Self {
            free: FreeSpace::new(world, room_m, PAIR_CELL_M),
            salt: pair_salt(kind, k),
            corridor_half_m: (kind == WorldKind::Corridor)
                .then(|| corridor_world_params().corridor_width_m / 2.0 - room_m),
        }
    }

    /// The pair of noise seed `seed`, at least `min_m` apart, or `None` if none was found.
    pub fn pair(&self, seed: u64, min_m: f64) -> Option<(Pose2, WorldPoint)> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0000_0000 ^ self.salt);
        match self.corridor_half_m {
            Some(h) => self
                .free
                .random_pair_where(&mut rng, min_m, |p| p.y_m().abs() <= h),
            None => self.free.random_pair(&mut rng, min_m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_pairs_are_free_far_apart_and_in_the_corridor() {
        for kind in [WorldKind::Random, WorldKind::Corridor] {
            let (world, start, target) = generated_world(kind, 3).unwrap();
            // The generator's own scenario is free for a 0.3 m robot.
            assert!(!world.disc_collides(start.position(), 0.3));
            assert!(!world.disc_collides(target, 0.3));
            let free = FreeSpace::new(&world, 0.4, 0.1);
            let half = corridor_world_params().corridor_width_m / 2.0 - 0.4;
            for i in 0..5u64 {
                let mut rng = ChaCha8Rng::seed_from_u64(i);
                let (s, g) = if kind == WorldKind::Corridor {
                    free.random_pair_where(&mut rng, 6.0, |p| p.y_m().abs() <= half)
                } else {
                    free.random_pair(&mut rng, 6.0)
                }
                .unwrap();
                assert!(s.position().distance_m(&g) >= 6.0);
                // At least the robot radius plus 0.1 m from every obstacle.
                assert!(!world.disc_collides(s.position(), 0.4));
                assert!(!world.disc_collides(g, 0.4));
                assert_eq!(free.region_of(s.position()), free.region_of(g));
                if kind == WorldKind::Corridor {
                    // The corridor is 4 m wide around y = 0.
                    assert!(s.y_m.abs() <= 1.6 && g.y_m().abs() <= 1.6);
                }
            }
        }
    }

    #[test]
    fn salts_differ_by_kind_and_index() {
        assert_eq!(pair_salt(WorldKind::Paper, 3), 0);
        assert_eq!(pair_salt(WorldKind::File, 3), 0);
        assert_eq!(pair_salt(WorldKind::Random, 0), 1 << 32);
        assert_eq!(pair_salt(WorldKind::Corridor, 1), (2 << 32) | (1 << 31));
    }
}
