//! The rectilinear heading measurement ([`localiser::wall_axes`]) on real buildings: the Intel
//! lab and the ACES building, against their logs' reference poses (corrected by a SLAM system
//! nobody here wrote). Each scan's walls, turned by its reference heading, give the
//! building's axes; they must agree with each other as closely as `[localiser]
//! rectilinear_sigma_deg` says.
#![allow(clippy::print_stdout)] // tests report their figures

use localiser::{AxesParams, wall_axes, wrap_quarter_rad};
use scan_log::{LogOptions, LogSource};

#[path = "common/shared_data.rs"]
mod shared_data;
use shared_data::shared;

/// Every scan's axes in the reference frame (degrees, modulo 90), and the scans read.
fn axes_in_reference_frame(rel: &str) -> Option<(Vec<f64>, usize)> {
    let path = shared(rel)?;
    let mut log = LogSource::open(&path, &LogOptions::default()).expect("the log opens");
    let params = AxesParams::default();
    let (mut out, mut scans) = (Vec::new(), 0);
    while let Ok(rec) = log.next_record() {
        scans += 1;
        let pose = rec.pose.expect("a corrected log has poses");
        if let Some(a) = wall_axes(&rec.geometry, &rec.scan, &params) {
            out.push(wrap_quarter_rad(a.angle_rad + pose.theta_rad).to_degrees());
        }
    }
    Some((out, scans))
}

/// The absolute deviations (degrees) of `dirs` from their mean modulo 90 deg.
fn deviations(dirs: &[f64]) -> Vec<f64> {
    let (s, c) = dirs.iter().fold((0.0, 0.0), |(s, c), d| {
        let a = 4.0 * d.to_radians();
        (s + a.sin(), c + a.cos())
    });
    let mean = 0.25 * f64::atan2(s, c);
    let mut devs: Vec<f64> = dirs
        .iter()
        .map(|d| wrap_quarter_rad(d.to_radians() - mean).to_degrees().abs())
        .collect();
    devs.sort_by(f64::total_cmp);
    devs
}

fn check(rel: &str, min_within_2_deg: f64) {
    let Some((dirs, scans)) = axes_in_reference_frame(rel) else {
        return;
    };
    let devs = deviations(&dirs);
    let median = devs[devs.len() / 2];
    let within = devs.iter().filter(|&&d| d <= 2.0).count() as f64 / devs.len() as f64;
    println!(
        "{rel}: {} of {scans} scans with axes, median deviation {median:.2} deg, {:.1} % within 2 deg",
        devs.len(),
        100.0 * within
    );
    // Most scans of a building show walls.
    assert!(devs.len() * 2 > scans, "{} of {scans}", devs.len());
    let sigma = navigator::Params::goalseek()
        .localiser
        .rectilinear_sigma_deg;
    assert!(
        median <= sigma,
        "median {median:.2} deg against {sigma} deg"
    );
    assert!(within >= min_within_2_deg, "{within:.3} within 2 deg");
}

#[test]
fn intel_walls_agree_on_the_buildings_axes() {
    // Some of the Intel lab's walls run off the axes: about 5 % of its scans lie more than 4 deg off.
    check("carmen/intel-corrected.log.gz", 0.85);
}

#[test]
fn aces_walls_agree_on_the_buildings_axes() {
    check("carmen/aces-corrected.log.gz", 0.95);
}
