//! What a careless user types gets a clear error that names the option, before any work is
//! done and without panics; and a few of the program's manners (exit codes, colours, pipes).

use std::path::Path;
use std::process::{Command, Output, Stdio};

#[path = "common/key_units.rs"]
mod key_units;

fn robot_app(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs")
}

/// `robot_app` with its address space capped at 2 GiB (`ulimit -v`), so that a regression
/// that plans in memory fails here instead of taking the machine's memory.
fn robot_app_capped(args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2097152 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_robot-app"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("sh runs robot-app")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Fails with exit status 1 (not a panic's 101) and a message holding every `needle`.
fn fails_naming(args: &[&str], needles: &[&str]) -> String {
    fails_naming_with(robot_app(args), args, needles)
}

/// [`fails_naming`] on an output already taken.
fn fails_naming_with(o: Output, args: &[&str], needles: &[&str]) -> String {
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    for n in needles {
        assert!(e.contains(n), "{args:?}: {n:?} not in {e}");
    }
    assert!(!e.contains("panicked"), "{e}");
    e
}

fn shared(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn far_or_absurd_goals_and_starts_are_refused_before_the_robot_moves() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().join("run");
    let o = o.to_str().unwrap();
    // The paper world spans -5..5 m.
    fails_naming(
        &["sim", "--goal", "1000,1000", "--out", o],
        &["target", "outside"],
    );
    fails_naming(
        &["sim", "--goal", "4000,4000", "--out", o],
        &["target", "outside"],
    );
    fails_naming(
        &["sim", "--goal", "1e19,0", "--out", o],
        &["target", "outside"],
    );
    fails_naming(
        &["sim", "--start=1e308,0,0", "--out", o],
        &["start", "outside"],
    );
    fails_naming(&["sim", "--goal", "nan,0", "--out", o], &["--goal"]);
    assert!(
        !Path::new(o).exists(),
        "nothing is written for a refused run"
    );
}

#[test]
fn a_world_whose_outside_holds_the_start_is_refused() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().join("run");
    let depot = shared("worlds/nav2/depot.yaml");
    if Path::new(&depot).exists() {
        fails_naming(
            &["sim", "--world", &depot, "--out", o.to_str().unwrap()],
            &["start", "outside the world", "--start"],
        );
    }
    let rooms = shared("worlds/stage/simple_rooms.png");
    if Path::new(&rooms).exists() {
        fails_naming(
            &["sim", "--world", &rooms, "--out", o.to_str().unwrap()],
            &["outside the world"],
        );
    }
}

#[test]
fn a_world_file_runs_its_own_scenario() {
    let dir = tempfile::tempdir().unwrap();
    // A folder that does not exist yet: `world generate` makes it.
    let world = dir.path().join("worlds/w{seed}.toml");
    let o = robot_app(&[
        "world",
        "generate",
        "--out",
        world.to_str().unwrap(),
        "--seed",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let world = dir.path().join("worlds/w3.toml");
    let text = std::fs::read_to_string(&world).unwrap();
    let out = dir.path().join("run");
    let _ = robot_app(&[
        "sim",
        "--world",
        world.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // The summary's start and goal are the file's, not the paper's (-3.92, -4.26) and (4, 4).
    let goal = &summary["goal"];
    let (gx, gy) = (goal["x_m"].as_f64().unwrap(), goal["y_m"].as_f64().unwrap());
    assert!((gx, gy) != (4.0, 4.0), "{summary}");
    let table: toml::Table = text.parse().unwrap();
    let target = table["target"].as_array().unwrap();
    assert!((target[0].as_float().unwrap() - gx).abs() < 1e-9, "{text}");
    assert!((target[1].as_float().unwrap() - gy).abs() < 1e-9, "{text}");
    // SPL's inputs: the geodesic is never shorter than the straight line, SPL in [0, 1] and
    // 0 exactly for a failure.
    let start = &summary["start"];
    let straight = (start["x_m"].as_f64().unwrap() - gx).hypot(start["y_m"].as_f64().unwrap() - gy);
    let l = summary["geodesic_m"].as_f64().unwrap();
    assert!(l >= straight - 1e-9, "{summary}");
    assert!(
        summary["true_path_length_m"].as_f64().unwrap() > 0.0,
        "{summary}"
    );
    let spl = summary["spl"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&spl), "{summary}");
    assert_eq!(spl == 0.0, summary["reached"] == false, "{summary}");

    // A batch in that world runs the same scenario.
    let batch = dir.path().join("batch");
    let o = robot_app(&[
        "batch",
        "--worlds",
        world.to_str().unwrap(),
        "--seeds",
        "0..1",
        "--scenarios",
        "paper",
        "--out",
        batch.to_str().unwrap(),
    ]);
    assert!(o.status.code().is_some_and(|c| c <= 1), "{}", stderr(&o));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(batch.join("batch.json")).unwrap()).unwrap();
    let rows = file["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 1, "{file}");
    assert_eq!(rows[0]["group"], "w3-scenario");
    assert_eq!(rows[0]["goal"], summary["goal"]);
    assert_eq!(rows[0]["start"], summary["start"]);
    // One run of the same scenario and robot: the same geodesic; the group's SPL is its SPL.
    assert_eq!(rows[0]["geodesic_m"], summary["geodesic_m"]);
    assert_eq!(file["aggregates"][0]["spl"], rows[0]["spl"]);
    assert_eq!(file["aggregates"][0]["spl_runs"], 1);

    // Every key of both files names its unit or is a documented unitless one.
    assert_eq!(
        key_units::keys_without_unit(&summary),
        Vec::<String>::new(),
        "{summary}"
    );
    assert_eq!(
        key_units::keys_without_unit(&file),
        Vec::<String>::new(),
        "{file}"
    );
    // A pose's heading is in degrees: the summary's start is the world file's, given in degrees.
    let start_deg = table["start"].as_array().unwrap()[2].as_float().unwrap();
    let d = summary["start"]["heading_deg"].as_f64().unwrap() - start_deg;
    assert!(
        (d + 540.0).rem_euclid(360.0) - 180.0 < 1e-9,
        "{summary} {text}"
    );
}

#[test]
fn configuration_values_out_of_range_name_their_key() {
    let dir = tempfile::tempdir().unwrap();
    for (text, key) in [
        (
            "[navigator]\ngoal_tolerance_m = 100\n",
            "navigator.goal_tolerance_m",
        ),
        (
            "[localiser]\nmap_resolution_m = 0.0001\n",
            "localiser.map_resolution_m",
        ),
        (
            "[planner]\ngrid_resolution_m = 0.001\n",
            "planner.grid_resolution_m",
        ),
        ("[robot]\nradius_m = -1\n", "robot.radius_m"),
    ] {
        let cfg = dir.path().join("c.toml");
        std::fs::write(&cfg, text).unwrap();
        fails_naming(
            &["sim", "--config", cfg.to_str().unwrap()],
            &[key, "c.toml"],
        );
    }
    let intel = shared("data/intel.gfs.log");
    if Path::new(&intel).exists() {
        let out = dir.path().join("map");
        fails_naming(
            &[
                "map",
                "--log",
                &intel,
                "--resolution",
                "0.0005",
                "--out",
                out.to_str().unwrap(),
            ],
            &["--resolution"],
        );
    }
    fails_naming(&["batch", "--min-distance", "nan"], &["--min-distance"]);
    fails_naming(&["batch", "--min-distance=-5"], &["--min-distance"]);
}

#[test]
fn batch_checks_its_output_folder_before_the_first_run() {
    let dir = tempfile::tempdir().unwrap();
    // A file where the folder should be: nothing can be written under it.
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let out = blocker.join("batch");
    let started = std::time::Instant::now();
    fails_naming(
        &["batch", "--seeds", "0..50", "--out", out.to_str().unwrap()],
        &["--out"],
    );
    // 100 runs take seconds; the check takes none of them.
    let o = robot_app(&[
        "batch",
        "--seeds",
        "0..2",
        "--scenarios",
        "paper",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(started.elapsed().as_secs() < 60);
    assert!(o.stdout.is_empty(), "no table: nothing ran");
}

#[test]
fn batches_too_large_to_plan_are_refused_before_they_take_the_memory() {
    // 2e11 runs planned in memory took all 24 GiB of this machine before the check.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let out = out.to_str().unwrap();
    let capped = |args: &[&str], needles: &[&str]| {
        fails_naming_with(robot_app_capped(args), args, needles);
    };
    capped(
        &["batch", "--seeds", "0..99999999999", "--out", out],
        &["--seeds 0..99999999999", "100000 runs"],
    );
    // Past u64: the count saturates instead of wrapping to a small number.
    capped(
        &[
            "batch",
            "--random-pairs",
            "18446744073709551615",
            "--scenarios",
            "pairs",
            "--out",
            out,
        ],
        &["100000 runs"],
    );
    capped(
        &["batch", "--random-worlds", "5000", "--out", out],
        &["--random-worlds 5000", "1000 generated worlds"],
    );
    capped(
        &["explore", "--seeds", "0..99999999999", "--out", out],
        &["--seeds 0..99999999999", "100000"],
    );
    // The limit's edge is counted by hand in `cmd::batch::jobs`'s unit test.
}

#[test]
fn errors_say_their_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let e = fails_naming(
        &["sim", "--config", dir.path().to_str().unwrap()],
        &["Is a directory"],
    );
    assert_eq!(e.matches("Is a directory").count(), 1, "{e}");
}

#[test]
fn no_colour_codes_when_stderr_is_not_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let o = robot_app(&["sim", "--out", dir.path().join("run").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(!e.is_empty());
    assert!(!e.contains('\u{1b}'), "ANSI escape in {e:?}");
}

#[test]
fn a_closed_stdout_ends_a_command_quietly() {
    // `robot-app scan --sim ... | head -1`: the reader goes away after one line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args(["scan", "--sim", "--count", "200", "--format", "csv"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 64];
    std::io::Read::read_exact(child.stdout.as_mut().unwrap(), &mut first).unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let e = stderr(&o);
    assert!(o.status.success(), "exit {:?}: {e}", o.status.code());
    assert!(!e.contains("Broken pipe"), "{e}");
}

/// Runs `robot-app args` with its stdout closed before it starts (a reader that has gone away).
fn with_stdout_closed(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_stdout_still_gets_every_file_written() {
    let dir = tempfile::tempdir().unwrap();
    let worlds = dir.path().join("w{seed}.toml");
    let o = with_stdout_closed(&[
        "world",
        "generate",
        "--count",
        "3",
        "--out",
        worlds.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "exit {:?}: {e}", o.status.code());
    assert!(!e.contains("panicked"), "{e}");
    for seed in 0..3 {
        assert!(dir.path().join(format!("w{seed}.toml")).exists(), "w{seed}");
    }
    let out = dir.path().join("batch");
    let o = with_stdout_closed(&[
        "-q",
        "batch",
        "--jobs",
        "1",
        "--seeds",
        "0..1",
        "--scenarios",
        "paper",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "exit {:?}: {e}", o.status.code());
    assert!(!e.contains("panicked"), "{e}");
    assert!(out.join("batch.json").exists());
}

#[test]
fn a_negative_value_is_named_by_its_option() {
    let log = shared("data/breezyslam/exp1.dat");
    fails_naming(
        &["slam", "--log", &log, "--max-range", "-5"],
        &["--max-range -5", "above 0"],
    );
    fails_naming(
        &["map", "--log", &log, "--resolution", "-1"],
        &["--resolution -1"],
    );
}

#[test]
fn a_slam_run_with_nothing_in_map_range_still_writes_its_report() {
    // No URG-04LX hit lies within 0.1 m: the map is empty, the trajectory and report are not.
    let dir = tempfile::tempdir().unwrap();
    let log = shared("data/breezyslam/exp1.dat");
    let o = robot_app(&[
        "-q",
        "slam",
        "--log",
        &log,
        "--no-loop-closure",
        "--max-range",
        "0.1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("slam.json")).unwrap()).unwrap();
    assert_eq!(report["placed"].as_u64(), Some(756));
    // No map, so no consistency figure (not 0 %), here and on the summary line.
    assert!(report["map_consistency_share"].is_null(), "{report}");
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("no map (no hit in map range)"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(dir.path().join("trajectory.tum").exists());
    assert!(!dir.path().join("map.pgm").exists());
}

#[test]
fn world_info_says_when_the_scenario_is_the_papers_fallback() {
    // A generated .yaml world stores no scenario; its .toml twin stores one.
    let dir = tempfile::tempdir().unwrap();
    for ext in ["yaml", "toml"] {
        let path = dir.path().join(format!("w.{ext}"));
        let o = robot_app(&[
            "-q",
            "world",
            "generate",
            "--seed",
            "3",
            "--out",
            path.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = robot_app(&["world", "info", path.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            text.contains("none stored: the paper's"),
            ext == "yaml",
            "{ext}: {text}"
        );
    }
}

#[test]
fn a_replay_whose_reader_goes_away_still_finishes_its_recording() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("r.mcap");
    let log = shared("data/breezyslam/exp1.dat");
    let o = with_stdout_closed(&[
        "-q",
        "replay",
        &log,
        "--rate",
        "0",
        "--record",
        rec.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A whole MCAP file ends with its magic bytes.
    let bytes = std::fs::read(&rec).unwrap();
    assert!(bytes.ends_with(b"\x89MCAP0\r\n"), "{} bytes", bytes.len());
}

#[test]
fn a_log_clock_that_jumps_is_not_slept_through() {
    // exp1's first six lines, the third's time stamp (microseconds) moved 10^15 us (31 years)
    // ahead: real-time pacing would sleep for years on it.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(shared("data/breezyslam/exp1.dat")).unwrap();
    let mut lines: Vec<String> = text.lines().take(6).map(str::to_string).collect();
    let (stamp, rest) = lines[2].split_once(' ').unwrap();
    lines[2] = format!(
        "{} {rest}",
        stamp.parse::<u64>().unwrap() + 1_000_000_000_000_000
    );
    let log = dir.path().join("jump.dat");
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    let t = std::time::Instant::now();
    let o = robot_app(&["replay", log.to_str().unwrap(), "--format", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(t.elapsed() < std::time::Duration::from_secs(20));
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 6);
    assert!(stderr(&o).contains("clock jumps"), "{}", stderr(&o));
}

#[test]
fn an_image_too_large_for_a_world_is_refused_from_its_header() {
    // A PGM header claiming 20 000 x 20 000 pixels (400 MB to decode, 1.6 GB as RGBA) and no
    // pixels: refused by the size its header gives, before anything is decoded.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.pgm");
    std::fs::write(&path, b"P5\n20000 20000\n255\n").unwrap();
    let p = path.to_str().unwrap();
    fails_naming_with(
        robot_app_capped(&["world", "info", p]),
        &["world", "info", p],
        &["big.pgm", "20000 x 20000 pixels", "at most 64000000 pixels"],
    );
}
