//! Heading after a rotation in place: the commanded angle (paper) or the angle measured by
//! aligning the scans taken before and after the rotation.

use scan_types::{RayStatus, Scan, ScanGeometry, normalize_angle_rad};

/// Where the heading after a rotation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum HeadingRule {
    /// The paper: heading plus the commanded rotation alpha.
    Commanded,
    /// goalseek: heading plus the rotation measured from the scans (commanded if the
    /// measurement is not confident).
    #[default]
    ScanMeasured,
}

/// The new heading under `rule`: `theta + measured` when the rule is `ScanMeasured` and a
/// measurement exists, else `theta + commanded`.
pub fn heading_after_rotation(
    rule: HeadingRule,
    theta_rad: f64,
    commanded_rad: f64,
    measured_rad: Option<f64>,
) -> f64 {
    let turn = match (rule, measured_rad) {
        (HeadingRule::ScanMeasured, Some(m)) => m,
        _ => commanded_rad,
    };
    normalize_angle_rad(theta_rad + turn)
}

/// Tuning of the scan alignment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationParams {
    /// Search the rotation within this of the commanded angle, radians.
    pub search_rad: f64,
    /// A range difference counts at most this much (robust to occlusions), metres.
    pub clip_m: f64,
    /// Fewest ray pairs (not both max range) that must overlap.
    pub min_pairs: usize,
    /// Largest RMS (clipped) range difference of the best alignment, metres.
    pub max_rms_m: f64,
    /// The cost three rays away from the best shift must exceed the best by this factor.
    pub min_contrast: f64,
}

impl Default for RotationParams {
    /// +-5 deg search, 0.3 m clip, 30 pairs, 0.12 m RMS, contrast 1.2.
    fn default() -> Self {
        Self {
            search_rad: 5f64.to_radians(),
            clip_m: 0.3,
            min_pairs: 30,
            max_rms_m: 0.12,
            min_contrast: 1.2,
        }
    }
}

/// A measured rotation with its quality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationEstimate {
    /// The rotation, counter-clockwise positive, radians.
    pub angle_rad: f64,
    /// RMS (clipped) range difference at the best alignment, metres.
    pub rms_m: f64,
    /// Ray pairs used at the best alignment.
    pub pairs: usize,
}

/// Measures the rotation in place between two scans: the shift (in rays, below one ray by
/// interpolation) that best aligns `after` with `before`, searched within `search_rad` of
/// `commanded_rad`. `None` when no confident match exists.
///
/// A rotation by alpha moves what ray `i + alpha / increment` saw before onto ray `i`.
pub fn measure_rotation(
    geometry: &ScanGeometry,
    before: &Scan,
    after: &Scan,
    commanded_rad: f64,
    search_rad: f64,
) -> Option<f64> {
    let params = RotationParams {
        search_rad,
        ..RotationParams::default()
    };
    measure_rotation_with(geometry, before, after, commanded_rad, &params).map(|e| e.angle_rad)
}

/// One ray's reading for alignment: a range, and whether it is max range.
#[derive(Clone, Copy)]
struct Reading {
    range: f64,
    open: bool,
}

fn readings(geometry: &ScanGeometry, scan: &Scan) -> Vec<Option<Reading>> {
    let n = geometry
        .ray_count
        .min(scan.ranges_m.len())
        .min(scan.status.len());
    (0..n)
        .map(|i| match scan.status[i] {
            RayStatus::Hit if scan.ranges_m[i].is_finite() => Some(Reading {
                range: scan.ranges_m[i],
                open: false,
            }),
            RayStatus::MaxRange => Some(Reading {
                range: geometry.max_range_m,
                open: true,
            }),
            _ => None,
        })
        .collect()
}

/// Neighbouring hits closer in range than this lie on one surface (else: an edge), metres.
const SMOOTH_M: f64 = 0.1;

/// What the scan before the rotation shows between rays `j` and `j + 1`, prepared once for
/// every shift [`cost`] tries.
#[derive(Clone, Copy)]
enum Pair {
    /// Neither ray usable.
    Empty,
    /// One usable ray, or two max-range rays (the same reading).
    Single(Reading),
    /// Two hits on one surface (ranges within `SMOOTH_M`).
    Smooth(Surface),
    /// A discontinuity between the two rays.
    Edge(Reading, Reading),
}

/// Two neighbouring hits `r0`, `r1` taken as the straight segment joining them.
#[derive(Clone, Copy)]
struct Surface {
    r0: f64,
    r1: f64,
    /// The segment in the frame of the lower ray: `(r1 cos inc - r0, r1 sin inc)`, and `r0`
    /// times its second coordinate.
    dx: f64,
    dy: f64,
    num: f64,
}

impl Surface {
    /// Range along the ray at `frac` of the way to the upper ray (`sp`, `cp`: sine and cosine
    /// of `frac * inc`) to the segment; the interpolated range where the segment is degenerate.
    #[inline]
    fn range_at(&self, frac: f64, sp: f64, cp: f64) -> f64 {
        let den = cp * self.dy - sp * self.dx;
        let t = self.num / den;
        if den.abs() > 1e-12 && t.is_finite() && t > 0.0 {
            t
        } else {
            self.r0 + frac * (self.r1 - self.r0)
        }
    }
}

/// The [`Pair`]s of `before`: entry `j` pairs ray `j` with ray `min(j + 1, n - 1)`.
fn pairs(before: &[Option<Reading>], inc: f64) -> Vec<Pair> {
    let n = before.len();
    let (si, ci) = inc.sin_cos();
    (0..n)
        .map(|j0| {
            let j1 = (j0 + 1).min(n - 1);
            match (before[j0], before[j1]) {
                (Some(b0), Some(b1)) => {
                    if b0.open == b1.open && (b0.range - b1.range).abs() < SMOOTH_M {
                        if b0.open {
                            // A smooth max-range stretch reads as its lower ray.
                            return Pair::Single(b0);
                        }
                        let (r0, r1) = (b0.range, b1.range);
                        let (dx, dy) = (r1 * ci - r0, r1 * si);
                        Pair::Smooth(Surface {
                            r0,
                            r1,
                            dx,
                            dy,
                            num: r0 * dy,
                        })
                    } else {
                        Pair::Edge(b0, b1)
                    }
                }
                (Some(b), None) | (None, Some(b)) => Pair::Single(b),
                _ => Pair::Empty,
            }
        })
        .collect()
}

/// `pairs` for whole-ray shifts: each smooth pair replaced by its value at the lower ray
/// (what [`cost`] computes for it at a zero fraction), which needs no division per shift.
fn at_rays(pairs: &[Pair], inc: f64) -> Vec<Pair> {
    let (sp, cp) = (0.0 * inc).sin_cos();
    pairs
        .iter()
        .map(|p| match *p {
            Pair::Smooth(surface) => Pair::Single(Reading {
                range: surface.range_at(0.0, sp, cp),
                open: false,
            }),
            other => other,
        })
        .collect()
}

/// Mean clipped squared difference and pair count at fractional shift `s` (rays), with
/// `before` prepared by [`pairs`] (or by [`at_rays`] when `s` is a whole number).
///
/// Only every `every`-th ray of `after` counts (1: all). Gives up with an infinite cost as
/// soon as the sum of squares exceeds `limit`.
fn cost(
    before: &[Pair],
    after: &[Option<Reading>],
    s: f64,
    clip: f64,
    inc: f64,
    every: usize,
    limit: f64,
) -> (f64, usize) {
    let n = before.len();
    // Between two hits the surface is taken as the straight segment joining them (exact on
    // flat walls, unlike interpolating the range): in the frame of the lower ray, the hits
    // are (r0, 0) and (r1 cos inc, r1 sin inc) and the query ray points at phi = f inc.
    let frac = s - s.floor();
    let (sp, cp) = (frac * inc).sin_cos();
    let mut sum = 0.0;
    let mut count = 0usize;
    for (i, a) in after.iter().enumerate().step_by(every.max(1)) {
        let Some(a) = a else { continue };
        let j = i as f64 + s;
        if j < 0.0 || j > (n - 1) as f64 {
            continue;
        }
        // j >= 0: truncation is the floor (and needs no libm call).
        let d = match before[j as usize] {
            // Smooth stretch of hits: interpolate below one ray.
            Pair::Smooth(surface) => (a.range - surface.range_at(frac, sp, cp)).abs(),
            Pair::Edge(b0, b1) => {
                // A discontinuity between the two rays: the ray may match either side.
                let side = |b: Reading| {
                    if a.open && b.open {
                        0.0
                    } else {
                        (a.range - b.range).abs()
                    }
                };
                side(b0).min(side(b1))
            }
            Pair::Single(b) => {
                if a.open && b.open {
                    continue;
                }
                (a.range - b.range).abs()
            }
            Pair::Empty => continue,
        };
        let d = d.min(clip);
        sum += d * d;
        count += 1;
        if sum > limit {
            return (f64::INFINITY, count);
        }
    }
    if count == 0 {
        (f64::INFINITY, 0)
    } else {
        (sum / count as f64, count)
    }
}

/// [`measure_rotation`] with every tuning knob, returning the fit quality too.
pub fn measure_rotation_with(
    geometry: &ScanGeometry,
    before: &Scan,
    after: &Scan,
    commanded_rad: f64,
    params: &RotationParams,
) -> Option<RotationEstimate> {
    let b = readings(geometry, before);
    let a = readings(geometry, after);
    if b.len() < 2 || a.is_empty() || !commanded_rad.is_finite() {
        return None;
    }
    let inc = geometry.increment_rad;
    let centre = commanded_rad / inc;
    let half = (params.search_rad.abs() / inc.abs()).ceil() as i64;
    let clip = params.clip_m;
    let b = pairs(&b, inc);
    let whole = at_rays(&b, inc);
    // The cost at shift `s` on all rays; infinite once it surely exceeds `above` (a mean).
    let eval_below = |s: f64, above: f64| {
        let table = if s == s.floor() { &whole } else { &b };
        let limit = above * a.len() as f64 * (1.0 + 1e-12);
        let (c, k) = cost(table, &a, s, clip, inc, 1, limit);
        if k >= params.min_pairs {
            (c, k)
        } else {
            (f64::INFINITY, k)
        }
    };
    let eval = |s: f64| eval_below(s, f64::INFINITY);
    // Integer search: every shift ranked on every second ray, the best three on all rays.
    let ranked = rank_integer_shifts(&whole, &a, centre.round() as i64, half, clip, inc, params);
    let mut best = (f64::INFINITY, 0i64);
    for &(_, shift) in ranked.iter().take(3).filter(|r| r.0.is_finite()) {
        let (c, _) = eval_below(shift as f64, best.0);
        if c < best.0 {
            best = (c, shift);
        }
    }
    if !best.0.is_finite() {
        return None;
    }
    let s0 = best.1 as f64;
    // Contrast: the alignment must be distinctly better than three rays off.
    // (Only whether a side scores below the bar matters: each is given up above it.)
    let bar = params.min_contrast * best.0 + 1e-9;
    let side = eval_below(s0 - 3.0, bar).0.min(eval_below(s0 + 3.0, bar).0);
    if side.is_finite() && side < bar {
        return None;
    }
    let (s, fine) = refine_sub_ray(s0, best.0, &eval_below);
    let (c, pairs) = eval(s);
    let (c, pairs) = if c.is_finite() {
        (c, pairs)
    } else {
        (fine.0, eval(fine.1).1)
    };
    let rms = c.sqrt();
    if rms > params.max_rms_m {
        return None;
    }
    Some(RotationEstimate {
        angle_rad: normalize_angle_rad(s * inc),
        rms_m: rms,
        pairs,
    })
}

/// Every integer shift within `half` rays of `base`, ranked best first on every second ray.
///
/// Shifts are scored outward from `base`, and a shift is given up once its sum shows it worse
/// than three scored ones whatever its remaining rays add (its mean is at least the sum over
/// the most rays it could count; 1e-12 covers rounding).
fn rank_integer_shifts(
    whole: &[Pair],
    a: &[Option<Reading>],
    base: i64,
    half: i64,
    clip: f64,
    inc: f64,
    params: &RotationParams,
) -> Vec<(f64, i64)> {
    let most = a.len().div_ceil(2) as f64;
    let mut ranked: Vec<(f64, i64)> = (-half..=half).map(|k| (f64::INFINITY, base + k)).collect();
    let mut top3 = [f64::INFINITY; 3];
    for t in 0..ranked.len() {
        // 0, -1, +1, -2, +2, ... from the middle entry.
        let off = (t as i64 + 1) / 2 * if t % 2 == 1 { -1 } else { 1 };
        let idx = (half + off) as usize;
        let limit = top3[2] * most * (1.0 + 1e-12);
        let (c, pairs) = cost(whole, a, ranked[idx].1 as f64, clip, inc, 2, limit);
        let c = if 2 * pairs >= params.min_pairs {
            c
        } else {
            f64::INFINITY
        };
        ranked[idx].0 = c;
        if c < top3[2] {
            top3[2] = c;
            top3.sort_by(f64::total_cmp);
        }
    }
    ranked.sort_by(|x, y| x.0.total_cmp(&y.0));
    ranked
}

/// Sub-ray refinement around the integer best `s0` (cost `best_cost`): a 0.25-ray grid within
/// +-1 ray, a 0.05-ray grid within +-0.25 ray of its best, then a parabola through the best
/// fine point and its grid neighbours. Returns the refined shift and the best fine point
/// (cost, shift). `eval_below(s, above)` is the cost at `s`, infinite once above `above`.
fn refine_sub_ray(
    s0: f64,
    best_cost: f64,
    eval_below: &impl Fn(f64, f64) -> (f64, usize),
) -> (f64, (f64, f64)) {
    let eval = |s: f64| eval_below(s, f64::INFINITY);
    let coarse_step = 0.25;
    let mut coarse = (f64::INFINITY, s0);
    for k in -4..=4 {
        let s = s0 + k as f64 * coarse_step;
        // The middle point is the integer best, already scored.
        let c = if k == 0 {
            best_cost
        } else {
            eval_below(s, coarse.0).0
        };
        if c < coarse.0 {
            coarse = (c, s);
        }
    }
    let step = 0.05;
    // The middle point is the coarse best, already scored.
    let grid: Vec<f64> = (-5..=5)
        .map(|k| match k {
            0 => coarse.0,
            _ => eval(coarse.1 + k as f64 * step).0,
        })
        .collect();
    let mut best_k = 5;
    for (k, &c) in grid.iter().enumerate() {
        if c < grid[best_k] {
            best_k = k;
        }
    }
    let fine = (grid[best_k], coarse.1 + (best_k as f64 - 5.0) * step);
    let cm = match best_k.checked_sub(1) {
        Some(k) => grid[k],
        None => eval(fine.1 - step).0,
    };
    let cp = match grid.get(best_k + 1) {
        Some(&c) => c,
        None => eval(fine.1 + step).0,
    };
    let mut s = fine.1;
    let den = cm - 2.0 * fine.0 + cp;
    if cm.is_finite() && cp.is_finite() && den > 1e-15 {
        s += (0.5 * step * (cm - cp) / den).clamp(-0.5 * step, 0.5 * step);
    }
    (s, fine)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cost before `Pair`s (the reference the prepared one must equal).
    fn cost_reference(
        before: &[Option<Reading>],
        after: &[Option<Reading>],
        s: f64,
        clip: f64,
        inc: f64,
    ) -> (f64, usize) {
        let n = before.len();
        // Between two hits the surface is taken as the straight segment joining them (exact on
        // flat walls, unlike interpolating the range): in the frame of the lower ray, the hits
        // are (r0, 0) and (r1 cos inc, r1 sin inc) and the query ray points at phi = f inc.
        let frac = s - s.floor();
        let (sp, cp) = (frac * inc).sin_cos();
        let (si, ci) = inc.sin_cos();
        let between = |r0: f64, r1: f64| {
            let (dx, dy) = (r1 * ci - r0, r1 * si);
            let den = cp * dy - sp * dx;
            let t = (r0 * dy) / den;
            if den.abs() > 1e-12 && t.is_finite() && t > 0.0 {
                t
            } else {
                r0 + frac * (r1 - r0)
            }
        };
        let mut sum = 0.0;
        let mut count = 0usize;
        for (i, a) in after.iter().enumerate() {
            let Some(a) = a else { continue };
            let j = i as f64 + s;
            if j < 0.0 || j > (n - 1) as f64 {
                continue;
            }
            // j >= 0: truncation is the floor (and needs no libm call).
            let j0 = j as usize;
            let j1 = (j0 + 1).min(n - 1);
            let d = match (before[j0], before[j1]) {
                (Some(b0), Some(b1)) => {
                    if b0.open == b1.open && (b0.range - b1.range).abs() < SMOOTH_M {
                        // Smooth stretch: interpolate below one ray.
                        if a.open && b0.open {
                            continue;
                        }
                        let b = if b0.open {
                            b0.range
                        } else {
                            between(b0.range, b1.range)
                        };
                        (a.range - b).abs()
                    } else {
                        // A discontinuity between the two rays: the ray may match either side.
                        let side = |b: Reading| {
                            if a.open && b.open {
                                0.0
                            } else {
                                (a.range - b.range).abs()
                            }
                        };
                        side(b0).min(side(b1))
                    }
                }
                (Some(b), None) | (None, Some(b)) => {
                    if a.open && b.open {
                        continue;
                    }
                    (a.range - b.range).abs()
                }
                _ => continue,
            };
            let d = d.min(clip);
            sum += d * d;
            count += 1;
        }
        if count == 0 {
            (f64::INFINITY, 0)
        } else {
            (sum / count as f64, count)
        }
    }

    #[test]
    fn prepared_cost_equals_the_reference() {
        // Ranges with smooth stretches, edges, max-range runs and error rays.
        let g = ScanGeometry::paper();
        let n = g.ray_count;
        let mut noise = scan_types::testkit::Noise::new(99);
        let mut uniform = || noise.uniform();
        let mut scan = |shift: f64| {
            let ranges: Vec<f64> = (0..n)
                .map(|i| {
                    let x = i as f64 + shift;
                    match (x / 40.0) as usize % 4 {
                        0 => 1.0 + 0.002 * x,
                        1 => 2.5 + 0.01 * (x * 0.1).sin(),
                        2 => g.max_range_m,
                        _ => 0.6 + 0.05 * ((x as usize % 7) as f64),
                    }
                })
                .collect();
            let mut s = Scan::from_ranges(&g, &ranges, 0.0);
            for _ in 0..20 {
                let k = (uniform() * n as f64) as usize;
                s.status[k] = RayStatus::Error(1);
                s.ranges_m[k] = f64::NAN;
            }
            s
        };
        let (before, after) = (scan(0.0), scan(7.3));
        let (b, a) = (readings(&g, &before), readings(&g, &after));
        let inc = g.increment_rad;
        let prepared = pairs(&b, inc);
        for k in -400..=400 {
            let s = k as f64 * 0.05 + 0.3 * (k % 3) as f64;
            let want = cost_reference(&b, &a, s, 0.3, inc);
            let table = if s == s.floor() {
                at_rays(&prepared, inc)
            } else {
                prepared.clone()
            };
            let got = cost(&table, &a, s, 0.3, inc, 1, f64::INFINITY);
            assert_eq!(want.1, got.1, "{s}");
            assert_eq!(want.0.to_bits(), got.0.to_bits(), "{s}");
            // A sum limit above the whole sum changes nothing; one below it gives up.
            if got.0.is_finite() && got.0 > 0.0 {
                let total = got.0 * got.1 as f64;
                let kept = cost(&table, &a, s, 0.3, inc, 1, 2.0 * total);
                assert_eq!(kept.0.to_bits(), got.0.to_bits(), "{s}");
                let cut = cost(&table, &a, s, 0.3, inc, 1, 0.5 * total);
                assert_eq!(cut.0, f64::INFINITY, "{s}");
                assert!(cut.1 < got.1, "{s}");
            }
        }
    }
}
