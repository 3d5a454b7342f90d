//! Laser-only SLAM front end on the shared real logs, against the logs' reference poses.
#![allow(clippy::print_stdout)] // tests report their figures

use std::path::PathBuf;

use scan_log::{LogOptions, LogReader};
use slam::eval::{absolute_error, relative_error};
use slam::{FrontEnd, FrontEndParams, Placement};

fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/")).join(rel);
    p.exists().then_some(p)
}

/// Runs the front end over a log; (estimates, references) of the placed scans and the skips.
fn run(rel: &str) -> Option<(Vec<scan_types::Pose2>, Vec<scan_types::Pose2>, usize)> {
    let path = shared(rel)?;
    let params: FrontEndParams = match std::env::var("SLAM_PARAMS") {
        Ok(j) => serde_json::from_str(&j).unwrap(),
        Err(_) => FrontEndParams::default(),
    };
    let mut fe = FrontEnd::new(params).unwrap();
    let (mut est, mut reference, mut skipped) = (Vec::new(), Vec::new(), 0);
    let t0 = std::time::Instant::now();
    let mut unrefined = 0;
    for rec in LogReader::open(&path, &LogOptions::default()).unwrap() {
        let rec = rec.unwrap();
        match fe.add_scan(&rec.geometry, &rec.scan) {
            Placement::Placed {
                pose,
                quality,
                refined,
                keyframe,
            } => {
                if std::env::var_os("SLAM_DEBUG").is_some() {
                    let r = rec.pose.unwrap();
                    println!(
                        "{} q {quality:.3} ref {refined} kf {keyframe} est {:.3} {:.3} {:.1} ref {:.3} {:.3} {:.1}",
                        rec.line,
                        pose.x_m,
                        pose.y_m,
                        pose.theta_rad.to_degrees(),
                        r.x_m,
                        r.y_m,
                        r.theta_rad.to_degrees()
                    );
                }
                unrefined += usize::from(!refined);
                est.push(pose);
                reference.push(rec.pose.unwrap());
            }
            Placement::Skipped { reason } => {
                println!("{rel} line {}: skipped: {reason}", rec.line);
                skipped += 1;
            }
        }
    }
    println!(
        "{rel}: {:.3} s, {unrefined} placed unrefined",
        t0.elapsed().as_secs_f64()
    );
    Some((est, reference, skipped))
}

#[test]
fn carmen_logs_laser_only() {
    for rel in [
        "carmen/intel-corrected.log.gz",
        "carmen/aces-corrected.log.gz",
    ] {
        let Some((est, reference, skipped)) = run(rel) else {
            continue;
        };
        if std::env::var_os("SLAM_DEBUG2").is_some() {
            for k in 0..est.len() - 1 {
                let de = est[k].inverse().compose(&est[k + 1]);
                let dr = reference[k].inverse().compose(&reference[k + 1]);
                let e = dr.inverse().compose(&de);
                if e.x_m.hypot(e.y_m) > 0.1 || e.theta_rad.abs() > 0.03 {
                    println!(
                        "k {k}: err {:.3} m {:.2} deg; ref step {:.3} {:.3} {:.1}; est step {:.3} {:.3} {:.1}",
                        e.x_m.hypot(e.y_m),
                        e.theta_rad.to_degrees(),
                        dr.x_m,
                        dr.y_m,
                        dr.theta_rad.to_degrees(),
                        de.x_m,
                        de.y_m,
                        de.theta_rad.to_degrees()
                    );
                }
            }
        }
        let r1 = relative_error(&est, &reference, 1).unwrap();
        let r10 = relative_error(&est, &reference, 10).unwrap();
        let ate = absolute_error(&est, &reference).unwrap();
        println!(
            "{rel}: {} placed, {skipped} skipped; k->k+1 {:.4} +- {:.4} m, {:.3} +- {:.3} deg; k->k+10 {:.4} m {:.3} deg; ATE rmse {:.3} m",
            est.len(),
            r1.translation_m.mean,
            r1.translation_m.std,
            r1.rotation_deg.mean,
            r1.rotation_deg.std,
            r10.translation_m.mean,
            r10.rotation_deg.mean,
            ate.rmse
        );
    }
}
