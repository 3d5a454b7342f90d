//! Seeded random worlds: a corridor with rooms on both sides, doors, and clutter; or, with no
//! rooms (`rooms_per_side = 0`), an open walled area with sparse clutter only.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{Obstacle, SimError, WorldDescription};

/// Parameters of the random world generator.
#[derive(Debug, Clone, PartialEq)]
pub struct GenParams {
    /// World width, metres.
    pub width_m: f64,
    /// World height, metres.
    pub height_m: f64,
    /// Rooms on each side of the corridor; 0 makes a clutter-only world: the outer walls and
    /// sparse clutter in the open, no corridor, rooms or doors.
    pub rooms_per_side: usize,
    /// Corridor width, metres.
    pub corridor_width_m: f64,
    /// Door width, metres.
    pub door_width_m: f64,
    /// Wall thickness, metres.
    pub wall_thickness_m: f64,
    /// Probability that two neighbouring rooms share a door.
    pub side_door_prob: f64,
    /// Number of clutter boxes.
    pub boxes: usize,
    /// Number of round clutter obstacles.
    pub circles: usize,
    /// Smallest and largest clutter size (box side, circle diameter), metres.
    pub clutter_size_m: [f64; 2],
    /// Free gap kept between clutter, walls, doors, start and target, metres.
    pub clearance_m: f64,
}

impl Default for GenParams {
    fn default() -> Self {
        Self {
            width_m: 16.0,
            height_m: 10.0,
            rooms_per_side: 3,
            corridor_width_m: 1.6,
            door_width_m: 1.0,
            wall_thickness_m: 0.1,
            side_door_prob: 0.5,
            boxes: 8,
            circles: 6,
            clutter_size_m: [0.2, 0.6],
            clearance_m: 0.7,
        }
    }
}

impl GenParams {
    fn validate(&self) -> Result<(), SimError> {
        let bad =
            |field: &'static str, message: String| Err(SimError::InvalidConfig { field, message });
        for (f, v) in [
            ("width_m", self.width_m),
            ("height_m", self.height_m),
            ("corridor_width_m", self.corridor_width_m),
            ("door_width_m", self.door_width_m),
            ("wall_thickness_m", self.wall_thickness_m),
            ("clearance_m", self.clearance_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(f, format!("{v} must be finite and > 0"));
            }
        }
        let [a, b] = self.clutter_size_m;
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= a) {
            return bad(
                "clutter_size_m",
                format!("[{a}, {b}] must be 0 < min <= max"),
            );
        }
        if self.rooms_per_side == 0 {
            // Start and target sit CLUTTER_END_M from the side walls, apart by at least 1 m.
            if self.width_m < 2.0 * CLUTTER_END_M + 1.0 || self.height_m < 2.0 {
                return bad(
                    if self.height_m < 2.0 {
                        "height_m"
                    } else {
                        "width_m"
                    },
                    format!(
                        "a clutter-only world needs at least {} m x 2 m",
                        2.0 * CLUTTER_END_M + 1.0
                    ),
                );
            }
            return Ok(());
        }
        let room_w = self.width_m / self.rooms_per_side as f64;
        if room_w < self.door_width_m + 4.0 * self.wall_thickness_m + 0.4 {
            return bad(
                "rooms_per_side",
                format!("rooms {room_w:.2} m wide are too narrow for a door"),
            );
        }
        let room_h = (self.height_m - self.corridor_width_m) / 2.0;
        if room_h < self.door_width_m + 4.0 * self.wall_thickness_m + 0.4 {
            return bad(
                "height_m",
                format!("rooms {room_h:.2} m deep are too shallow"),
            );
        }
        if !(0.0..=1.0).contains(&self.side_door_prob) {
            return bad(
                "side_door_prob",
                format!("{} must be in 0..=1", self.side_door_prob),
            );
        }
        Ok(())
    }
}

/// A horizontal or vertical wall from `a` to `b` along one axis, with gaps, as boxes.
fn wall_with_gaps(
    out: &mut Vec<Obstacle>,
    horizontal: bool,
    fixed: f64,
    from: f64,
    to: f64,
    gaps: &[(f64, f64)],
    t: f64,
) {
    let mut cuts: Vec<(f64, f64)> = gaps.to_vec();
    cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut s = from;
    let mut pieces = Vec::new();
    for (g0, g1) in cuts {
        if g0 > s {
            pieces.push((s, g0));
        }
        s = s.max(g1);
    }
    if to > s {
        pieces.push((s, to));
    }
    for (p0, p1) in pieces {
        let (c, len) = ((p0 + p1) / 2.0, p1 - p0);
        if len <= 1e-9 {
            continue;
        }
        out.push(if horizontal {
            Obstacle::Box {
                centre: [c, fixed],
                size: [len, t],
                angle_rad: 0.0,
            }
        } else {
            Obstacle::Box {
                centre: [fixed, c],
                size: [t, len],
                angle_rad: 0.0,
            }
        });
    }
}

/// Generates a world: a corridor along x through the middle, `rooms_per_side` rooms above and
/// below it, each with a door onto the corridor (and sometimes onto its neighbour), clutter
/// boxes and discs inside the rooms, a start in the first room and a target in the last.
/// The same seed gives the same world.
///
/// ```
/// use sim_laser::{GenParams, generate_world};
/// let a = generate_world(3, &GenParams::default()).unwrap();
/// let b = generate_world(3, &GenParams::default()).unwrap();
/// assert_eq!(a, b);
/// let w = a.to_world().unwrap();
/// let s = a.start.unwrap();
/// assert!(!w.disc_collides(scan_types::WorldPoint::new(s[0], s[1]), 0.3));
/// ```
pub fn generate_world(seed: u64, p: &GenParams) -> Result<WorldDescription, SimError> {
    p.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (hw, hh) = (p.width_m / 2.0, p.height_m / 2.0);
    let mut obs = Vec::new();
    outer_walls(&mut obs, p);
    if p.rooms_per_side == 0 {
        return Ok(clutter_only(&mut rng, seed, p, obs));
    }
    let xs = room_splits(&mut rng, p);
    let (rooms, doors) = rooms_and_doors(&mut rng, p, &xs, &mut obs);
    let centre_of = |r: &Room| [(r.0 + r.1) / 2.0, (r.2 + r.3) / 2.0];
    let start_room = rooms[0];
    let target_room = rooms[rooms.len() - 1];
    let start_xy = centre_of(&start_room);
    let target = centre_of(&target_room);
    let start_theta = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let keep_clear: Vec<[f64; 2]> = doors.iter().copied().chain([start_xy, target]).collect();
    place_clutter(&mut rng, p, &rooms, &keep_clear, &mut obs);
    Ok(WorldDescription {
        name: format!("generated-{seed}"),
        bounds: Some(([-hw, -hh], [hw, hh])),
        boundary: false,
        obstacles: obs,
        start: Some([start_xy[0], start_xy[1], start_theta]),
        target: Some(target),
    })
}

/// Distance of a clutter-only world's start and target from the left and right walls, metres.
pub const CLUTTER_END_M: f64 = 1.5;

/// A clutter-only world: the outer walls, a start `CLUTTER_END_M` from the left wall and a
/// target as far from the right wall (each at a random height in the middle half), and the
/// clutter anywhere in the open, clear of the walls, start and target and of each other.
fn clutter_only(
    rng: &mut ChaCha8Rng,
    seed: u64,
    p: &GenParams,
    mut obs: Vec<Obstacle>,
) -> WorldDescription {
    let (hw, hh, t) = (p.width_m / 2.0, p.height_m / 2.0, p.wall_thickness_m);
    let y_span = (hh / 2.0).max(1e-3);
    let start_xy = [-hw + CLUTTER_END_M, rng.random_range(-y_span..y_span)];
    let target = [hw - CLUTTER_END_M, rng.random_range(-y_span..y_span)];
    let start_theta = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let open: Room = (-hw + t, hw - t, -hh + t, hh - t);
    place_clutter(rng, p, &[open], &[start_xy, target], &mut obs);
    WorldDescription {
        name: format!("clutter-{seed}"),
        bounds: Some(([-hw, -hh], [hw, hh])),
        boundary: false,
        obstacles: obs,
        start: Some([start_xy[0], start_xy[1], start_theta]),
        target: Some(target),
    }
}

/// A room's interior: x0, x1, y0, y1.
type Room = (f64, f64, f64, f64);

/// The four outer walls, inside the bounds.
fn outer_walls(obs: &mut Vec<Obstacle>, p: &GenParams) {
    let (hw, hh, t) = (p.width_m / 2.0, p.height_m / 2.0, p.wall_thickness_m);
    wall_with_gaps(obs, true, -hh + t / 2.0, -hw, hw, &[], t);
    wall_with_gaps(obs, true, hh - t / 2.0, -hw, hw, &[], t);
    wall_with_gaps(obs, false, -hw + t / 2.0, -hh + t, hh - t, &[], t);
    wall_with_gaps(obs, false, hw - t / 2.0, -hh + t, hh - t, &[], t);
}

/// The x of the room dividers: jittered splits of the width, the same above and below (with
/// the outer walls' x at both ends).
fn room_splits(rng: &mut ChaCha8Rng, p: &GenParams) -> Vec<f64> {
    let (hw, t) = (p.width_m / 2.0, p.wall_thickness_m);
    let n = p.rooms_per_side;
    let room_w = p.width_m / n as f64;
    let jitter = (room_w - p.door_width_m - 4.0 * t - 0.4).max(0.0) * 0.25;
    let mut xs = vec![-hw];
    for k in 1..n {
        xs.push(-hw + k as f64 * room_w + rng.random_range(-jitter..=jitter));
    }
    xs.push(hw);
    xs
}

/// The rooms on both sides of the corridor, their walls with a door each and the side doors
/// between rooms; returns the rooms' interiors and the doors as points to keep clear.
fn rooms_and_doors(
    rng: &mut ChaCha8Rng,
    p: &GenParams,
    xs: &[f64],
    obs: &mut Vec<Obstacle>,
) -> (Vec<Room>, Vec<[f64; 2]>) {
    let (hw, hh, t) = (p.width_m / 2.0, p.height_m / 2.0, p.wall_thickness_m);
    let c2 = p.corridor_width_m / 2.0;
    let n = p.rooms_per_side;
    let mut rooms = Vec::new();
    let mut doors: Vec<[f64; 2]> = Vec::new();
    let dw = p.door_width_m;
    for side in [1.0f64, -1.0] {
        let wall_y = side * (c2 + t / 2.0);
        let (ry0, ry1) = if side > 0.0 {
            (c2 + t, hh - t)
        } else {
            (-hh + t, -c2 - t)
        };
        let mut gaps = Vec::new();
        for k in 0..n {
            let (x0, x1) = (xs[k] + t, xs[k + 1] - t);
            let lo = x0 + t + 0.1;
            let hi = x1 - t - 0.1 - dw;
            let g0 = if hi > lo {
                rng.random_range(lo..hi)
            } else {
                (x0 + x1 - dw) / 2.0
            };
            gaps.push((g0, g0 + dw));
            doors.push([g0 + dw / 2.0, wall_y]);
            rooms.push((x0, x1, ry0, ry1));
        }
        wall_with_gaps(obs, true, wall_y, -hw + t, hw - t, &gaps, t);
        for &x in xs.iter().take(n).skip(1) {
            let mut g = Vec::new();
            if rng.random::<f64>() < p.side_door_prob {
                let lo = ry0 + 0.1;
                let hi = ry1 - 0.1 - dw;
                if hi > lo {
                    let g0 = rng.random_range(lo..hi);
                    g.push((g0, g0 + dw));
                    doors.push([x, g0 + dw / 2.0]);
                }
            }
            wall_with_gaps(obs, false, x, ry0, ry1, &g, t);
        }
    }
    (rooms, doors)
}

/// Clutter boxes then circles, rejection-sampled inside rooms, clear of the walls, of
/// `keep_clear` and of each other.
fn place_clutter(
    rng: &mut ChaCha8Rng,
    p: &GenParams,
    rooms: &[Room],
    keep_clear: &[[f64; 2]],
    obs: &mut Vec<Obstacle>,
) {
    let dw = p.door_width_m;
    // Placed items as (centre, circumradius).
    let mut placed: Vec<([f64; 2], f64)> = Vec::new();
    let gap = p.clearance_m;
    let kinds = std::iter::repeat_n(true, p.boxes).chain(std::iter::repeat_n(false, p.circles));
    for is_box in kinds {
        for _attempt in 0..200 {
            let r = &rooms[rng.random_range(0..rooms.len())];
            let size = rng.random_range(p.clutter_size_m[0]..=p.clutter_size_m[1]);
            let (o, rad) = if is_box {
                let w = size;
                let h = rng.random_range(p.clutter_size_m[0]..=p.clutter_size_m[1]);
                let ang = rng.random_range(0.0..std::f64::consts::PI);
                (
                    Obstacle::Box {
                        centre: [0.0, 0.0],
                        size: [w, h],
                        angle_rad: ang,
                    },
                    0.5 * w.hypot(h),
                )
            } else {
                (
                    Obstacle::Circle {
                        centre: [0.0, 0.0],
                        radius: size / 2.0,
                    },
                    size / 2.0,
                )
            };
            // A full gap from the room's walls keeps every room traversable.
            let (x0, x1, y0, y1) = (
                r.0 + rad + gap,
                r.1 - rad - gap,
                r.2 + rad + gap,
                r.3 - rad - gap,
            );
            if x1 <= x0 || y1 <= y0 {
                continue;
            }
            let c = [rng.random_range(x0..x1), rng.random_range(y0..y1)];
            let d = |q: [f64; 2]| (q[0] - c[0]).hypot(q[1] - c[1]);
            if keep_clear.iter().any(|&q| d(q) < rad + gap + dw / 2.0) {
                continue;
            }
            if placed.iter().any(|&(q, qr)| d(q) < rad + qr + gap) {
                continue;
            }
            placed.push((c, rad));
            obs.push(match o {
                Obstacle::Box {
                    size, angle_rad, ..
                } => Obstacle::Box {
                    centre: c,
                    size,
                    angle_rad,
                },
                _ => Obstacle::Circle {
                    centre: c,
                    radius: rad,
                },
            });
            break;
        }
    }
}
