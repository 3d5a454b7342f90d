//! Exact ray casting through the grid: single rays and lanes of rays from one eye.

use scan_types::WorldPoint;

use super::{IDLE, LIST, Prim, World};

impl World {
    /// Distance from `origin` along the direction `angle_rad` to the first obstacle, if one lies
    /// within `max_range_m`. Exact against the geometry (bitmap cells are solid squares).
    pub fn raycast(&self, origin: WorldPoint, angle_rad: f64, max_range_m: f64) -> Option<f64> {
        let (s, c) = angle_rad.sin_cos();
        self.raycast_dir([origin.x_m(), origin.y_m()], [c, s], max_range_m)
    }

    /// Ray cast with a unit direction vector.
    pub(crate) fn raycast_dir(&self, o: [f64; 2], d: [f64; 2], max_range_m: f64) -> Option<f64> {
        let mut ray = Ray::default();
        if let Some(r) = self.ray_start(o, d, max_range_m, &mut ray) {
            return r;
        }
        loop {
            if let Some(r) = self.ray_step::<true>(&mut ray) {
                return r;
            }
        }
    }

    /// The ray origin `o` seen from each quadrant of travel, for rays cast from it.
    fn eye(&self, o: [f64; 2]) -> Eye {
        let gx = (o[0] - self.x0) * self.irx;
        let gy = (o[1] - self.y0) * self.iry;
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        let mut eye = Eye {
            inside: gx >= 0.0 && gy >= 0.0 && gx < nx && gy < ny,
            o,
            ..Eye::default()
        };
        if eye.inside {
            for q in 0..4 {
                let ox = if q & 1 == 1 { gx } else { nx - gx };
                let oy = if q & 2 == 2 { gy } else { ny - gy };
                eye.g[q] = [ox, oy];
                eye.c[q] = [
                    (ox as i32).clamp(0, self.nx as i32 - 1),
                    (oy as i32).clamp(0, self.ny as i32 - 1),
                ];
            }
        }
        eye
    }

    /// [`World::ray_start`] for a ray from `eye`'s origin, quicker when the origin is in the grid.
    #[inline(always)]
    fn ray_start_eye<'a>(
        &'a self,
        eye: &Eye,
        d: [f64; 2],
        max: f64,
        ray: &mut Ray<'a>,
    ) -> Option<Option<f64>> {
        if !(eye.inside && d[0].is_finite() && d[1].is_finite() && max >= 0.0 && max.is_finite()) {
            return self.ray_start(eye.o, d, max, ray);
        }
        let q = usize::from(d[0] >= 0.0) | (usize::from(d[1] >= 0.0) << 1);
        let dx = d[0].abs() * self.irx;
        let dy = d[1].abs() * self.iry;
        *ray = Ray {
            ox: eye.g[q][0],
            oy: eye.g[q][1],
            dx,
            dy,
            ix: 1.0 / dx,
            iy: 1.0 / dy,
            t1: max,
            max,
            t: 0.0,
            best: f64::INFINITY,
            cx: eye.c[q][0],
            cy: eye.c[q][1],
            q,
            plane: &self.planes[q],
            o: eye.o,
            d,
        };
        None
    }

    /// Sets up a ray for [`World::ray_step`], or answers at once.
    fn ray_start<'a>(
        &'a self,
        o: [f64; 2],
        d: [f64; 2],
        max: f64,
        ray: &mut Ray<'a>,
    ) -> Option<Option<f64>> {
        if !(o[0].is_finite()
            && o[1].is_finite()
            && d[0].is_finite()
            && d[1].is_finite()
            && max.is_finite()
            && max >= 0.0)
        {
            return Some(None);
        }
        // A zero component counts as positive: the ray then stays in the cell at or after it.
        let (sx, sy) = (d[0] >= 0.0, d[1] >= 0.0);
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        // Mirrored cell coordinates in which the ray moves toward +x and +y.
        let gx = (o[0] - self.x0) * self.irx;
        let gy = (o[1] - self.y0) * self.iry;
        let ox = if sx { gx } else { nx - gx };
        let oy = if sy { gy } else { ny - gy };
        let dx = d[0].abs() * self.irx;
        let dy = d[1].abs() * self.iry;
        let (ix, iy) = (1.0 / dx, 1.0 / dy);
        let (mut t0, mut t1) = (0.0f64, max);
        for (oo, dd, ii, hi) in [(ox, dx, ix, nx), (oy, dy, iy, ny)] {
            if dd == 0.0 {
                if oo < 0.0 || oo >= hi {
                    return Some(None);
                }
            } else {
                t0 = t0.max(-oo * ii);
                t1 = t1.min((hi - oo) * ii);
            }
        }
        if t0 > t1 {
            return Some(None);
        }
        *ray = Ray {
            ox,
            oy,
            dx,
            dy,
            ix,
            iy,
            t1,
            max,
            t: t0,
            best: f64::INFINITY,
            cx: ((ox + t0 * dx) as i32).clamp(0, self.nx as i32 - 1),
            cy: ((oy + t0 * dy) as i32).clamp(0, self.ny as i32 - 1),
            q: usize::from(sx) | (usize::from(sy) << 1),
            plane: &self.planes[usize::from(sx) | (usize::from(sy) << 1)],
            o,
            d,
        };
        None
    }

    /// Advances a ray by one empty square (or one cell holding shapes); the answer once it is known.
    /// Without `SHAPES` the world must have no cells holding shapes (a pure bitmap).
    #[inline(always)]
    fn ray_step<const SHAPES: bool>(&self, r: &mut Ray) -> Option<Option<f64>> {
        let (cx, cy) = (r.cx, r.cy);
        let k = r.plane[cy as usize * self.nx + cx as usize];
        if k == 0 {
            return Some((r.t <= r.max).then_some(r.t));
        }
        let kk = if SHAPES && k == LIST { 1 } else { i32::from(k) };
        let ex = ((cx + kk) as f64 - r.ox) * r.ix;
        let ey = ((cy + kk) as f64 - r.oy) * r.iy;
        let e = if ex < ey { ex } else { ey };
        if SHAPES && k == LIST && self.test_list(r, e) {
            return Some((r.best <= r.max).then_some(r.best));
        }
        if e > r.t1 {
            return Some((r.best <= r.max).then_some(r.best));
        }
        // The cell the ray enters: across the exit side(s), and on the other axis the cell holding
        // the exit point, clamped to the square's span so rounding can never skip a cell.
        let (ncx, ncy) = if ex < ey {
            (cx + kk, ((r.oy + e * r.dy) as i32).max(cy).min(cy + kk - 1))
        } else if ey < ex {
            (((r.ox + e * r.dx) as i32).max(cx).min(cx + kk - 1), cy + kk)
        } else {
            (cx + kk, cy + kk)
        };
        if ncx >= self.nx as i32 || ncy >= self.ny as i32 {
            return Some((r.best <= r.max).then_some(r.best));
        }
        r.cx = ncx;
        r.cy = ncy;
        r.t = e;
        None
    }

    /// Tests the shapes of the ray's current cell; true when the nearest hit lies before `exit`.
    #[inline(never)]
    fn test_list(&self, r: &mut Ray, exit: f64) -> bool {
        let ax = if r.q & 1 == 1 {
            r.cx
        } else {
            self.nx as i32 - 1 - r.cx
        };
        let ay = if r.q & 2 == 2 {
            r.cy
        } else {
            self.ny as i32 - 1 - r.cy
        };
        for &p in self.list(self.cells[ay as usize * self.nx + ax as usize]) {
            if let Some(th) = ray_prim(r.o, r.d, &self.prims[p as usize]) {
                r.best = r.best.min(th);
            }
        }
        r.best <= exit
    }

    /// Casts rays from `o` along `dir(0)`, `dir(1)`, ... (called in order), several at once;
    /// `out[i]` is ray i's hit distance, or infinity for none within `max`.
    /// Each ray gives the same answer as [`World::raycast_dir`]; stepping six rays in turn lets
    /// the processor overlap their memory reads and arithmetic.
    pub(crate) fn raycast_many<'a>(
        &'a self,
        o: [f64; 2],
        mut dir: impl FnMut(usize) -> [f64; 2],
        max: f64,
        out: &mut [f64],
    ) {
        const LANES: usize = 6;
        let n = out.len();
        let eye = self.eye(o);
        let mut next = 0;
        let mut rays = [Ray::default(); LANES];
        let mut ids = [IDLE; LANES];
        // Starts the next ray that needs stepping in `ray`, answering the others at once.
        let mut refill = |next: &mut usize, out: &mut [f64], ray: &mut Ray<'a>| -> usize {
            while *next < n {
                let i = *next;
                *next += 1;
                match self.ray_start_eye(&eye, dir(i), max, ray) {
                    None => return i,
                    Some(r) => out[i] = r.unwrap_or(f64::INFINITY),
                }
            }
            IDLE
        };
        for (id, ray) in ids.iter_mut().zip(rays.iter_mut()) {
            *id = refill(&mut next, out, ray);
        }
        // A world without shapes has no cells holding shapes.
        if self.prims.is_empty() {
            let step = |ray: &mut Ray<'a>| self.ray_step::<false>(ray);
            run_lanes(&mut ids, &mut rays, step, &mut next, out, &mut refill);
        } else {
            let step = |ray: &mut Ray<'a>| self.ray_step::<true>(ray);
            run_lanes(&mut ids, &mut rays, step, &mut next, out, &mut refill);
        }
    }
}

/// Steps the rays of `lanes` in turn until every ray is answered, writing answers to `out` and
/// starting the next rays with `refill`.
#[inline(always)]
fn run_lanes<'a, const L: usize>(
    ids: &mut [usize; L],
    rays: &mut [Ray<'a>; L],
    step: impl Fn(&mut Ray<'a>) -> Option<Option<f64>>,
    next: &mut usize,
    out: &mut [f64],
    refill: &mut impl FnMut(&mut usize, &mut [f64], &mut Ray<'a>) -> usize,
) {
    loop {
        let mut active = false;
        for (id, ray) in ids.iter_mut().zip(rays.iter_mut()) {
            if *id == IDLE {
                continue;
            }
            active = true;
            if let Some(res) = step(ray) {
                out[*id] = res.unwrap_or(f64::INFINITY);
                *id = refill(next, out, ray);
            }
        }
        if !active {
            break;
        }
    }
}

/// A ray in flight, in the mirrored cell coordinates of its quadrant `q` (bit 0: moving toward
/// +x, bit 1: toward +y): an axis along which the ray moves toward -x (or -y) is flipped,
/// `m = n - g` for cell coordinate `g` on a grid of `n` cells, so the ray always moves toward +m.
/// The point at distance `t` (metres) is `(ox + t dx, oy + t dy)`.
#[derive(Debug, Clone, Copy, Default)]
struct Ray<'a> {
    /// Origin, mirrored cell coordinates.
    ox: f64,
    oy: f64,
    /// Direction per metre, cells (>= 0).
    dx: f64,
    dy: f64,
    /// 1 / dx and 1 / dy (may be infinite).
    ix: f64,
    iy: f64,
    /// Where the ray stops: the maximum range, or where it leaves the grid.
    t1: f64,
    /// The maximum range.
    max: f64,
    /// Where the ray entered the current cell.
    t: f64,
    /// The nearest shape hit so far.
    best: f64,
    /// The current cell, mirrored.
    cx: i32,
    cy: i32,
    /// The quadrant.
    q: usize,
    /// Its plane.
    plane: &'a [u8],
    /// Origin and unit direction, world coordinates (for exact shape tests).
    o: [f64; 2],
    d: [f64; 2],
}

/// A ray origin seen from each quadrant of travel (`q` as in [`Ray`]).
#[derive(Debug, Clone, Copy, Default)]
struct Eye {
    /// True when the origin lies inside the grid.
    inside: bool,
    /// The origin, world coordinates.
    o: [f64; 2],
    /// The origin in each quadrant's mirrored cell coordinates.
    g: [[f64; 2]; 4],
    /// Its cell there.
    c: [[i32; 2]; 4],
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn ray_prim(o: [f64; 2], d: [f64; 2], p: &Prim) -> Option<f64> {
    match *p {
        Prim::Segment { a, b, .. } => {
            let e = [b[0] - a[0], b[1] - a[1]];
            let den = cross(d, e);
            if den == 0.0 {
                return None;
            }
            let ao = [a[0] - o[0], a[1] - o[1]];
            let t = cross(ao, e) / den;
            let s = cross(ao, d) / den;
            (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
        }
        Prim::Circle { c, r } => {
            let oc = [o[0] - c[0], o[1] - c[1]];
            let b = d[0] * oc[0] + d[1] * oc[1];
            let cc = oc[0] * oc[0] + oc[1] * oc[1] - r * r;
            let disc = b * b - cc;
            if disc < 0.0 {
                return None;
            }
            let sq = disc.sqrt();
            let t_near = -b - sq;
            if t_near >= 0.0 {
                Some(t_near)
            } else if cc <= 0.0 {
                Some(0.0) // inside the disc
            } else {
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::{Bitmap, Obstacle, WorldParts};
    use approx::assert_abs_diff_eq;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    fn vec_world(obstacles: Vec<Obstacle>) -> World {
        World::from_parts(WorldParts {
            name: "t".into(),
            obstacles,
            ..Default::default()
        })
        .unwrap()
    }

    #[test]
    fn wall_straight_and_oblique() {
        // A wall x = 2 from y = -5 to 5; robot at the origin.
        let w = vec_world(vec![Obstacle::Segment {
            a: [2.0, -5.0],
            b: [2.0, 5.0],
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(w.raycast(o, 0.0, 10.0).unwrap(), 2.0, epsilon = 1e-12);
        // At 60 deg the distance is 2 / cos 60 = 4.
        assert_abs_diff_eq!(w.raycast(o, PI / 3.0, 10.0).unwrap(), 4.0, epsilon = 1e-9);
        assert_eq!(w.raycast(o, PI / 3.0, 3.9), None);
        assert_eq!(w.raycast(o, PI, 100.0), None);
        assert_eq!(w.raycast(o, FRAC_PI_2, 100.0), None);
    }

    #[test]
    fn corner_of_a_box() {
        // Box [1,3] x [1,3]; from the origin at 45 deg the ray meets the corner (1,1).
        let w = vec_world(vec![Obstacle::Box {
            centre: [2.0, 2.0],
            size: [2.0, 2.0],
            angle_rad: 0.0,
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(
            w.raycast(o, FRAC_PI_4, 10.0).unwrap(),
            2f64.sqrt(),
            epsilon = 1e-9
        );
        // From (0, 2) heading +x: the face x = 1.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(0.0, 2.0), 0.0, 10.0).unwrap(),
            1.0,
            epsilon = 1e-12
        );
        assert!(w.is_occupied(WorldPoint::new(2.0, 2.0)));
        assert!(!w.is_occupied(WorldPoint::new(0.5, 2.0)));
        assert_abs_diff_eq!(
            w.clearance(WorldPoint::new(0.0, 0.0), 5.0),
            2f64.sqrt(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn circle_tangent_and_centre() {
        // Circle at (5, 0) radius 1: straight ahead 4 m; tangent ray at asin(1/5).
        let w = vec_world(vec![Obstacle::Circle {
            centre: [5.0, 0.0],
            radius: 1.0,
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(w.raycast(o, 0.0, 10.0).unwrap(), 4.0, epsilon = 1e-12);
        let a = (1.0f64 / 5.0).asin();
        // Just inside the tangent: hits near the tangent distance sqrt(24).
        let r = w.raycast(o, a - 1e-7, 10.0).unwrap();
        assert_abs_diff_eq!(r, 24f64.sqrt(), epsilon = 2e-3);
        assert_eq!(w.raycast(o, a + 1e-6, 10.0), None);
        assert!(w.disc_collides(WorldPoint::new(3.75, 0.0), 0.3));
        assert!(!w.disc_collides(WorldPoint::new(3.65, 0.0), 0.3));
    }

    #[test]
    fn bitmap_cells_are_solid_squares() {
        // 4 x 4 bitmap of 0.5 m cells at origin (0,0); cell (col 2, row 1) occupied.
        let mut occ = vec![false; 16];
        occ[4 + 2] = true;
        let w = World::from_parts(WorldParts {
            name: "b".into(),
            bitmap: Some(Bitmap {
                width: 4,
                height: 4,
                cell_w_m: 0.5,
                cell_h_m: 0.5,
                origin: [0.0, 0.0],
                occupied: occ,
            }),
            ..Default::default()
        })
        .unwrap();
        // Cell covers x in [1, 1.5], y in [0.5, 1]. From (0, 0.75) heading +x: 1.0.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(0.0, 0.75), 0.0, 10.0).unwrap(),
            1.0,
            epsilon = 1e-12
        );
        // From (1.25, 3) heading -y: top face y = 1 at 2.0.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(1.25, 3.0), -FRAC_PI_2, 10.0)
                .unwrap(),
            2.0,
            epsilon = 1e-12
        );
        // From (0.25, 0) at 45 deg: y = x - 0.25 enters the left face at (1, 0.75).
        let r = w.raycast(WorldPoint::new(0.25, 0.0), FRAC_PI_4, 10.0);
        assert_abs_diff_eq!(r.unwrap(), 0.75 * 2f64.sqrt(), epsilon = 1e-9);
        // Behind the bitmap (outside the grid) heading away: nothing.
        assert_eq!(w.raycast(WorldPoint::new(-1.0, 0.75), PI, 10.0), None);
        // From outside the grid heading in.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(-3.0, 0.75), 0.0, 10.0).unwrap(),
            4.0,
            epsilon = 1e-12
        );
    }
}
