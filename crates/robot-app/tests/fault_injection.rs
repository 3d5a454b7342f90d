//! The whole loop under faults: the simulator casts the scans, the SCIP emulator serves them
//! on a pseudo-terminal, `robot-app run` reads them through its driver, and this test is the
//! robot base on the other end of `--base stdio`, moving the simulated robot. Each fault must
//! end the run with its own reason, the base always gets `stop`, and every output is whole.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::time::Duration;

use scan_types::{MotionBase, WorldPoint};
use sim_laser::{BaseGains, SensorPreset, SimBase, Simulation, TruthHandle, World, paper_start};
use urg_driver::{Fault, FixedSource, Model, Profile, PtyServer};

/// A goal two legs from the paper's start (about 70 scans): quick over a 10 Hz sensor.
const GOAL: (f64, f64) = (-1.0, -3.0);

#[path = "common/tum.rs"]
mod tum;

struct Harness {
    child: Child,
    to_app: ChildStdin,
    from_app: BufReader<ChildStdout>,
    base: SimBase,
    truth: TruthHandle,
    server: PtyServer,
    out: tempfile::TempDir,
    commands: usize,
    stops: usize,
}

impl Harness {
    fn start(gains: BaseGains, extra: &[&str]) -> Harness {
        let preset = SensorPreset::Urg04lx;
        let sim = Simulation::new(
            Arc::new(World::paper()),
            preset,
            preset.default_noise(),
            sim_laser::MotionNoise::default(),
            0.3,
            paper_start(),
            3,
        )
        .with_base_gains(gains);
        let (laser, base, truth) = sim.split();
        let server = urg_driver::serve_pty(Profile::of(Model::Urg04lx), laser).expect("a pty");
        let out = tempfile::tempdir().unwrap();
        let start = paper_start();
        let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
            .arg("run")
            .args(["--port", server.path()])
            .arg(format!("--goal={},{}", GOAL.0, GOAL.1))
            .arg(format!(
                "--start={},{},{}",
                start.x_m,
                start.y_m,
                start.theta_rad.to_degrees()
            ))
            .args(["--base", "stdio"])
            .arg("--out")
            .arg(out.path().join("run"))
            .args(extra)
            .env("RUST_LOG", "warn")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("robot-app starts");
        let to_app = child.stdin.take().unwrap();
        let from_app = BufReader::new(child.stdout.take().unwrap());
        Harness {
            child,
            to_app,
            from_app,
            base,
            truth,
            server,
            out,
            commands: 0,
            stops: 0,
        }
    }

    /// Plays the base until robot-app closes its end; `fault` runs before each answer with
    /// the number of motion commands so far.
    fn drive(&mut self, fault: impl FnMut(usize, &Harness)) {
        self.drive_answering(fault, |_| None);
    }

    /// [`Harness::drive`], with `answer` replacing the base's answer to command `n` when it
    /// returns one.
    fn drive_answering(
        &mut self,
        mut fault: impl FnMut(usize, &Harness),
        answer_of: impl Fn(usize) -> Option<&'static str>,
    ) {
        let mut line = String::new();
        loop {
            line.clear();
            if self.from_app.read_line(&mut line).unwrap_or(0) == 0 {
                break;
            }
            let cmd = line.trim();
            let mut words = cmd.split_whitespace();
            let answer = match (words.next(), words.next().map(str::parse::<f64>)) {
                (Some("rotate"), Some(Ok(a))) => self.base.rotate(a).map(|()| "done"),
                (Some("forward"), Some(Ok(d))) => self.base.forward(d).map(|()| "done"),
                (Some("stop"), None) => {
                    self.stops += 1;
                    Ok("done")
                }
                _ => panic!("not a base command: {cmd:?}"),
            }
            .expect("the simulated base moves");
            let mut answer = answer;
            if cmd != "stop" {
                self.commands += 1;
                fault(self.commands, self);
                answer = answer_of(self.commands).unwrap_or(answer);
            }
            // robot-app may have exited already after `stop`.
            let _ = writeln!(self.to_app, "{answer}");
            let _ = self.to_app.flush();
        }
    }

    fn finish(mut self) -> Ended {
        let status = self.child.wait().unwrap();
        let mut stderr = String::new();
        std::io::Read::read_to_string(self.child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
        let dir = self.out.path().join("run");
        let summary = std::fs::read_to_string(dir.join("summary.json"))
            .map(|t| serde_json::from_str::<serde_json::Value>(&t).expect("summary.json parses"));
        let distance = self
            .truth
            .pose()
            .position()
            .distance_m(&WorldPoint::new(GOAL.0, GOAL.1));
        self.server.stop();
        Ended {
            status,
            stderr,
            summary: summary.ok(),
            stops: self.stops,
            commands: self.commands,
            true_distance_m: distance,
            dir: self.out,
        }
    }
}

struct Ended {
    status: ExitStatus,
    stderr: String,
    summary: Option<serde_json::Value>,
    stops: usize,
    commands: usize,
    true_distance_m: f64,
    dir: tempfile::TempDir,
}

impl Ended {
    fn reason(&self) -> String {
        let s = self.summary.as_ref().unwrap_or_else(|| {
            panic!("no summary.json; stderr:\n{}", self.stderr);
        });
        s["reason"].as_str().unwrap().to_string()
    }

    /// The base got exactly one `stop`, and every output file is whole.
    fn assert_clean_end(&self) {
        assert_eq!(self.stops, 1, "stop sent once; stderr:\n{}", self.stderr);
        let run = self.dir.path().join("run");
        for f in [
            "summary.json",
            "trajectory.csv",
            "map.pgm",
            "map.yaml",
            "map.png",
        ] {
            let p = run.join(f);
            assert!(
                p.metadata().is_ok_and(|m| m.len() > 0),
                "{f} missing or empty"
            );
        }
        assert_no_partial_files(&run);
    }
}

fn assert_no_partial_files(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !name.ends_with(".partial") && !name.starts_with(".tmp"),
            "half-written file left: {name}"
        );
    }
}

#[test]
fn no_fault_reaches_the_goal_and_maps_the_run() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    h.drive(|_, _| {});
    let end = h.finish();
    assert!(end.status.success(), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "reached");
    assert!(
        end.true_distance_m < 0.3,
        "{} m from the goal",
        end.true_distance_m
    );
    end.assert_clean_end();
    // `run` maps by default: every scan the run read is recorded and placed.
    let run = end.dir.path().join("run");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run.join("slam/slam.json")).unwrap()).unwrap();
    assert_eq!(report["scans"].as_u64(), Some(recorded_scans(&run)));
    assert_eq!(report["placed"], report["scans"]);
    // Each search is centred on the navigator's own estimate, recorded with every scan.
    assert_eq!(report["motion_prior"], serde_json::json!(true));
    assert!(report["evaluation"].is_object());
    assert!(
        run.join("slam/map.pgm")
            .metadata()
            .is_ok_and(|m| m.len() > 0)
    );
}

#[test]
fn no_slam_map_records_and_maps_nothing() {
    let mut h = Harness::start(BaseGains::default(), &["--no-slam-map"]);
    h.drive(|_, _| {});
    let end = h.finish();
    assert!(end.status.success(), "stderr:\n{}", end.stderr);
    end.assert_clean_end();
    let run = end.dir.path().join("run");
    assert!(run.join("summary.json").exists());
    assert!(!run.join("run.mcap").exists());
    assert!(!run.join("slam").exists());
}

/// The number of scans in the run's recording `run/run.mcap`.
fn recorded_scans(run: &Path) -> u64 {
    let mut log = scan_log::open_log(&run.join("run.mcap"), None).expect("the recording opens");
    let mut scans = 0u64;
    while scan_types::LaserSource::next_scan(&mut log).is_ok() {
        scans += 1;
    }
    scans
}

#[test]
fn unplug_and_replug_mid_leg_is_survived() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    h.drive(|n, h| {
        if n == 10 {
            // Mid-leg: the sensor is gone for 2 s, then back behind the same path.
            let ctl = h.server.control().clone();
            ctl.unplug();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_secs(2));
                ctl.plug();
            });
        }
    });
    let end = h.finish();
    assert!(end.status.success(), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "reached");
    assert!(
        end.stderr.contains("reconnected"),
        "stderr:\n{}",
        end.stderr
    );
    end.assert_clean_end();
}

#[test]
fn a_checksum_storm_is_ridden_out() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    h.drive(|n, h| {
        if n == 5 {
            // Fewer in a row than the driver tolerates (10): each bad scan is dropped.
            for _ in 0..6 {
                h.server.control().inject(Fault::CorruptChecksum);
            }
        }
    });
    let end = h.finish();
    assert!(end.status.success(), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "reached");
    end.assert_clean_end();
}

#[test]
fn a_stalled_sensor_ends_as_sensor_failure() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    h.drive(|n, h| {
        if n == 5 {
            h.server.control().set_stalled(true);
        }
    });
    let end = h.finish();
    assert!(!end.status.success());
    assert_eq!(end.reason(), "sensor_failure");
    end.assert_clean_end();
}

#[test]
fn a_stalled_base_ends_as_base_stalled() {
    let mut h = Harness::start(
        BaseGains {
            drive: 0.0,
            turn: 1.0,
        },
        &[],
    );
    h.drive(|_, _| {});
    let end = h.finish();
    assert!(!end.status.success());
    assert_eq!(end.reason(), "base_stalled");
    end.assert_clean_end();
}

#[test]
fn a_slipping_base_gives_no_false_arrival() {
    let mut h = Harness::start(
        BaseGains {
            drive: 0.5,
            turn: 1.0,
        },
        &[],
    );
    h.drive(|_, _| {});
    let end = h.finish();
    if end.reason() == "reached" {
        // The goal tolerance (0.15 m) plus 0.1 m of localisation error.
        assert!(
            end.true_distance_m < 0.25,
            "reached, but {} m away",
            end.true_distance_m
        );
    }
    end.assert_clean_end();
}

#[test]
fn sigint_stops_the_base_writes_everything_and_exits_130() {
    let rec = tempfile::tempdir().unwrap();
    let rec_path = rec.path().join("rec.mcap");
    let mut h = Harness::start(
        BaseGains::default(),
        &["--record", rec_path.to_str().unwrap()],
    );
    let pid = nix::unistd::Pid::from_raw(i32::try_from(h.child.id()).unwrap());
    h.drive(|n, _| {
        if n == 8 {
            // What Ctrl-C in the terminal sends.
            nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).unwrap();
        }
    });
    let end = h.finish();
    assert_eq!(end.status.code(), Some(130), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "interrupted");
    assert!(end.commands < 40, "it stopped soon after the signal");
    end.assert_clean_end();
    // The recording is finished, not left half-written.
    let mut log = scan_log::open_log(&rec_path, None).expect("the recording opens");
    let mut scans = 0;
    while scan_types::LaserSource::next_scan(&mut log).is_ok() {
        scans += 1;
    }
    assert!(scans > 0);
    assert_no_partial_files(rec.path());
}

#[test]
fn ctrl_c_still_maps_the_run_from_its_scans() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    let pid = nix::unistd::Pid::from_raw(i32::try_from(h.child.id()).unwrap());
    // Where the simulated robot stood before each motion command, in the frame of its start
    // (the first scan's): the run scans only between moves.
    let start = paper_start().inverse();
    let mut stood = Vec::new();
    h.drive(|n, h| {
        stood.push(start.compose(&h.truth.pose()));
        if n == 20 {
            nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).unwrap();
        }
    });
    stood.push(start.compose(&h.truth.pose()));
    let end = h.finish();
    assert_eq!(end.status.code(), Some(130), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "interrupted");
    end.assert_clean_end();
    let run = end.dir.path().join("run");
    // Every scan the run read is in its recording, and every one of them was mapped.
    let scans = recorded_scans(&run);
    let slam = run.join("slam");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(slam.join("slam.json")).unwrap()).unwrap();
    assert!(scans > 0);
    assert_eq!(report["scans"].as_u64(), Some(scans));
    assert_eq!(report["placed"].as_u64(), Some(scans));
    for f in ["map.pgm", "map.yaml", "map.png", "trajectory.tum"] {
        assert!(slam.join(f).metadata().is_ok_and(|m| m.len() > 0), "{f}");
    }
    assert_no_partial_files(&slam);
    // The laser-only estimate of the last scan is within 3 cm of one of the last places the
    // robot stood (which one depends on when the streaming sensor's last scan was taken).
    let last = tum::last_xy(&slam.join("trajectory.tum"));
    let off = stood
        .iter()
        .rev()
        .take(4)
        .map(|p| (last[0] - p.x_m).hypot(last[1] - p.y_m))
        .fold(f64::INFINITY, f64::min);
    let moved = stood.last().unwrap();
    assert!(
        moved.x_m.hypot(moved.y_m) > 0.8 && off < 0.03,
        "stood at {:?}, estimate {last:?}",
        &stood[stood.len().saturating_sub(4)..]
    );
}

#[test]
fn a_base_error_ends_as_base_failure_not_sensor_failure() {
    let mut h = Harness::start(BaseGains::default(), &[]);
    h.drive_answering(|_, _| {}, |n| (n == 6).then_some("error motor stalled"));
    let end = h.finish();
    assert!(!end.status.success());
    assert_eq!(end.reason(), "base_failure");
    let note = end.summary.as_ref().unwrap()["note"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(note.contains("motor stalled"), "{note}");
    end.assert_clean_end();
}

#[test]
fn a_base_that_never_moves_is_not_taken_to_have_arrived_one_leg_away() {
    // The emulator's fixed room: walls 3 m ahead, 1.5 m behind and 2.5 m / 2 m to the sides.
    // The target lies 1 m straight ahead, one leg; the base answers `done` and never moves,
    // so every scan is the first one. After a commanded 1 m the side walls pair either way,
    // but the wall ahead is still 3 m away: the laser puts the travel at 0, not the command.
    let server = fixed_room();
    let out = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args(["run", "--port", server.path(), "--goal=1,0"])
        .args(["--base", "stdio"])
        .args(["--no-slam-map", "--out"])
        .arg(out.path().join("run"))
        .env("RUST_LOG", "warn")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("robot-app starts");
    let mut to_app = child.stdin.take().unwrap();
    let from_app = BufReader::new(child.stdout.take().unwrap());
    let (mut forward_m, mut stops) = (0.0, 0);
    for line in from_app.lines() {
        let line = line.unwrap();
        let mut words = line.split_whitespace();
        match (words.next(), words.next().map(str::parse::<f64>)) {
            (Some("forward"), Some(Ok(d))) => forward_m += d,
            (Some("rotate"), Some(Ok(_))) => {}
            (Some("stop"), None) => stops += 1,
            _ => panic!("not a base command: {line:?}"),
        }
        let _ = writeln!(to_app, "done");
        let _ = to_app.flush();
    }
    let status = child.wait().unwrap();
    server.stop();
    let summary: serde_json::Value = serde_json::from_slice(
        &std::fs::read(out.path().join("run/summary.json")).expect("summary.json written"),
    )
    .unwrap();
    assert!(!status.success());
    assert_eq!(summary["reason"], "base_stalled", "{summary}");
    assert_eq!(summary["reached"], false);
    // It was told to drive the leg (twice: stall_legs), and stopped once at the end.
    assert!(forward_m >= 1.9, "commanded {forward_m} m");
    assert_eq!(stops, 1);
}

#[test]
fn sigint_while_a_move_goes_unanswered_still_stops_the_base_and_exits_130() {
    // The base takes move 8 and never answers it (stuck, or a slow move); Ctrl-C comes then.
    let mut h = Harness::start(BaseGains::default(), &[]);
    let pid = nix::unistd::Pid::from_raw(i32::try_from(h.child.id()).unwrap());
    let mut line = String::new();
    let mut after_signal = Vec::new();
    loop {
        line.clear();
        if h.from_app.read_line(&mut line).unwrap_or(0) == 0 {
            break;
        }
        let cmd = line.trim().to_string();
        if cmd == "stop" {
            h.stops += 1;
        } else if h.commands < 8 {
            let mut words = cmd.split_whitespace();
            match (words.next(), words.next().map(str::parse::<f64>)) {
                (Some("rotate"), Some(Ok(a))) => h.base.rotate(a).unwrap(),
                (Some("forward"), Some(Ok(d))) => h.base.forward(d).unwrap(),
                _ => panic!("not a base command: {cmd:?}"),
            }
        }
        if h.commands >= 8 {
            after_signal.push(cmd.clone());
        }
        if cmd != "stop" {
            h.commands += 1;
            if h.commands == 8 {
                std::thread::sleep(Duration::from_millis(300));
                nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).unwrap();
                continue;
            }
        }
        let _ = writeln!(h.to_app, "done");
        let _ = h.to_app.flush();
    }
    let end = h.finish();
    assert_eq!(end.status.code(), Some(130), "stderr:\n{}", end.stderr);
    assert_eq!(end.reason(), "interrupted");
    // Nothing but `stop` after the unanswered move.
    assert_eq!(after_signal, ["stop"], "stderr:\n{}", end.stderr);
    end.assert_clean_end();
}

#[test]
fn a_run_that_fails_to_start_stops_the_base_and_keeps_the_earlier_recording() {
    // A target too far for any map: refused after the base and the sensor are open.
    let server = fixed_room();
    let out = tempfile::tempdir().unwrap();
    let run = out.path().join("run");
    std::fs::create_dir_all(&run).unwrap();
    let earlier = b"an earlier run's recording".to_vec();
    std::fs::write(run.join("run.mcap"), &earlier).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args(["run", "--port", server.path(), "--goal=1e19,0"])
        .args(["--base", "stdio", "--out"])
        .arg(&run)
        .env("RUST_LOG", "warn")
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs");
    server.stop();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert_eq!(String::from_utf8_lossy(&o.stdout), "stop\n", "{stderr}");
    assert_eq!(std::fs::read(run.join("run.mcap")).unwrap(), earlier);
    assert_no_partial_files(&run);
}

/// The emulator's fixed room (a URG-04LX) on a pseudo-terminal.
fn fixed_room() -> PtyServer {
    let p = Profile::of(Model::Urg04lx);
    urg_driver::serve_pty(p.clone(), FixedSource::room(p.params.geometry())).expect("a pty")
}
