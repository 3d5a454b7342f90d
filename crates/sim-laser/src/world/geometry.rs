//! Plane geometry of the world's shapes: distances, point in polygon, segment against box.

use super::Prim;

pub(super) fn point_prim_distance(q: [f64; 2], p: &Prim) -> f64 {
    match *p {
        Prim::Segment { a, b, .. } => point_segment_distance(q, a, b),
        Prim::Circle { c, r } => ((q[0] - c[0]).hypot(q[1] - c[1]) - r).max(0.0),
    }
}

pub(crate) fn point_segment_distance(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let t = if l2 > 0.0 {
        (((q[0] - a[0]) * e[0] + (q[1] - a[1]) * e[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q[0] - a[0] - t * e[0]).hypot(q[1] - a[1] - t * e[1])
}

pub(crate) fn point_in_polygon(q: [f64; 2], pts: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = pts.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (pts[i], pts[j]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if q[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

pub(super) fn segment_hits_box(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    // Liang-Barsky clip of the segment against the box.
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
        } else {
            let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
    }
    t0 <= t1
}
