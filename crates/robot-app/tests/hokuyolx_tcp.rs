//! `robot-app emulate --model ust-10lx --tcp` opened by a client nobody here wrote: the PyPI
//! driver `hokuyolx` (Python, for Ethernet Hokuyos), through `tests/tools/hokuyolx_client.py`.
//! Skipped with a notice when python3 lacks hokuyolx, except under CI (`CI` set), where a
//! missing hokuyolx fails the test.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use urg_driver::{FixedSource, Model, Profile};

/// Kills the emulator when the test ends, however it ends.
struct Emulator(Child);

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn hokuyolx_available() -> bool {
    Command::new("python3")
        .args(["-c", "import hokuyolx"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// CPU time (user + system) of process `pid` so far, in clock ticks (Linux only).
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split(' ').collect();
    // Fields 14 and 15 of proc(5) (utime, stime) are 11 and 12 after the name and state.
    Some(fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?)
}

/// Runs the client script against `port`, failing after 60 s.
fn run_client(port: u16) -> serde_json::Value {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/tools/hokuyolx_client.py"
    );
    let mut child = Command::new("python3")
        .args([script, "127.0.0.1", &port.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    let started = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if started.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the hokuyolx client did not finish in 60 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().expect("client output");
    assert!(
        out.status.success(),
        "hokuyolx client failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the client prints one JSON object")
}

fn ints(v: &serde_json::Value) -> Vec<u64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_u64().expect("integer"))
        .collect()
}

#[test]
#[allow(clippy::print_stderr)] // the skip notice goes to the terminal
fn hokuyolx_reads_the_emulated_ust_10lx_over_tcp() {
    if !hokuyolx_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 cannot import hokuyolx (pip install hokuyolx)"
        );
        eprintln!("skipped: python3 lacks hokuyolx (pip install hokuyolx); CI would fail here");
        return;
    }
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .args([
            "-q",
            "emulate",
            "--model",
            "ust-10lx",
            "--no-stdin",
            "--tcp",
        ])
        .arg(format!("127.0.0.1:{port}"))
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("robot-app runs");
    let stdout = child.stdout.take().unwrap();
    let emulator = Emulator(child);
    let mut line = String::new();
    BufReader::new(stdout).read_line(&mut line).unwrap();
    assert_eq!(line.trim(), format!("tcp:127.0.0.1:{port}"));

    let out = run_client(port);

    // PP as hokuyolx parsed it: the UST-10LX's 1081 steps over 270 deg at 2400 rpm.
    let pp = &out["params"];
    for (key, value) in [
        ("AMIN", 0),
        ("AMAX", 1080),
        ("AFRT", 540),
        ("ARES", 1440),
        ("SCAN", 2400),
        ("DMIN", 20),
        ("DMAX", 30000),
    ] {
        assert_eq!(pp[key], value, "PP {key}");
    }
    assert_eq!(out["scan_freq"], 40, "2400 rpm is 40 Hz");
    assert_eq!(out["version"]["PROT"], "SCIP 2.0");
    assert_eq!(out["state"]["LASR"], "ON");

    // hokuyolx's own angles: (step - AFRT) * 2 pi / ARES, -135 .. +135 deg.
    assert_eq!(out["angle_count"], 1081);
    let angles: Vec<f64> = out["angles_rad"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_f64().unwrap())
        .collect();
    let q = std::f64::consts::FRAC_PI_4;
    assert!((angles[0] + 3.0 * q).abs() < 1e-9, "{angles:?}");
    assert!(angles[1].abs() < 1e-12, "{angles:?}");
    assert!((angles[2] - 3.0 * q).abs() < 1e-9, "{angles:?}");

    // TM1 in time-adjust mode: the sensor's timer runs forward.
    let tm = ints(&out["tm1_ms"]);
    assert!(tm.windows(2).all(|w| w[0] <= w[1]), "{tm:?}");

    // The ranges are the emulator's: its fixed room, in millimetres, error codes below DMIN.
    let p = Profile::of(Model::Ust10lx);
    let room = {
        use scan_types::LaserSource;
        FixedSource::room(p.params.geometry()).next_scan().unwrap()
    };
    let check = |ranges: &[u64], what: &str| {
        assert_eq!(ranges.len(), 1081, "{what}");
        for (i, (&mm, status)) in ranges.iter().zip(&room.status).enumerate() {
            match status {
                scan_types::RayStatus::Hit => {
                    let expect = (room.ranges_m[i] * 1000.0).round() as u64;
                    assert_eq!(mm, expect, "{what}: step {i}");
                }
                scan_types::RayStatus::Error(code) => {
                    assert_eq!(mm, u64::from(*code), "{what}: step {i}")
                }
                _ => assert_eq!(mm, 0, "{what}: step {i} (no return is code 0)"),
            }
        }
    };
    let singles = out["single"].as_array().unwrap();
    assert_eq!(singles.len(), 2);
    for (k, s) in singles.iter().enumerate() {
        check(&ints(&s["ranges_mm"]), &format!("GD scan {k}"));
    }
    // Step 540 is straight ahead: the wall 3 m away; step 180 (-90 deg) is error code 7.
    let first = ints(&singles[0]["ranges_mm"]);
    assert_eq!((first[540], first[180]), (3000, 7));
    let t0 = singles[0]["timestamp_ms"].as_u64().unwrap();
    let t1 = singles[1]["timestamp_ms"].as_u64().unwrap();
    assert!(t1 > t0, "single scans {t0} then {t1}");

    // MD with a count of 5: the echo counts the scans still to come, 4 down to 0, and the
    // stamps are one 25 ms revolution apart.
    let stream = out["stream"].as_array().unwrap();
    assert_eq!(stream.len(), 5);
    let pending: Vec<u64> = stream
        .iter()
        .map(|s| s["pending"].as_u64().unwrap())
        .collect();
    assert_eq!(pending, [4, 3, 2, 1, 0]);
    let stamps: Vec<u64> = stream
        .iter()
        .map(|s| s["timestamp_ms"].as_u64().unwrap())
        .collect();
    assert!(stamps.windows(2).all(|w| w[1] - w[0] == 25), "{stamps:?}");
    assert!(
        stamps[0] > t1,
        "streamed after the single scans: {stamps:?}"
    );
    for (k, s) in stream.iter().enumerate() {
        check(&ints(&s["ranges_mm"]), &format!("MD scan {k}"));
    }

    // The client has gone: the server idles without spinning (under 0.3 s of CPU in 1 s)...
    let pid = emulator.0.id();
    if let Some(before) = cpu_ticks(pid) {
        std::thread::sleep(Duration::from_secs(1));
        let used = cpu_ticks(pid).unwrap() - before;
        assert!(
            used < 30,
            "the idle emulator used {used} clock ticks in 1 s"
        );
    }
    // ...and serves the next client.
    let again = run_client(port);
    assert_eq!(again["angle_count"], 1081);
    assert_eq!(again["stream"].as_array().unwrap().len(), 5);
}
