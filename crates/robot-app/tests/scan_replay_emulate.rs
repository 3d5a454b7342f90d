//! The built `robot-app` as a user runs it: `scan` stopped by a signal or losing its sensor,
//! `replay --loop` of cut or damaged recordings, what `emulate` announces, and the checks of
//! `--noise` and the numeric options.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use clap::Parser;
use robot_app::cmd::scan::{self, ScanArgs};
use scan_log::{LegSummary, McapRecorder, partial_path, read_mcap, read_mcap_metadata};
use urg_driver::{FixedSource, Model, Profile, serve_pty};

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

/// Held while a child starts, and by the test serving a pseudo-terminal for its whole run: a
/// child started in the instant before the emulator makes its ends close-on-exec would
/// inherit them and keep the terminal open through the unplug.
static NO_PTY_OPEN: Mutex<()> = Mutex::new(());

fn pty_lock() -> MutexGuard<'static, ()> {
    NO_PTY_OPEN.lock().unwrap_or_else(|e| e.into_inner())
}

/// `Command::spawn` while no pseudo-terminal of this process is open.
trait SpawnLocked {
    fn spawn_locked(&mut self) -> Child;
}

impl SpawnLocked for Command {
    fn spawn_locked(&mut self) -> Child {
        let _no_pty = pty_lock();
        self.spawn().expect("the child starts")
    }
}

fn robot_app(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn_locked()
        .wait_with_output()
        .expect("robot-app runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Waits for `child` at most `limit`; kills it and fails past that.
fn wait_at_most(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let started = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            panic!("robot-app still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `robot-app sim --record` of the paper's scenario into `dir`: the recording's path.
fn recorded_sim_run(dir: &Path) -> std::path::PathBuf {
    let rec = dir.join("run.mcap");
    let out = dir.join("out");
    let o = robot_app(&[
        "-q",
        "sim",
        "--record",
        rec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    rec
}

#[test]
fn scan_record_interrupted_finishes_the_recording() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("scans.mcap");
    let mut child = Command::new(BIN)
        .args(["-q", "scan", "--sim", "--count", "100000000", "--record"])
        .arg(&rec)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn_locked();
    std::thread::sleep(Duration::from_secs(1));
    sigint(&child);
    let status = wait_at_most(&mut child, Duration::from_secs(20));
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(!partial_path(&rec).exists(), "a .partial file is left");
    let records = read_mcap(&rec).unwrap();
    assert!(!records.is_empty());
    for r in &records {
        let r = r
            .as_ref()
            .expect("every record of a finished recording reads");
        assert_eq!(r.scan.ranges_m.len(), r.geometry.ray_count);
    }
}

/// Runs robot-app with `args` and sends SIGINT after `delay`: its exit status, how long it took
/// to stop after the signal, and what it printed on stdout.
fn interrupted_after(
    args: &[&std::ffi::OsStr],
    delay: Duration,
) -> (std::process::ExitStatus, Duration, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn_locked();
    // Read while it runs, so that a full pipe cannot hold it up.
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut printed = String::new();
        stdout.read_to_string(&mut printed).unwrap();
        printed
    });
    std::thread::sleep(delay);
    sigint(&child);
    let stopped = Instant::now();
    let status = wait_at_most(&mut child, Duration::from_secs(30));
    let took = stopped.elapsed();
    (status, took, reader.join().unwrap())
}

#[test]
fn replay_slam_landmarks_and_emulate_stop_on_ctrl_c() {
    let dir = tempfile::tempdir().unwrap();
    let exp1 =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/breezyslam/exp1.dat");
    assert!(exp1.exists(), "{} missing", exp1.display());
    let os = |s: &'static str| std::ffi::OsStr::new(s);
    // replay paces the 75 s log in real time: Ctrl-C ends it within its 50 ms naps, and the
    // recording of the scans played so far is finished.
    let rec = dir.path().join("played.mcap");
    let (status, took, _) = interrupted_after(
        &[
            os("-q"),
            os("replay"),
            exp1.as_os_str(),
            os("--record"),
            rec.as_os_str(),
        ],
        Duration::from_secs(1),
    );
    assert_eq!(status.code(), Some(130));
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(!partial_path(&rec).exists(), "a .partial file is left");
    let played = read_mcap(&rec).unwrap().len();
    assert!(
        (1..756).contains(&played),
        "{played} of exp1's 756 scans recorded"
    );
    // slam over 20 copies of exp1 (15 120 scans, several seconds): Ctrl-C ends the reading,
    // and the outputs hold the scans read, without loop closure.
    let text = std::fs::read(&exp1).unwrap();
    let long = dir.path().join("long.dat");
    std::fs::write(&long, text.repeat(20)).unwrap();
    let out = dir.path().join("slam");
    let (status, took, _) = interrupted_after(
        &[
            os("-q"),
            os("slam"),
            os("--log"),
            long.as_os_str(),
            os("--out"),
            out.as_os_str(),
        ],
        Duration::from_millis(1500),
    );
    assert_eq!(status.code(), Some(130));
    assert!(took < Duration::from_secs(10), "{took:?}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("slam.json")).unwrap()).unwrap();
    let scans = report["scans"].as_u64().unwrap();
    assert!((1..15_120).contains(&scans), "{scans} scans read");
    assert!(
        report["loop_closure"].is_null(),
        "{}",
        report["loop_closure"]
    );
    let lines = std::fs::read_to_string(out.join("trajectory.tum")).unwrap();
    let poses = lines.lines().filter(|l| !l.starts_with('#')).count() as u64;
    assert_eq!(poses, report["placed"].as_u64().unwrap());
    // landmarks counts the same log for about 14 s: it stops without printing.
    let (status, took, printed) = interrupted_after(
        &[os("-q"), os("landmarks"), os("--log"), long.as_os_str()],
        Duration::from_millis(1500),
    );
    assert_eq!(status.code(), Some(130));
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(printed.is_empty(), "{printed}");
    // emulate serves until stopped: Ctrl-C stops it, with or without its standard input.
    let (status, took, _) = interrupted_after(
        &[os("-q"), os("emulate"), os("--no-stdin")],
        Duration::from_secs(1),
    );
    assert_eq!(status.code(), Some(130));
    assert!(took < Duration::from_secs(2), "{took:?}");
}

// In this process, not as a child: a child would inherit the emulator's end of the
// pseudo-terminal (opened without close-on-exec), and the terminal would never close.
#[test]
fn scan_on_a_hokuyo_survives_an_unplug() {
    let _no_child_starts = pty_lock();
    let profile = Profile::of(Model::Urg04lx);
    let geometry = profile.params.geometry();
    let server = serve_pty(profile, FixedSource::room(geometry)).unwrap();
    let count = 20;
    let args = ScanCli::try_parse_from(["scan", "--port", server.path(), "--count", "20"])
        .unwrap()
        .args;
    let scanning = std::thread::spawn(move || {
        let mut out = Vec::new();
        scan::run_to(&args, &mut out).map(|()| out)
    });
    // Unplug once a few scans are out, for 2 s.
    let started = Instant::now();
    while server.control().scans_served() < 3 {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "no scans served"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    server.control().unplug();
    std::thread::sleep(Duration::from_secs(2));
    assert!(!scanning.is_finished(), "scan ended while unplugged");
    server.control().plug();
    let out = scanning.join().unwrap().expect("scan survives the unplug");
    let stdout = text(&out);
    assert_eq!(stdout.matches("# goalseek-scan ").count(), count);
    // Every block is a whole URG-04LX scan: one row per step 44..=725, the wall 3 m ahead
    // (step 384 = AFRT, row 340) in each.
    let rows: Vec<&str> = stdout
        .lines()
        .filter(|l| l.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .collect();
    assert_eq!(rows.len(), count * (725 - 44 + 1));
    let ahead: Vec<&str> = rows
        .iter()
        .filter(|r| r.starts_with("340,"))
        .copied()
        .collect();
    assert_eq!(ahead.len(), count);
    assert!(
        ahead.iter().all(|r| r.ends_with(",3.000000,1")),
        "{ahead:?}"
    );
    assert!(server.control().scans_served() > count as u64 - 1);
}

/// `robot-app scan`'s arguments on their own.
#[derive(clap::Parser)]
struct ScanCli {
    #[command(flatten)]
    args: ScanArgs,
}

#[test]
fn replay_loop_of_a_cut_recording_fails() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recorded_sim_run(dir.path());
    let bytes = std::fs::read(&rec).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let o = robot_app(&["-q", "replay", "--loop", cut.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    let err = text(&o.stderr);
    assert!(
        err.contains("did not reach the target: sensor_failure"),
        "{err}"
    );
}

#[test]
fn replay_of_legs_that_differ_says_them_readably() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recorded_sim_run(dir.path());
    // The same recording with one bit of one recorded point B changed.
    let (reason, mut legs) = scan_log::read_recorded_legs(&rec).unwrap().unwrap();
    let (row, b) = legs
        .iter_mut()
        .enumerate()
        .find_map(|(i, l)| l.point_b.as_mut().map(|b| (i, b)))
        .unwrap();
    let recorded_x = b[0];
    b[0] = f64::from_bits(b[0].to_bits() + 1);
    let changed_x = b[0];
    let bad = dir.path().join("bad.mcap");
    let mut w = McapRecorder::create(&bad).unwrap();
    for (name, values) in read_mcap_metadata(&rec).unwrap() {
        if name == scan_log::RUN_METADATA {
            w.write_metadata(&name, &values).unwrap();
        }
    }
    for r in read_mcap(&rec).unwrap() {
        let r = r.unwrap();
        w.record_scan(&r.geometry, &r.scan, r.true_pose, r.pose)
            .unwrap();
    }
    w.write_legs(&legs, &reason).unwrap();
    w.finish().unwrap();

    let o = robot_app(&["-q", "replay", "--loop", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    for debug in ["Some(", "LegSummary", "{ "] {
        assert!(!err.contains(debug), "{debug:?} in {err}");
    }
    let leg: &LegSummary = &legs[row];
    // The recorded (changed) value and the replayed (original) one, each as Rust reads it back.
    assert!(err.contains(&format!("at row {row}")), "{err}");
    assert!(err.contains(&format!("recorded leg {}:", leg.leg)), "{err}");
    assert!(err.contains(&format!("point B ({changed_x}, ")), "{err}");
    assert!(err.contains(&format!("point B ({recorded_x}, ")), "{err}");
}

#[test]
fn emulate_names_the_log_it_serves() {
    let log =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/breezyslam/exp1.dat");
    assert!(log.exists(), "{} missing", log.display());
    let mut child = Command::new(BIN)
        .args(["emulate", "--source"])
        .arg(&log)
        .env("RUST_LOG", "info")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn_locked();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut announced = String::new();
    while !announced.contains("emulated") {
        announced.clear();
        assert!(
            stderr.read_line(&mut announced).unwrap() > 0,
            "no announcement"
        );
    }
    drop(child.stdin.take()); // end of input stops it
    let status = wait_at_most(&mut child, Duration::from_secs(10));
    assert!(status.success());
    assert!(announced.contains("exp1.dat"), "{announced}");
    assert!(!announced.contains("fixed scan"), "{announced}");
}

#[test]
fn noise_takes_on_off_and_default_everywhere() {
    for cmd in ["sim", "scan", "emulate"] {
        let help = text(&robot_app(&[cmd, "-h"]).stdout);
        assert!(help.contains("[possible values: on, off]"), "{cmd}: {help}");
        let o = robot_app(&[cmd, "--noise", "loud"]);
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        assert!(text(&o.stderr).contains("--noise"), "{cmd}");
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for value in ["on", "default", "off"] {
        let o = robot_app(&["-q", "scan", "--sim", "--noise", value]);
        assert!(
            o.status.success(),
            "scan --noise {value}: {}",
            text(&o.stderr)
        );
        let o = robot_app(&["-q", "sim", "--noise", value, "--out", out]);
        assert!(
            o.status.success(),
            "sim --noise {value}: {}",
            text(&o.stderr)
        );
    }
    // `default` is `on`: the same scans for the same seed, and not those without noise.
    let scan = |v: &str| robot_app(&["-q", "scan", "--sim", "--noise", v, "--seed", "3"]).stdout;
    assert_eq!(scan("default"), scan("on"));
    assert_ne!(scan("off"), scan("on"));
}

#[test]
fn numeric_options_out_of_range_are_refused_by_name() {
    let log = "/nonexistent.log";
    for (args, option) in [
        (vec!["scan", "--sim", "--count", "0"], "--count"),
        (vec!["scan", "--sim", "--count=-3"], "--count"),
        (vec!["replay", log, "--rate=-1"], "--rate"),
        (vec!["replay", log, "--rate", "inf"], "--rate"),
        (vec!["replay", log, "--count", "0"], "--count"),
    ] {
        let o = robot_app(&args);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("invalid value") && err.contains(option),
            "{args:?}: {err}"
        );
    }
}

/// Sends SIGINT to `child`, as Ctrl-C in its terminal does.
fn sigint(child: &Child) {
    let pid = nix::unistd::Pid::from_raw(i32::try_from(child.id()).expect("a pid"));
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).expect("the signal is sent");
}
