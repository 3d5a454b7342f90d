//! A recording of the simulated paper run, replayed through the loop, reproduces the same legs.
//!
//! The live run records every scan with its true pose and the navigator's estimate; the replay
//! feeds the recorded scans, in order, to the same navigator (same settings, read from the
//! recording) over a base that executes nothing. The loop's decisions depend only on the scans
//! and its settings, so it must give the same commands and the same legs, bit for bit.
#![allow(clippy::print_stderr, clippy::print_stdout)] // tests report to the terminal

use std::path::Path;

use robot_app::cmd::replay::{ReplayArgs, run_to};
use robot_app::cmd::scan::ScanFormat;
use robot_app::cmd::sim::{SimSpec, record_run};
use robot_app::outputs::Reason;
use robot_app::record::{Recorder, RunSettings, replay_loop};
use robot_app::runloop::run_loop;
use robot_base::LoggingBase;
use scan_log::{LEGS_METADATA, RUN_METADATA, read_mcap};
use scan_types::{Pose2, Scan};

fn paper_spec() -> SimSpec {
    SimSpec::paper(0, robot_app::config::load(None, None).unwrap())
}

fn settings_of(spec: &SimSpec) -> RunSettings {
    RunSettings {
        start: spec.setup.start,
        goal: spec.goal,
        config: spec.config.clone(),
        world: spec.setup.world_name.clone(),
        sensor: spec.setup.sensor.name().into(),
        seed: spec.setup.seed,
        noise: spec.setup.noise,
    }
}

fn pose_bits(p: Pose2) -> [u64; 3] {
    [p.x_m.to_bits(), p.y_m.to_bits(), p.theta_rad.to_bits()]
}

fn assert_same_scan(a: &Scan, b: &Scan, k: usize) {
    assert_eq!(a.status, b.status, "scan {k}");
    for (i, (x, y)) in a.ranges_m.iter().zip(&b.ranges_m).enumerate() {
        assert!(
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
            "scan {k} ray {i}: {x} vs {y}"
        );
    }
    assert_eq!(a.intensities, b.intensities, "scan {k}");
    assert_eq!(a.sensor_time_ms, b.sensor_time_ms, "scan {k}");
    assert_eq!(a.host_time_s.to_bits(), b.host_time_s.to_bits(), "scan {k}");
}

fn replay_args(file: std::path::PathBuf) -> ReplayArgs {
    ReplayArgs {
        file,
        rate: 0.0,
        sensor: None,
        topic: None,
        count: None,
        format: ScanFormat::Csv,
        record: None,
        profile: Default::default(),
        through_loop: true,
        out: None,
        live: Default::default(),
    }
}

/// The live run with a recording base, so the commands can be compared too.
#[test]
fn replayed_paper_run_gives_the_same_commands_and_legs() {
    let spec = paper_spec();
    let cfg = &spec.config;
    // The paper's setup: noise on, the configuration's robot radius.
    let sim = spec.setup.build().unwrap();
    let geometry = spec.setup.sensor.geometry();
    let (mut laser, base, truth) = sim.split();
    let mut base = LoggingBase::new(base);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("paper.mcap");
    let mut rec = Recorder::create(&path, &geometry).unwrap();
    rec.write_metadata(RUN_METADATA, &settings_of(&spec).to_metadata())
        .unwrap();
    let mut written: Vec<(Scan, Pose2, Pose2)> = Vec::new();
    let mut hook = |s: &Scan, e: &Pose2| {
        let t = truth.pose();
        rec.record_scan(&geometry, s, Some(t), Some(*e)).unwrap();
        written.push((s.clone(), t, *e));
    };
    let live_run = run_loop(
        &mut laser,
        &mut base,
        cfg,
        (spec.setup.start, spec.goal),
        Some(&truth),
        Some(&mut hook),
    )
    .unwrap();
    let live = &live_run.outcome;
    rec.finish().unwrap();
    // A collision ends a live run on the simulator's count, which a recording does not hold.
    assert_ne!(live.reason, Reason::Collision, "{}", live.note);
    assert!(live.legs_driven >= 2, "{} legs", live.legs_driven);
    assert_eq!(written.len(), live.scans);
    check_recording(&path, &written, spec.setup.start, live.legs_driven);

    // Replay through the loop.
    let replay = replay_loop(&path, cfg, spec.setup.start, spec.goal).unwrap();
    let r = &replay.run.outcome;
    assert_eq!(replay.commands, base.commands, "commanded motion");
    assert_eq!(r.reason, live.reason);
    assert_eq!(r.legs_driven, live.legs_driven);
    assert_eq!(r.scans, live.scans);
    assert_eq!(replay.scans_read, live.scans);
    assert_eq!(replay.scans_left, 0);
    assert_eq!(r.path_length_m.to_bits(), live.path_length_m.to_bits());
    assert_eq!(pose_bits(r.estimate), pose_bits(live.estimate));
    assert_eq!(r.first_leg, live.first_leg);
    // Every leg: estimate, recorded truth, landmark, point B and the scan's world points.
    assert_eq!(replay.run.log, live_run.log);
}

/// The recording at `path` reads back bit for bit (scans, true poses, estimates) as `written`,
/// starts at `start`, and carries a new estimate at nearly every scan.
fn check_recording(path: &Path, written: &[(Scan, Pose2, Pose2)], start: Pose2, legs: usize) {
    let back: Vec<_> = read_mcap(path)
        .unwrap()
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(back.len(), written.len());
    for (k, (r, (s, t, e))) in back.iter().zip(written).enumerate() {
        assert_same_scan(&r.scan, s, k);
        assert_eq!(r.true_pose.map(pose_bits), Some(pose_bits(*t)), "scan {k}");
        assert_eq!(r.pose.map(pose_bits), Some(pose_bits(*e)), "scan {k}");
    }
    // The first scan is taken at the start, where estimate and truth agree.
    assert_eq!(pose_bits(written[0].1), pose_bits(start));
    assert_eq!(pose_bits(written[0].2), pose_bits(start));
    // The estimate follows the robot between leg ends (moved by each command), so nearly
    // every scan carries a new estimate.
    let distinct = written.windows(2).filter(|w| w[0].2 != w[1].2).count();
    assert!(
        distinct * 10 >= written.len() * 9,
        "{distinct} of {}",
        written.len()
    );
    let worst = written
        .iter()
        .map(|(_, t, e)| t.position().distance_m(&e.position()))
        .fold(0.0, f64::max);
    println!(
        "{} scans, {legs} legs; worst estimate error at a scan {worst:.3} m",
        written.len()
    );
}

/// The `robot-app sim --record` path and `robot-app replay FILE --loop`.
#[test]
fn sim_record_then_replay_loop_reports_the_same_legs() {
    let spec = paper_spec();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("paper.mcap");
    let live = record_run(&spec, &path).unwrap();
    assert_ne!(
        live.summary.reason,
        Reason::Collision,
        "{}",
        live.summary.note
    );
    assert_eq!(RunSettings::read(&path).unwrap(), settings_of(&spec));

    let records: Vec<_> = read_mcap(&path)
        .unwrap()
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(records.len(), live.outcome.scans);
    assert!(
        records
            .iter()
            .all(|r| r.pose.is_some() && r.true_pose.is_some())
    );
    // The true pose of the scan a leg ended on is the truth the run logged for that leg.
    let last = records.last().unwrap();
    let logged = live.log.legs.last().unwrap();
    assert_eq!(last.true_pose, logged.truth);

    let mut out = Vec::new();
    run_to(&replay_args(path.clone()), &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    println!("{text}");
    assert!(text.contains("same legs as recorded"), "{text}");
    assert!(
        text.contains(&format!("{} scans read, 0 left", records.len())),
        "{text}"
    );

    // A recording whose legs differ in one bit is reported as different.
    let mut legs = live.log.leg_summaries();
    let b = legs.iter_mut().find_map(|l| l.point_b.as_mut()).unwrap();
    b[0] = f64::from_bits(b[0].to_bits() + 1);
    let bad = dir.path().join("bad.mcap");
    let mut rec = Recorder::create(&bad, &records[0].geometry).unwrap();
    rec.write_metadata(RUN_METADATA, &settings_of(&spec).to_metadata())
        .unwrap();
    for r in &records {
        rec.record_scan(&r.geometry, &r.scan, r.true_pose, r.pose)
            .unwrap();
    }
    let m = std::collections::BTreeMap::from([
        ("legs".to_string(), serde_json::to_string(&legs).unwrap()),
        ("reason".to_string(), "reached".to_string()),
    ]);
    rec.write_metadata(LEGS_METADATA, &m).unwrap();
    rec.finish().unwrap();
    let err = run_to(&replay_args(bad), &mut Vec::new()).unwrap_err();
    assert!(err.to_string().contains("differ"), "{err:#}");
}
