//! `run.png` and `run.svg`: the paper's Fig. 13 for one run — the scans in the world frame,
//! the estimated and the true path, each leg's landmark and point B, the start and the target.

use std::path::Path;
use std::sync::Once;

use anyhow::{Context, anyhow};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::outputs::write_atomic;
use scan_log::RunLog;

/// DejaVu Sans, shipped with the repository (bitmap text needs a registered font).
const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";
static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The embedded file is a valid font; a failure would only lose the text.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// Pixel size of the figures.
pub const SIZE: (u32, u32) = (900, 900);

/// Renders the run as PNG bytes.
pub fn render_png(log: &RunLog, title: &str) -> anyhow::Result<Vec<u8>> {
    register_font();
    let (w, h) = SIZE;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        draw(&root, log, title).map_err(|e| anyhow!("drawing run.png: {e}"))?;
        root.present()
            .map_err(|e| anyhow!("drawing run.png: {e:?}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).context("plot buffer has the wrong size")?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .context("encoding run.png")?;
    Ok(png)
}

/// Renders the run as SVG text.
pub fn render_svg(log: &RunLog, title: &str) -> anyhow::Result<String> {
    register_font();
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, SIZE).into_drawing_area();
        draw(&root, log, title).map_err(|e| anyhow!("drawing run.svg: {e}"))?;
        root.present()
            .map_err(|e| anyhow!("drawing run.svg: {e:?}"))?;
    }
    Ok(s)
}

/// Writes `run.png` and `run.svg` in `dir`.
pub fn write_plots(dir: &Path, log: &RunLog, title: &str) -> anyhow::Result<()> {
    write_atomic(&dir.join("run.png"), &render_png(log, title)?)?;
    write_atomic(&dir.join("run.svg"), render_svg(log, title)?.as_bytes())
}

/// The square world window holding everything drawn, with a margin.
fn bounds(log: &RunLog) -> (f64, f64, f64, f64) {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for r in &log.legs {
        pts.push((r.estimate.x_m, r.estimate.y_m));
        if let Some(t) = r.truth {
            pts.push((t.x_m, t.y_m));
        }
        pts.extend(r.scan_points.iter().map(|p| (p.x_m(), p.y_m())));
    }
    if let Some(g) = log.goal {
        pts.push((g.x_m(), g.y_m()));
    }
    let pts: Vec<(f64, f64)> = pts
        .into_iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if pts.is_empty() {
        return (-1.0, 1.0, -1.0, 1.0);
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let half = ((x1 - x0).max(y1 - y0) / 2.0 + 0.3).max(0.5);
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    (cx - half, cx + half, cy - half, cy + half)
}

/// Scan hits thinned to one per 2 cm cell (the figure cannot show more).
fn thinned_scan_points(log: &RunLog) -> Vec<(f64, f64)> {
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    for r in &log.legs {
        for p in &r.scan_points {
            if !(p.x_m().is_finite() && p.y_m().is_finite()) {
                continue;
            }
            let key = (
                (p.x_m() / 0.02).round() as i64,
                (p.y_m() / 0.02).round() as i64,
            );
            if seen.insert(key) {
                out.push((p.x_m(), p.y_m()));
            }
        }
    }
    out
}

/// A path as separate two-point segments: a wide polyline's mitre join at a reversal (the
/// robot backing out the way it came) would draw a spike far off the path.
fn segments(points: &[(f64, f64)], style: ShapeStyle) -> Vec<PathElement<(f64, f64)>> {
    points
        .windows(2)
        .map(|w| PathElement::new(vec![w[0], w[1]], style))
        .collect()
}

/// The chart of the figure: world coordinates on both axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    log: &RunLog,
    title: &str,
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{e:?}");
    root.fill(&WHITE).map_err(err)?;
    let (x0, x1, y0, y1) = bounds(log);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(54)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((FAMILY, 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    draw_scans_and_paths(&mut chart, log).map_err(err)?;
    draw_legs(&mut chart, log).map_err(err)?;
    draw_ends(&mut chart, log).map_err(err)?;
    chart
        .configure_series_labels()
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The scan hits, the true path (where known) and the estimated path with its leg ends.
fn draw_scans_and_paths<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    log: &RunLog,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let scan_colour = RGBColor(150, 150, 150);
    chart
        .draw_series(
            thinned_scan_points(log)
                .into_iter()
                .map(|p| Circle::new(p, 1, scan_colour.filled())),
        )?
        .label("scans (world frame, estimated pose)")
        .legend(move |(x, y)| Circle::new((x + 8, y), 3, scan_colour.filled()));

    let truth: Vec<(f64, f64)> = log
        .legs
        .iter()
        .filter_map(|r| r.truth.map(|t| (t.x_m, t.y_m)))
        .collect();
    if !truth.is_empty() {
        chart
            .draw_series(segments(&truth, RED.stroke_width(2)))?
            .label("true path")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(2)));
    }
    let est: Vec<(f64, f64)> = log
        .legs
        .iter()
        .map(|r| (r.estimate.x_m, r.estimate.y_m))
        .collect();
    chart
        .draw_series(segments(&est, BLUE.stroke_width(2)))?
        .label("estimated path")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLUE.stroke_width(2)));
    chart.draw_series(est.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))?;
    Ok(())
}

/// Each leg's landmark and point B.
fn draw_legs<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    log: &RunLog,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let green = RGBColor(0, 150, 0);
    chart
        .draw_series(
            log.legs
                .iter()
                .filter_map(|r| r.landmark)
                .map(|p| TriangleMarker::new((p.x_m(), p.y_m()), 6, green.filled())),
        )?
        .label("landmark of each leg")
        .legend(move |(x, y)| TriangleMarker::new((x + 8, y), 6, green.filled()));
    chart
        .draw_series(
            log.legs
                .iter()
                .filter_map(|r| r.point_b)
                .map(|p| Cross::new((p.x_m(), p.y_m()), 5, MAGENTA.stroke_width(2))),
        )?
        .label("point B of each leg")
        .legend(|(x, y)| Cross::new((x + 8, y), 5, MAGENTA.stroke_width(2)));
    Ok(())
}

/// The start (its true pose where known) and the target.
fn draw_ends<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    log: &RunLog,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if let Some(s) = log.legs.first() {
        let p = s.truth.unwrap_or(s.estimate);
        chart
            .draw_series(std::iter::once(Circle::new(
                (p.x_m, p.y_m),
                7,
                BLACK.filled(),
            )))?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 8, y), 5, BLACK.filled()));
    }
    if let Some(g) = log.goal {
        let orange = RGBColor(230, 120, 0);
        chart
            .draw_series(std::iter::once(Cross::new(
                (g.x_m(), g.y_m()),
                9,
                orange.stroke_width(3),
            )))?
            .label("target")
            .legend(move |(x, y)| Cross::new((x + 8, y), 6, orange.stroke_width(3)));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan_log::{LegRecord, RunLog};
    use scan_types::{Pose2, WorldPoint};

    #[test]
    fn bounds_are_square_and_hold_everything() {
        let leg = LegRecord {
            leg: 0,
            time_s: 0.0,
            estimate: Pose2::new(0.0, 0.0, 0.5),
            truth: Some(Pose2::new(3.55, 3.0, 0.5)),
            landmark: None,
            point_b: None,
            scan_points: vec![WorldPoint::new(-1.0, 4.0), WorldPoint::new(2.0, -0.5)],
        };
        let log = RunLog {
            goal: Some(WorldPoint::new(3.5, 3.5)),
            legs: vec![leg],
        };
        let (x0, x1, y0, y1) = bounds(&log);
        assert!((x1 - x0 - (y1 - y0)).abs() < 1e-12);
        assert!(x0 <= -1.0 && x1 >= 3.55 && y0 <= -0.5 && y1 >= 4.0);
    }
}
