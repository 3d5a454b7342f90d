//! `robot-app info`, `scan` and `emulate` against the emulator on a pseudo-terminal.

use robot_app::cmd::Noise;
use robot_app::cmd::emulate::{self, EmulateArgs};
use robot_app::cmd::info::{self, InfoArgs};
use robot_app::cmd::scan::{self, ScanArgs, ScanFormat};
use scan_types::{LaserSource, RayStatus};
use urg_driver::{FixedSource, Model, Profile, serve_pty};

fn scan_args(port: Option<String>, format: ScanFormat, count: usize) -> ScanArgs {
    ScanArgs {
        port,
        count,
        format,
        stream: false,
        sim: false,
        world: None,
        pose: None,
        sensor: "paper".into(),
        seed: 0,
        noise: Noise::Off,
        record: None,
        profile: Default::default(),
    }
}

#[test]
fn info_prints_vv_pp_ii() {
    let p = Profile::of(Model::Urg04lx);
    let server = serve_pty(p.clone(), FixedSource::room(p.params.geometry())).unwrap();
    let mut out = Vec::new();
    info::run_to(
        &InfoArgs {
            port: server.path().to_string(),
        },
        &mut out,
    )
    .unwrap();
    let text = String::from_utf8(out).unwrap();
    for needle in [
        "SERI  H0706400",
        "FIRM  3.1.04(02/Aug./2007)",
        "AFRT  step 384 (straight ahead)",
        "SCAN  600 rpm (100 ms per scan)",
        "682 rays from -119.531 to 119.883 deg",
        "STAT  Sensor works well.",
        "LASR  ",
    ] {
        assert!(text.contains(needle), "{needle:?} missing from:\n{text}");
    }
}

#[test]
fn scan_writes_csv_and_json() {
    let p = Profile::of(Model::Urg04lx);
    let server = serve_pty(p.clone(), FixedSource::room(p.params.geometry())).unwrap();
    let mut out = Vec::new();
    scan::run_to(
        &scan_args(Some(server.path().into()), ScanFormat::Csv, 1),
        &mut out,
    )
    .unwrap();
    let (g, s) = scan_log::read_scan_csv(&out[..], "scan output").unwrap();
    assert_eq!(g.ray_count, 682);
    assert_eq!(s.ranges_m[340], 3.0);
    assert_eq!(
        s.status[84],
        RayStatus::Error(0),
        "invalid rays read back as invalid"
    );

    let mut out = Vec::new();
    let mut args = scan_args(Some(server.path().into()), ScanFormat::Json, 3);
    args.stream = true;
    scan::run_to(&args, &mut out).unwrap();
    let lines: Vec<serde_json::Value> = String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    assert_eq!(lines[0]["ranges_m"][340], 3.0);
    assert_eq!(lines[0]["status"][84], "error:7");
    assert!(lines[0]["ranges_m"][84].is_null());
    let t0 = lines[0]["sensor_time_ms"].as_u64().unwrap();
    let t1 = lines[1]["sensor_time_ms"].as_u64().unwrap();
    assert_eq!(t1 - t0, 100);
}

#[test]
fn scan_sim_and_emulate_sim_agree() {
    // The simulator seen directly and through the emulated URG-04LX on a pty, both at the
    // paper's start (the emulator's default pose).
    let mut direct =
        robot_app::simsetup::sim_scan_source(None, sim_laser::paper_start(), "urg-04lx", 0, false)
            .unwrap();
    let want = direct.next_scan().unwrap();
    let server = emulate::start(&EmulateArgs {
        model: Model::Urg04lx,
        scip1: true,
        sim: true,
        world: None,
        pose: None,
        seed: 0,
        noise: Noise::Off,
        no_stdin: true,
        source: None,
        topic: None,
        tcp: None,
    })
    .unwrap();
    let mut out = Vec::new();
    scan::run_to(
        &scan_args(Some(server.location()), ScanFormat::Csv, 1),
        &mut out,
    )
    .unwrap();
    let (g, got) = scan_log::read_scan_csv(&out[..], "scan output").unwrap();
    assert_eq!(g.ray_count, direct.geometry().ray_count);
    let mut hits = 0;
    for i in 0..g.ray_count {
        match (want.status[i], got.status[i]) {
            (RayStatus::Hit, RayStatus::Hit) => {
                // Millimetre resolution on the wire.
                assert!(
                    (want.ranges_m[i] - got.ranges_m[i]).abs() <= 0.0005 + 1e-12,
                    "ray {i}"
                );
                hits += 1;
            }
            (a, b) => assert_eq!(
                a == RayStatus::Hit,
                b == RayStatus::Hit,
                "ray {i}: {a:?} vs {b:?}"
            ),
        }
    }
    assert!(hits > 100, "{hits} hits");

    // `scan --sim` gives the simulator's scan without any device.
    let mut args = scan_args(None, ScanFormat::Csv, 1);
    args.sim = true;
    args.sensor = "urg-04lx".into();
    args.pose = None; // the paper's start
    let mut out = Vec::new();
    scan::run_to(&args, &mut out).unwrap();
    let (_, sim) = scan_log::read_scan_csv(&out[..], "sim output").unwrap();
    for i in 0..g.ray_count {
        if want.status[i] == RayStatus::Hit {
            assert!((sim.ranges_m[i] - want.ranges_m[i]).abs() < 1e-5, "ray {i}");
        }
    }
}
