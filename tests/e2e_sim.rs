//! End to end in the simulator: the paper's scenario through `robot-app sim`'s own code path
//! (simulate, then write every output), and runs that end early still leave their summary.
//!
//! Numbers come from the issue (target (4, 4), success radius 0.3 m, the paper's start) and
//! from the geometry of the written files, never from the code under test.
#![allow(clippy::print_stderr, clippy::print_stdout)] // tests report to the terminal

use std::ffi::OsStr;
use std::path::Path;

use clap::Parser;
use navigator::{Method, Params};
use robot_app::cmd::sim::{SimArgs, SimSpec, simulate, write_outputs};

/// `robot-app sim`'s arguments on their own.
#[derive(Parser)]
struct SimCli {
    #[command(flatten)]
    args: SimArgs,
}

/// The paper's target and start (issue 7).
const TARGET: (f64, f64) = (4.0, 4.0);
const START: (f64, f64, f64) = (-3.92, -4.26, 45.0);

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name))
        .unwrap_or_else(|e| panic!("{} missing: {e}", dir.join(name).display()))
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(dir, "summary.json")).expect("summary.json is JSON")
}

/// Rows of a TUM file as (time, x, y, qz, qw), checking the 8-column format.
fn tum_rows(text: &str) -> Vec<[f64; 5]> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .map(|t| t.parse().expect("TUM values are numbers"))
                .collect();
            assert_eq!(v.len(), 8, "TUM line {l:?}: timestamp tx ty tz qx qy qz qw");
            // Planar: tz, qx, qy are zero and the quaternion has unit norm.
            assert_eq!((v[3], v[4], v[5]), (0.0, 0.0, 0.0), "{l}");
            assert!((v[6].hypot(v[7]) - 1.0).abs() < 1e-6, "{l}");
            [v[0], v[1], v[2], v[6], v[7]]
        })
        .collect()
}

/// Every field the issue lists for summary.json, with its JSON type.
fn check_summary_fields(s: &serde_json::Value) {
    assert!(s["reached"].is_boolean(), "reached: {s}");
    assert!(s["reason"].is_string(), "reason: {s}");
    let reason = s["reason"].as_str().unwrap();
    assert!(
        [
            "reached",
            "unreachable",
            "leg_limit",
            "collision",
            "sensor_failure"
        ]
        .contains(&reason),
        "{reason}"
    );
    for key in ["legs", "scans", "collisions"] {
        assert!(s[key].is_u64(), "{key}: {s}");
    }
    for key in [
        "commanded_path_length_m",
        "final_position_error_m",
        "final_heading_error_deg",
        "ate_rmse_m",
        "goal_distance_m",
        "cpu_time_s",
    ] {
        let v = s[key].as_f64().unwrap_or_else(|| panic!("{key}: {s}"));
        assert!(v.is_finite() && v >= 0.0, "{key} = {v}");
    }
}

#[test]
fn paper_scenario_reaches_the_target_and_writes_every_output() {
    let spec = SimSpec::paper(0, Params::preset(Method::Goalseek));
    let run = simulate(&spec, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    write_outputs(dir.path(), &run, "e2e").expect("outputs written");
    let d = dir.path();

    let s = summary(d);
    check_summary_fields(&s);
    println!("paper scenario: {s}");
    assert_eq!(s["reason"], "reached", "{s}");
    assert_eq!(s["reached"], true);
    assert_eq!(s["collisions"], 0);
    let legs = s["legs"].as_u64().unwrap() as usize;
    assert!(legs >= 1);

    // The true final position, from truth.tum, is within 0.3 m of (4, 4).
    let truth = tum_rows(&read(d, "truth.tum"));
    let est = tum_rows(&read(d, "estimate.tum"));
    // One pose at the start and one at the end of every leg.
    assert_eq!(truth.len(), legs + 1);
    assert_eq!(est.len(), legs + 1);
    let last = truth.last().unwrap();
    let to_target = (last[1] - TARGET.0).hypot(last[2] - TARGET.1);
    assert!(to_target <= 0.3, "true end {to_target:.3} m from (4, 4)");
    assert!((s["goal_distance_m"].as_f64().unwrap() - to_target).abs() < 1e-5);

    // Row 0 is the start, heading 45 deg: qz = sin(22.5 deg), qw = cos(22.5 deg).
    for rows in [&truth, &est] {
        let r = rows[0];
        assert_eq!((r[0], r[1], r[2]), (0.0, START.0, START.1));
        assert!((r[3] - 22.5f64.to_radians().sin()).abs() < 1e-9);
        assert!((r[4] - 22.5f64.to_radians().cos()).abs() < 1e-9);
    }
    // Time stamps are the simulated clock of each leg's last scan: the first scan at 0 s, then
    // increasing; the drives alone take their length over the simulator's 0.3 m/s.
    assert!(truth.iter().zip(&est).all(|(t, e)| t[0] == e[0]));
    assert!(est.windows(2).all(|w| w[1][0] > w[0][0]), "{est:?}");
    let drive_s = s["commanded_path_length_m"].as_f64().unwrap() / 0.3;
    assert!(
        est[legs][0] >= 0.95 * drive_s,
        "{} s < {drive_s} s",
        est[legs][0]
    );

    // Localisation errors recomputed from the two TUM files (6-decimal rounding).
    let errs: Vec<f64> = est
        .iter()
        .zip(&truth)
        .map(|(e, t)| (e[1] - t[1]).hypot(e[2] - t[2]))
        .collect();
    let ate = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    assert!((s["ate_rmse_m"].as_f64().unwrap() - ate).abs() < 1e-5);
    assert!((s["final_position_error_m"].as_f64().unwrap() - errs[legs]).abs() < 1e-5);

    // The robot drove at least the straight distance it covered (2 % drive noise aside).
    let covered = (last[1] - START.0).hypot(last[2] - START.1);
    assert!(s["commanded_path_length_m"].as_f64().unwrap() >= 0.95 * covered);

    check_trajectory_csv(d, &truth, legs);
    check_maps_and_figure(d);
}

/// trajectory.csv: a header and one row per leg end, truth columns equal to truth.tum; the
/// first leg with a landmark fixes a landmark and a point B.
fn check_trajectory_csv(d: &Path, truth: &[[f64; 5]], legs: usize) {
    let csv = read(d, "trajectory.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 11);
    assert_eq!(header[0], "leg");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), legs + 1);
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), 11, "row {i}");
        assert_eq!(r[0].parse::<usize>().unwrap(), i);
        let tx: f64 = r[4].parse().unwrap();
        let ty: f64 = r[5].parse().unwrap();
        assert!((tx - truth[i][1]).abs() < 2e-6 && (ty - truth[i][2]).abs() < 2e-6);
    }
    assert!(
        rows.iter()
            .skip(1)
            .any(|r| !r[7].is_empty() && !r[9].is_empty())
    );
}

/// Maps: map_server PGM + YAML, and PNG; the figure as PNG and SVG; no temporary file left.
fn check_maps_and_figure(d: &Path) {
    let pgm = std::fs::read(d.join("map.pgm")).unwrap();
    assert!(pgm.starts_with(b"P5"));
    let yaml = read(d, "map.yaml");
    assert!(yaml.contains("image: map.pgm"), "{yaml}");
    assert!(yaml.contains("resolution:"), "{yaml}");
    let pgm_img = image::open(d.join("map.pgm")).expect("map.pgm decodes");
    let png = image::open(d.join("map.png")).expect("map.png decodes");
    assert_eq!(
        (png.width(), png.height()),
        (pgm_img.width(), pgm_img.height())
    );
    let fig = image::open(d.join("run.png")).expect("run.png decodes");
    assert!(fig.width() >= 400 && fig.height() >= 400);
    let svg = read(d, "run.svg");
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"));
    // Atomic writes leave no temporary files behind.
    for e in std::fs::read_dir(d).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp-"), "{name} left behind");
    }
}

/// `robot-app sim` with a leg limit of 1: the command fails, and its folder holds a summary
/// that says why, the configuration used, and the one leg's trajectory.
#[test]
fn a_run_stopped_by_the_leg_limit_leaves_its_summary() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("one-leg.toml");
    std::fs::write(&cfg, "[navigator]\nmax_legs = 1\n").unwrap();
    let out = dir.path().join("out");
    // Parsed as `robot-app sim` parses its command line.
    let argv: [&OsStr; 7] = [
        "sim".as_ref(),
        "--seed".as_ref(),
        "3".as_ref(),
        "--config".as_ref(),
        cfg.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    let args = SimCli::try_parse_from(argv).expect("arguments parse").args;
    let err = robot_app::cmd::sim::run(args).expect_err("one leg cannot reach the target");
    assert!(err.to_string().contains("leg_limit"), "{err}");
    let s = summary(&out);
    check_summary_fields(&s);
    assert_eq!(s["reached"], false);
    assert_eq!(s["reason"], "leg_limit");
    assert_eq!(s["legs"], 1);
    assert!(!s["note"].as_str().unwrap().is_empty());
    // The paper's start is 11.44 m from the target; the robot truly moved at most the
    // commanded distance plus the 2 % drive-scale noise (5 % allowed).
    let driven = s["commanded_path_length_m"].as_f64().unwrap();
    assert!(s["goal_distance_m"].as_f64().unwrap() >= 11.44 - 1.05 * driven - 0.01);
    assert_eq!(tum_rows(&read(&out, "truth.tum")).len(), 2);
    assert!(read(&out, "config.toml").contains("max_legs = 1"));
    for f in ["map.pgm", "map.yaml", "map.png", "run.png", "run.svg"] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

/// A target outside the paper world's walls can never be reached: the run ends without a
/// collision, as unreachable or at the leg limit, and says so in its summary.
#[test]
fn a_target_beyond_the_walls_ends_as_a_failure_with_its_reason() {
    let mut config = Params::preset(Method::Goalseek);
    config.navigator.max_legs = 12;
    let mut spec = SimSpec::paper(1, config);
    // The paper world spans -5..5 m with a wall around it.
    spec.goal = scan_types::WorldPoint::new(7.0, 0.0);
    let run = simulate(&spec, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    write_outputs(dir.path(), &run, "e2e unreachable").unwrap();
    let s = summary(dir.path());
    check_summary_fields(&s);
    println!("target beyond the walls: {s}");
    assert_eq!(s["reached"], false);
    assert_eq!(s["collisions"], 0);
    assert!(
        ["unreachable", "leg_limit"].contains(&s["reason"].as_str().unwrap()),
        "{s}"
    );
    assert!(s["goal_distance_m"].as_f64().unwrap() >= 2.0 - 0.3);
}

/// A run through the 0.74 m door of `sim/door_row.toml` (narrower than 2 (r + 0.1 m) = 0.8 m,
/// so only graded clearance passes it) lists that door in summary.json's `narrow_passages`.
#[test]
fn a_run_through_a_narrow_door_lists_it_in_its_summary() {
    let world = concat!(env!("CARGO_MANIFEST_DIR"), "/sim/door_row.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let argv: [&OsStr; 10] = [
        "sim".as_ref(),
        "--world".as_ref(),
        world.as_ref(),
        "--goal".as_ref(),
        "2.4,1.8".as_ref(),
        "--start=2.4,-1.5,90".as_ref(),
        "--seed".as_ref(),
        "0".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    let args = SimCli::try_parse_from(argv).expect("arguments parse").args;
    robot_app::cmd::sim::run(args).expect("the 0.74 m door is passable");
    let s = summary(&out);
    assert_eq!(s["reason"], "reached", "{s}");
    let passages = s["narrow_passages"].as_array().expect("an array");
    // The door spans x in 2.4 +- 0.37 in the wall at y = 0 (0.1 m thick).
    let door: Vec<_> = passages
        .iter()
        .filter(|p| (p["at"]["x_m"].as_f64().unwrap() - 2.4).abs() < 0.37)
        .filter(|p| p["at"]["y_m"].as_f64().unwrap().abs() < 0.2)
        .collect();
    assert!(!door.is_empty(), "{s}");
    for p in door {
        assert!(p["leg"].as_u64().unwrap() >= 1, "{p}");
        assert!((p["width_m"].as_f64().unwrap() - 0.74).abs() < 0.04, "{p}");
        assert!(p["clearance_m"].as_f64().unwrap() > 0.3, "{p}");
    }
}
