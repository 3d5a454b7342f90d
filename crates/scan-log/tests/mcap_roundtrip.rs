//! goalseek MCAP recordings read back bit for bit; cut and dropped recordings.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_log::{LogOptions, LogSource, McapRecorder, partial_path, read_mcap};
use scan_types::{LaserSource, Pose2, RayStatus, Scan, ScanGeometry};

/// Random scans with awkward f64 values (no short decimal form), every ray status, intensities.
fn scans(
    n: usize,
    geometry: &ScanGeometry,
    seed: u64,
) -> Vec<(Scan, Option<Pose2>, Option<Pose2>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let mut ranges = Vec::new();
            let mut status = Vec::new();
            for _ in 0..geometry.ray_count {
                match rng.random_range(0..10) {
                    0 => {
                        ranges.push(geometry.max_range_m);
                        status.push(RayStatus::MaxRange);
                    }
                    1 => {
                        ranges.push(f64::NAN);
                        status.push(RayStatus::Error(rng.random_range(0..20)));
                    }
                    _ => {
                        ranges.push(rng.random::<f64>() * geometry.max_range_m);
                        status.push(RayStatus::Hit);
                    }
                }
            }
            let scan = Scan {
                ranges_m: ranges,
                status,
                intensities: (k % 2 == 0).then(|| {
                    (0..geometry.ray_count)
                        .map(|_| rng.random::<f32>() * 1e4)
                        .collect()
                }),
                sensor_time_ms: (k % 3 != 0).then(|| rng.random::<u64>() >> 12),
                host_time_s: 1.7e9 + rng.random::<f64>() * 1e3,
            };
            let pose = |rng: &mut ChaCha8Rng| {
                Pose2::new(
                    rng.random::<f64>() * 10.0 - 5.0,
                    rng.random::<f64>() * 0.1,
                    rng.random::<f64>() * 6.0 - 3.0,
                )
            };
            let t = (k % 4 != 1).then(|| pose(&mut rng));
            let e = (k % 4 != 2).then(|| pose(&mut rng));
            (scan, t, e)
        })
        .collect()
}

fn same_scan(a: &Scan, b: &Scan) {
    assert_eq!(a.status, b.status);
    for (x, y) in a.ranges_m.iter().zip(&b.ranges_m) {
        assert!(
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
            "{x} vs {y}"
        );
    }
    assert_eq!(
        a.intensities
            .as_ref()
            .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
        b.intensities
            .as_ref()
            .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
    );
    assert_eq!(a.sensor_time_ms, b.sensor_time_ms);
    assert_eq!(a.host_time_s.to_bits(), b.host_time_s.to_bits());
}

fn bits(p: Option<Pose2>) -> Option<[u64; 3]> {
    p.map(|p| [p.x_m.to_bits(), p.y_m.to_bits(), p.theta_rad.to_bits()])
}

#[test]
fn recording_reads_back_bit_for_bit() {
    let g = ScanGeometry::new(
        -2.0862 + 1e-13,
        std::f64::consts::TAU / 1024.0,
        37,
        0.02,
        5.6,
    )
    .unwrap();
    let data = scans(40, &g, 7);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    assert!(partial_path(&path).exists() && !path.exists());
    for (s, t, e) in &data {
        rec.record_scan(&g, s, *t, *e).unwrap();
    }
    assert_eq!(rec.finish().unwrap(), 40);
    assert!(path.exists() && !partial_path(&path).exists());

    let back: Vec<_> = read_mcap(&path)
        .unwrap()
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(back.len(), 40);
    for (r, (s, t, e)) in back.iter().zip(&data) {
        assert_eq!(r.geometry, g);
        same_scan(&r.scan, s);
        assert_eq!(bits(r.true_pose), bits(*t));
        assert_eq!(bits(r.pose), bits(*e));
    }

    // And as a LaserSource.
    let mut src = LogSource::open(&path, &LogOptions::default()).unwrap();
    assert_eq!(*src.geometry(), g);
    for (s, t, e) in &data {
        same_scan(&src.next_scan().unwrap(), s);
        assert_eq!(bits(src.true_pose()), bits(*t));
        assert_eq!(bits(src.pose()), bits(*e));
    }
    assert!(src.next_scan().unwrap_err().is_end_of_log());
}

#[test]
fn foxglove_fields_are_there() {
    let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fox.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    let scan = Scan::from_ranges(&g, &[1.5, 4.0, f64::NAN], 12.25);
    rec.record_scan(&g, &scan, None, Some(Pose2::new(1.0, 2.0, 0.5)))
        .unwrap();
    rec.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let names: Vec<_> = summary
        .schemas
        .values()
        .map(|s| (s.name.clone(), s.encoding.clone()))
        .collect();
    assert!(
        names.contains(&("foxglove.LaserScan".into(), "jsonschema".into())),
        "{names:?}"
    );
    assert!(
        names.contains(&("foxglove.PoseInFrame".into(), "jsonschema".into())),
        "{names:?}"
    );
    let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(msgs.len(), 2);
    assert_eq!(msgs[0].log_time, 12_250_000_000);
    let v: serde_json::Value = serde_json::from_slice(&msgs[0].data).unwrap();
    assert_eq!(v["timestamp"]["sec"], 12);
    assert_eq!(v["timestamp"]["nsec"], 250_000_000);
    assert_eq!(v["frame_id"], "map");
    assert_eq!(v["start_angle"], -0.5);
    assert_eq!(v["end_angle"], 0.5);
    assert_eq!(v["ranges"], serde_json::json!([1.5, 4.0, 0.0]));
    assert_eq!(v["pose"]["position"]["x"], 1.0);
    assert!((v["pose"]["orientation"]["z"].as_f64().unwrap() - 0.25f64.sin()).abs() < 1e-15);
    assert_eq!(msgs[1].channel.topic, "/pose_estimate");
}

#[test]
fn dropped_recorder_still_leaves_a_readable_file() {
    let g = ScanGeometry::centred(5, 1.0, 0.0, 4.0).unwrap();
    let data = scans(6, &g, 3);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dropped.mcap");
    {
        let mut rec = McapRecorder::create(&path).unwrap();
        for (s, t, e) in &data[..4] {
            rec.record_scan(&g, s, *t, *e).unwrap();
        }
    }
    let back: Vec<_> = read_mcap(&path)
        .unwrap()
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(back.len(), 4);
}

#[test]
fn a_cut_recording_gives_its_scans_then_an_error() {
    let g = ScanGeometry::centred(5, 1.0, 0.0, 4.0).unwrap();
    let data = scans(10, &g, 5);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("whole.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    for (s, t, e) in &data {
        rec.record_scan(&g, s, *t, *e).unwrap();
    }
    rec.finish().unwrap();
    // Simulate a crash: a file cut in the data section, as `<name>.partial` would be.
    let bytes = std::fs::read(&path).unwrap();
    let cut_path = dir.path().join("crash.mcap.partial");
    // Cut at 60 % of the data: well inside the chunks, before the summary.
    std::fs::write(&cut_path, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let items = read_mcap(&cut_path).unwrap();
    let ok: Vec<_> = items.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert!(ok.len() >= 3 && ok.len() < 10, "{} scans", ok.len());
    for (r, (s, _, _)) in ok.iter().zip(&data) {
        same_scan(&r.scan, s);
    }
    let err = items.last().unwrap().as_ref().unwrap_err().to_string();
    assert!(err.contains("crash.mcap.partial"), "{err}");
    // The source reads the whole scans and counts the damage.
    let mut src = LogSource::open(&cut_path, &LogOptions::default()).unwrap();
    let mut n = 0;
    while src.next_scan().is_ok() {
        n += 1;
    }
    assert_eq!((n, src.skipped()), (ok.len(), 1));
}

/// The JSON types `schema` declares for `v` (the `type`, `properties` and `items` keywords,
/// enough for the recording's schemas), as a list of mismatches.
fn type_errors(schema: &serde_json::Value, v: &serde_json::Value, at: &str, out: &mut Vec<String>) {
    use serde_json::Value;
    let ok = |t: &str| match t {
        "object" => v.is_object(),
        "array" => v.is_array(),
        "string" => v.is_string(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64(),
        "boolean" => v.is_boolean(),
        "null" => v.is_null(),
        _ => false,
    };
    let fits = match schema.get("type") {
        Some(Value::String(t)) => ok(t),
        Some(Value::Array(ts)) => ts.iter().filter_map(Value::as_str).any(ok),
        _ => true,
    };
    if !fits {
        out.push(format!("{at}: {v} is not {}", schema["type"]));
    }
    if let (Some(Value::Object(props)), Value::Object(fields)) = (schema.get("properties"), v) {
        for (k, sub) in props {
            if let Some(x) = fields.get(k) {
                type_errors(sub, x, &format!("{at}.{k}"), out);
            }
        }
    }
    if let (Some(items), Value::Array(xs)) = (schema.get("items"), v) {
        for (i, x) in xs.iter().enumerate() {
            type_errors(items, x, &format!("{at}[{i}]"), out);
        }
    }
}

#[test]
fn every_message_matches_its_embedded_schema() {
    // Scans with and without a sensor time stamp (a CARMEN or BreezySLAM replay has none),
    // with a dropped reading, with and without poses.
    let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    let mut stamped = Scan::from_ranges(&g, &[1.5, 4.0, f64::NAN], 1.0);
    stamped.sensor_time_ms = Some(1000);
    let unstamped = Scan::from_ranges(&g, &[1.0, 2.0, 3.0], 2.0);
    rec.record_scan(
        &g,
        &stamped,
        Some(Pose2::new(0.0, 0.0, 0.0)),
        Some(Pose2::new(1.0, 2.0, 0.5)),
    )
    .unwrap();
    rec.record_scan(&g, &unstamped, None, None).unwrap();
    rec.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut checked = 0;
    let mut errors = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        let schema: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        type_errors(&schema, &v, &m.channel.topic, &mut errors);
        checked += 1;
    }
    assert!(checked >= 4, "{checked} messages");
    assert!(errors.is_empty(), "{errors:#?}");
}

/// A recording written before the keys named their units: poses on `/pose/estimated` and
/// `/pose/true` in frame `world` with `goalseek.theta_rad`, metadata poses as bare arrays and
/// the end reason as a bare word. It still reads, to the same values.
#[test]
fn recordings_with_the_old_names_still_read() {
    let g = ScanGeometry::centred(5, 1.0, 0.0, 4.0).unwrap();
    let data = scans(3, &g, 11);
    let dir = tempfile::tempdir().unwrap();
    let new = dir.path().join("new.mcap");
    let mut rec = McapRecorder::create(&new).unwrap();
    for (s, t, e) in &data {
        rec.record_scan(&g, s, *t, *e).unwrap();
    }
    rec.finish().unwrap();
    let bytes = std::fs::read(&new).unwrap();

    // The same messages under the old names.
    let old = dir.path().join("old.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&old).unwrap(),
    ))
    .unwrap();
    let mut channels = std::collections::BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let (topic, data) = match m.channel.topic.as_str() {
            "/scan" => ("/scan", m.data.to_vec()),
            t => {
                let mut v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
                v["frame_id"] = "world".into();
                let extra = v["goalseek"].as_object_mut().unwrap();
                let h = extra.remove("heading_rad").unwrap();
                extra.insert("theta_rad".into(), h);
                let old = if t == "/pose_truth" {
                    "/pose/true"
                } else {
                    "/pose/estimated"
                };
                (old, serde_json::to_vec(&v).unwrap())
            }
        };
        let schema = m.channel.schema.as_ref().unwrap();
        let id = *channels.entry(topic).or_insert_with(|| {
            let s = w
                .add_schema(&schema.name, &schema.encoding, &schema.data)
                .unwrap();
            w.add_channel(s, topic, "json", &Default::default())
                .unwrap()
        });
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        w.write_to_known_channel(&header, &data).unwrap();
    }
    let run = std::collections::BTreeMap::from([
        ("start".to_string(), "[1.5,-2.0,0.25]".to_string()),
        ("goal".to_string(), "[4.0,4.0]".to_string()),
        ("config".to_string(), "{}".to_string()),
        ("world".to_string(), "\"paper\"".to_string()),
        ("sensor".to_string(), "\"paper\"".to_string()),
        ("seed".to_string(), "3".to_string()),
        ("noise".to_string(), "true".to_string()),
    ]);
    w.write_metadata(&mcap::records::Metadata {
        name: scan_log::RUN_METADATA.into(),
        metadata: run,
    })
    .unwrap();
    let legs = std::collections::BTreeMap::from([
        (
            "legs".to_string(),
            r#"[{"leg":0,"estimate":[1.5,-2.0,0.25],"landmark":null,"point_b":[3.0,1.0]}]"#
                .to_string(),
        ),
        ("reason".to_string(), "reached".to_string()),
    ]);
    w.write_metadata(&mcap::records::Metadata {
        name: scan_log::LEGS_METADATA.into(),
        metadata: legs,
    })
    .unwrap();
    w.finish().unwrap();
    drop(w);

    let got: Vec<_> = read_mcap(&old)
        .unwrap()
        .into_iter()
        .map(|r| r.unwrap())
        .collect();
    assert_eq!(got.len(), data.len());
    for (r, (_, t, e)) in got.iter().zip(&data) {
        assert_eq!(r.true_pose, *t);
        assert_eq!(r.pose, *e);
    }
    let s = scan_log::RunSettings::<serde_json::Value>::read(&old).unwrap();
    assert_eq!(
        (s.start.x_m, s.start.y_m, s.start.theta_rad),
        (1.5, -2.0, 0.25)
    );
    assert_eq!((s.goal.x_m(), s.goal.y_m()), (4.0, 4.0));
    let (reason, legs) = scan_log::read_recorded_legs(&old).unwrap().unwrap();
    assert_eq!(reason, "reached");
    assert_eq!(legs[0].estimate, [1.5, -2.0, 0.25]);
    assert_eq!(legs[0].landmark, None);
    assert_eq!(legs[0].point_b, Some([3.0, 1.0]));

    // The new names: the metadata as objects with unit-named fields, the reason as JSON text.
    let m = scan_log::legs_metadata(&legs, "reached");
    assert_eq!(m["reason"], "\"reached\"");
    assert_eq!(
        m["legs"],
        r#"[{"leg":0,"estimate":{"x_m":1.5,"y_m":-2.0,"heading_rad":0.25},"landmark":null,"point_b":{"x_m":3.0,"y_m":1.0}}]"#
    );
    let again = s.to_metadata();
    assert_eq!(
        again["start"],
        r#"{"x_m":1.5,"y_m":-2.0,"heading_rad":0.25}"#
    );
    assert_eq!(again["goal"], r#"{"x_m":4.0,"y_m":4.0}"#);
}

#[test]
fn an_unknown_topic_names_a_recordings_pose_topics() {
    let g = ScanGeometry::paper();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    for (s, t, e) in scans(3, &g, 1) {
        rec.record_scan(&g, &s, t, e).unwrap();
    }
    rec.finish().unwrap();
    let options = LogOptions {
        topic: Some("/pose_estimate".into()),
        ..LogOptions::default()
    };
    let Err(e) = LogSource::open(&path, &options) else {
        panic!("a pose topic opened as a laser topic");
    };
    let text = e.to_string();
    assert!(
        text.contains(
            "no laser scan topic /pose_estimate (laser topics: /scan; other topics: /pose_truth (goalseek poses of /scan), /pose_estimate (goalseek poses of /scan))"
        ),
        "{text}"
    );
}
