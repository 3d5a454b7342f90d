//! Unit-level tests of the program's modules through their public items: outputs, figures,
//! configuration files, batch tables and seeds, the fixed simulated laser.

mod outputs {
    use robot_app::outputs::*;

    #[test]
    fn spl_by_hand() {
        // Success on a path twice the shortest: 0.5.
        assert_eq!(spl(true, 4.0, 8.0), 0.5);
        // Failure: 0 whatever the paths.
        assert_eq!(spl(false, 4.0, 4.0), 0.0);
        // A path "shorter" than the geodesic (the geodesic's grid overestimates a little): 1.
        assert_eq!(spl(true, 4.0, 3.9), 1.0);
        // Exact path: 1; start on the target: 1.
        assert_eq!(spl(true, 2.5, 2.5), 1.0);
        assert_eq!(spl(true, 0.0, 0.0), 1.0);
        // Bad numbers never give NaN.
        assert_eq!(spl(true, 4.0, f64::NAN), 1.0);
        assert_eq!(spl(true, f64::NAN, 3.0), 1.0);
    }
    use scan_log::{LegRecord, RunLog, trajectory_csv, tum, write_trajectory};
    use scan_types::{Pose2, WorldPoint};
    use std::f64::consts::FRAC_PI_2;

    fn row(leg: usize, est: (f64, f64), truth: (f64, f64)) -> LegRecord {
        LegRecord {
            leg,
            time_s: leg as f64,
            estimate: Pose2::new(est.0, est.1, 0.0),
            truth: Some(Pose2::new(truth.0, truth.1, 0.1)),
            landmark: Some(WorldPoint::new(1.0, 2.0)),
            point_b: None,
            scan_points: vec![],
        }
    }

    #[test]
    fn ate_by_hand() {
        // Rows with errors 0 and 5 (a 3-4-5 triangle): rmse = sqrt(25 / 2).
        let log = RunLog {
            goal: None,
            legs: vec![
                row(0, (0.0, 0.0), (0.0, 0.0)),
                row(1, (3.0, 4.0), (0.0, 0.0)),
            ],
        };
        assert!((log.ate_rmse_m().unwrap() - (12.5f64).sqrt()).abs() < 1e-12);
        let (p, h) = log.final_errors().unwrap();
        assert!((p - 5.0).abs() < 1e-12);
        assert!((h - 0.1f64.to_degrees()).abs() < 1e-9);
    }

    #[test]
    fn tum_quaternion_of_a_quarter_turn() {
        let t = tum([(3.0, Pose2::new(1.0, 2.0, FRAC_PI_2))]);
        let f: Vec<f64> = t.split_whitespace().map(|x| x.parse().unwrap()).collect();
        assert_eq!(f.len(), 8);
        assert_eq!(f[0], 3.0);
        assert_eq!((f[1], f[2], f[3]), (1.0, 2.0, 0.0));
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((f[6] - h).abs() < 1e-9 && (f[7] - h).abs() < 1e-9);
    }

    #[test]
    fn csv_leaves_missing_values_empty() {
        let mut r = row(0, (0.5, 0.25), (0.0, 0.0));
        r.truth = None;
        let s = trajectory_csv(&RunLog {
            goal: None,
            legs: vec![r],
        });
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines.len(), 2);
        // Every column names its unit, headings in radians as in the TUM files.
        assert_eq!(
            lines[0],
            "leg,est_x_m,est_y_m,est_heading_rad,true_x_m,true_y_m,true_heading_rad,landmark_x_m,landmark_y_m,b_x_m,b_y_m"
        );
        assert_eq!(
            lines[1],
            "0,0.500000,0.250000,0.000000,,,,1.000000,2.000000,,"
        );
    }

    #[test]
    fn files_are_written_whole_and_no_temp_is_left() {
        let dir = tempfile::tempdir().unwrap();
        let log = RunLog {
            goal: None,
            legs: vec![row(0, (0.0, 0.0), (0.0, 0.0))],
        };
        write_trajectory(dir.path(), &log).unwrap();
        let s = Summary {
            reached: false,
            reason: Reason::SensorFailure,
            legs: 0,
            scans: 1,
            collisions: 0,
            commanded_path_length_m: 0.0,
            true_path_length_m: None,
            geodesic_m: None,
            spl: None,
            final_position_error_m: None,
            final_heading_error_deg: None,
            ate_rmse_m: None,
            goal_distance_m: None,
            cpu_time_s: 0.0,
            method: "goalseek".into(),
            seed: None,
            start: PoseOut::of(&scan_types::Pose2::default()),
            goal: PointOut::of(scan_types::WorldPoint::new(1.0, 1.0)),
            final_estimate: PoseOut::of(&scan_types::Pose2::default()),
            final_truth: None,
            note: "laser timed out".into(),
            narrow_passages: Vec::new(),
            position_sigma_m: vec![0.0],
            heading_sigma_deg: vec![0.0],
        };
        write_summary(dir.path(), &s).unwrap();
        let text = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["reason"], "sensor_failure");
        assert_eq!(v["reached"], false);
        // The SPL fields are there, null off the simulator.
        for k in ["true_path_length_m", "geodesic_m", "spl"] {
            assert!(v.get(k).is_some_and(|x| x.is_null()), "{k}: {text}");
        }
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                "estimate.tum",
                "summary.json",
                "trajectory.csv",
                "truth.tum"
            ]
        );
    }

    #[test]
    fn atomic_write_into_missing_folder_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_atomic(&dir.path().join("nope/x.json"), b"{}").unwrap_err();
        assert!(format!("{e:#}").contains("nope/x.json"));
    }
}

mod plot {
    use robot_app::plot::*;
    use scan_log::{LegRecord, RunLog};
    use scan_types::{Pose2, WorldPoint};

    fn log() -> RunLog {
        let mut legs = Vec::new();
        for i in 0..4 {
            let f = i as f64;
            legs.push(LegRecord {
                leg: i,
                time_s: i as f64,
                estimate: Pose2::new(f, f, 0.5),
                truth: Some(Pose2::new(f + 0.05, f, 0.5)),
                landmark: Some(WorldPoint::new(f + 0.5, f - 0.5)),
                point_b: Some(WorldPoint::new(f + 0.4, f + 0.4)),
                scan_points: (0..100)
                    .map(|k| WorldPoint::new(-1.0 + k as f64 * 0.05, 4.0))
                    .collect(),
            });
        }
        RunLog {
            goal: Some(WorldPoint::new(3.5, 3.5)),
            legs,
        }
    }

    #[test]
    fn png_is_a_png_of_the_right_size_with_ink() {
        let png = render_png(&log(), "test run").unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), SIZE);
        // Some pixels are pure blue (the estimated path) and most are white.
        let blue = img.pixels().filter(|p| p.0 == [0, 0, 255]).count();
        let white = img.pixels().filter(|p| p.0 == [255, 255, 255]).count();
        assert!(blue > 50, "blue pixels: {blue}");
        assert!(white > (SIZE.0 * SIZE.1 / 2) as usize);
    }

    #[test]
    fn svg_has_legend_and_axes() {
        let svg = render_svg(&log(), "test run").unwrap();
        for label in [
            "estimated path",
            "true path",
            "point B",
            "target",
            "x (m)",
            "y (m)",
        ] {
            assert!(svg.contains(label), "missing {label}");
        }
    }

    #[test]
    fn a_path_that_turns_back_draws_no_spike() {
        // True positions of the last 31 legs of a run that went back and forth in a dead end
        // (generated world 9, pair 2): as one wide polyline, a join drew a line off the chart.
        const TRUE: [(f64, f64); 31] = [
            (-7.254, -1.541),
            (-7.484, -1.393),
            (-7.434, -1.8),
            (-7.409, -1.322),
            (-7.164, -1.48),
            (-7.22, -1.519),
            (-7.471, -1.703),
            (-7.267, -1.555),
            (-7.473, -1.391),
            (-7.442, -1.786),
            (-7.415, -1.325),
            (-7.171, -1.482),
            (-7.467, -1.654),
            (-7.47, -1.426),
            (-7.238, -1.55),
            (-7.479, -1.72),
            (-7.278, -1.568),
            (-7.474, -1.365),
            (-7.446, -1.797),
            (-7.43, -1.32),
            (-7.185, -1.482),
            (-7.475, -1.678),
            (-7.221, -1.513),
            (-7.467, -1.398),
            (-7.439, -1.807),
            (-7.399, -1.318),
            (-7.155, -1.491),
            (-7.466, -1.624),
            (-7.424, -1.315),
            (-7.18, -1.488),
            (-7.476, -1.644),
        ];
        // The estimate is drawn 1 m north of the truth: the same shape, whose ink gives the
        // size the red ink must have.
        let legs = TRUE
            .iter()
            .enumerate()
            .map(|(k, &(x, y))| LegRecord {
                leg: k,
                time_s: k as f64,
                estimate: Pose2::new(x, y + 1.0, 0.0),
                truth: Some(Pose2::new(x, y, 0.0)),
                landmark: None,
                point_b: None,
                scan_points: Vec::new(),
            })
            .collect();
        let log = RunLog { goal: None, legs };
        let png = render_png(&log, "reversals").unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        // Width and height of the ink of colour `c`, outside the legend's box (top left).
        let extent = |c: [u8; 3]| {
            let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
            for (x, y, p) in img.enumerate_pixels() {
                if p.0 == c && !(x < 360 && y < 180) {
                    (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                }
            }
            assert!(x0 <= x1, "no ink of {c:?}");
            (x1 - x0, y1 - y0)
        };
        let (blue, red) = (extent([0, 0, 255]), extent([255, 0, 0]));
        // The blue path carries 3-pixel dots at its points; the red one does not.
        assert!(
            red.0 <= blue.0 + 2 && red.1 <= blue.1 + 2 && red.0 + 12 >= blue.0,
            "red ink {red:?} against blue {blue:?} (pixels)"
        );
    }

    #[test]
    fn empty_log_still_draws() {
        assert!(render_png(&RunLog::default(), "empty").is_ok());
    }
}

mod config {
    use robot_app::config::*;

    #[test]
    fn file_overrides_a_subset() {
        let c = from_toml_str(
            "[tracking]\ngate_m = 0.1\n[navigator]\nmax_legs = 5\n",
            None,
        )
        .unwrap();
        assert_eq!(c.tracking.gate_m, 0.1);
        assert_eq!(c.navigator.max_legs, 5);
        assert_eq!(c.tracking.step_m, 0.05);
        assert_eq!(c.method, Method::Goalseek);
    }

    #[test]
    fn integer_accepted_for_float() {
        let c = from_toml_str("[robot]\nradius_m = 1\n", None).unwrap();
        assert_eq!(c.robot.radius_m, 1.0);
    }

    #[test]
    fn method_from_file_and_command_line() {
        let c = from_toml_str("method = \"paper\"\n", None).unwrap();
        assert_eq!(c.planner.rule, navigator::PlanRule::Greedy);
        let c = from_toml_str("method = \"paper\"\n", Some(Method::Goalseek)).unwrap();
        assert_eq!(c.planner.rule, navigator::PlanRule::MapPath);
        assert_eq!(c.method, Method::Goalseek);
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let e = from_toml_str("[tracking]\ngate_m = 0.1\ngait_m = 2\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("tracking.gait_m"), "{msg}");
        assert!(msg.contains("line 3"), "{msg}");
        let e = from_toml_str("[trackin]\ngate_m = 0.1\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("'trackin'") && msg.contains("line 1"), "{msg}");
    }

    #[test]
    fn wrong_type_and_bad_values_are_errors() {
        let e = from_toml_str("[tracking]\ngate_m = \"wide\"\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("tracking.gate_m") && msg.contains("line 2"),
            "{msg}"
        );
        let e =
            from_toml_str("[planner]\nwidth_window_deg = 2\nrule = \"astar\"\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("astar") && msg.contains("'planner.rule'") && msg.contains("line 3"),
            "{msg}"
        );
        // Two such values: the first in the file is named with its own message.
        let e = from_toml_str(
            "[localiser]\nheading_rule = \"sideways\"\n[planner]\nrule = \"astar\"\n",
            None,
        )
        .unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("'localiser.heading_rule'")
                && msg.contains("sideways")
                && !msg.contains("astar")
                && msg.contains("line 2"),
            "{msg}"
        );
        let e = from_toml_str("[robot]\nradius_m = -1.0\n", None).unwrap_err();
        assert!(format!("{e:#}").contains("robot.radius_m"), "{e:#}");
        let e = from_toml_str("# tuning\n[navigator]\nmin_leg_m = nan\n", None).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("line 3") && msg.contains("navigator.min_leg_m"),
            "{msg}"
        );
        assert!(from_toml_str("[robot\n", None).is_err());
    }

    #[test]
    fn round_trips_through_toml() {
        for m in [Method::Paper, Method::Goalseek] {
            let c = Params::preset(m);
            let back = from_toml_str(&to_toml_string(&c), None).unwrap();
            assert_eq!(back, c);
        }
    }
}

mod batch_table {
    use robot_app::cmd::batch::table::*;
    use robot_app::outputs::Reason;
    use sim_laser::WorldKind;

    fn row(group: &str, reached: bool, err: f64) -> BatchRow {
        BatchRow {
            group: group.into(),
            kind: WorldKind::Paper,
            world: "w".into(),
            pair: None,
            method: "goalseek".into(),
            seed: 0,
            start: robot_app::outputs::PoseOut::of(&scan_types::Pose2::default()),
            goal: robot_app::outputs::PointOut::of(scan_types::WorldPoint::new(0.0, 0.0)),
            reached,
            reason: if reached {
                Reason::Reached
            } else {
                Reason::LegLimit
            },
            legs: 3,
            scans: 10,
            collisions: 0,
            final_position_error_m: Some(err),
            final_heading_error_deg: Some(0.0),
            ate_rmse_m: Some(err),
            goal_distance_m: Some(0.1),
            commanded_path_length_m: 1.0,
            true_path_length_m: None,
            geodesic_m: None,
            spl: None,
            cpu_time_s: 0.1,
            final_position_sigma_m: None,
            note: String::new(),
        }
    }

    #[test]
    fn aggregates_per_group() {
        let rows = vec![
            row("a", true, 0.01),
            row("a", false, 0.03),
            row("b", true, 0.5),
            row("a", true, 0.02),
        ];
        let a = aggregate(&rows);
        assert_eq!(a.len(), 2);
        assert_eq!((a[0].group.as_str(), a[0].runs, a[0].reached), ("a", 3, 2));
        assert!((a[0].success_share - 2.0 / 3.0).abs() < 1e-12);
        assert!((a[0].median_final_error_m - 0.02).abs() < 1e-12);
        assert_eq!(a[0].reasons["leg_limit"], 1);
        let t = table(&a);
        assert!(t.lines().count() == 3);
        // The kind column is padded: "paper" then three spaces before the method.
        assert!(t.contains("paper    goalseek"), "{t}");
        // No row has a geodesic: no SPL.
        assert_eq!((a[0].spl, a[0].spl_runs), (None, 0));
        // Nor an uncertainty.
        assert_eq!(
            (a[0].median_final_sigma_m, a[0].within_final_sigma_share),
            (None, None)
        );
    }

    #[test]
    fn the_final_error_is_judged_against_the_runs_own_uncertainty() {
        let mut rows = vec![
            row("a", true, 0.05),
            row("a", true, 0.2),
            row("a", false, 0.4),
            row("a", true, 0.1),
        ];
        // 0.05 within 0.1, 0.2 beyond 0.1, 0.4 within 0.5; the last run reports none.
        rows[0].final_position_sigma_m = Some(0.1);
        rows[1].final_position_sigma_m = Some(0.1);
        rows[2].final_position_sigma_m = Some(0.5);
        let a = aggregate(&rows);
        assert!((a[0].within_final_sigma_share.unwrap() - 2.0 / 3.0).abs() < 1e-12);
        assert!((a[0].median_final_sigma_m.unwrap() - 0.1).abs() < 1e-12);
        // An error equal to the uncertainty lies within it.
        rows[1].final_position_sigma_m = Some(0.2);
        assert_eq!(aggregate(&rows)[0].within_final_sigma_share, Some(1.0));
    }

    #[test]
    fn spl_is_the_mean_over_runs_with_a_geodesic() {
        let mut rows = vec![
            row("a", true, 0.0),
            row("a", false, 0.0),
            row("a", true, 0.0),
        ];
        // Success on a path twice the geodesic (0.5), a failure (0), a run without a geodesic
        // (left out): (0.5 + 0) / 2.
        rows[0].spl = Some(0.5);
        rows[1].spl = Some(0.0);
        let a = aggregate(&rows);
        assert_eq!(a[0].spl_runs, 2);
        assert!((a[0].spl.unwrap() - 0.25).abs() < 1e-12);
        let t = table(&a);
        assert!(t.lines().next().unwrap().contains("SPL"), "{t}");
        assert!(t.contains(" 0.250 "), "{t}");
    }
}

mod batch {
    use robot_app::cmd::batch::*;

    #[test]
    fn seeds_parse() {
        assert_eq!(parse_seeds("0..50").unwrap(), 0..50);
        assert_eq!(parse_seeds("7").unwrap(), 7..8);
        assert!(parse_seeds("5..5").is_err());
        assert!(parse_seeds("a..b").is_err());
        // The largest seed has no seed after it: refused, not wrapped.
        let e = parse_seeds(&u64::MAX.to_string()).unwrap_err().to_string();
        assert!(e.contains("--seeds"), "{e}");
    }
}

mod simsetup {
    use robot_app::simsetup::*;
    use scan_types::{LaserSource, RayStatus};
    use std::path::Path;

    #[test]
    fn pose_errors_name_the_option_and_the_part() {
        let e = format!("{:#}", parse_pose("1,2,x").unwrap_err());
        assert!(e.starts_with("--pose: pose \"1,2,x\""), "{e}");
        assert!(e.contains("\"x\""), "{e}");
    }

    #[test]
    fn scan_source_in_the_paper_world() {
        let mut l = sim_scan_source(None, paper_start(), "paper", 1, false).unwrap();
        let s = l.next_scan().unwrap();
        assert_eq!(s.len(), 685);
        // Noise off: no dropouts, so no ray is an error.
        assert!(s.status.iter().all(|st| !matches!(st, RayStatus::Error(_))));
        assert!(
            sim_scan_source(
                Some(Path::new("/no/such.toml")),
                paper_start(),
                "paper",
                1,
                true
            )
            .is_err()
        );
        assert!(
            sim_scan_source(None, paper_start(), "lms200", 1, true)
                .unwrap_err()
                .to_string()
                .contains("lms200")
        );
    }
}
