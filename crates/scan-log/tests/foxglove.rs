//! What Foxglove needs to open a recording as it is, checked without the app:
//! schema names and encodings, the field names and types of Foxglove's `LaserScan` and
//! `PoseInFrame`, schemas its JSON-schema reader accepts, and the MCAP summary.

use std::collections::BTreeMap;

use scan_log::{McapRecorder, read_mcap_metadata, recording_schemas};
use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};
use serde_json::Value;

/// The fields of Foxglove's schemas (docs.foxglove.dev, "Message schemas": LaserScan,
/// PoseInFrame, Pose, Vector3, Quaternion, Time) and their JSON types.
fn foxglove_fields(schema: &str) -> Vec<(&'static str, &'static str)> {
    let mut f = vec![
        ("timestamp", "object"),
        ("timestamp.sec", "integer"),
        ("timestamp.nsec", "integer"),
        ("frame_id", "string"),
        ("pose", "object"),
        ("pose.position", "object"),
        ("pose.position.x", "number"),
        ("pose.position.y", "number"),
        ("pose.position.z", "number"),
        ("pose.orientation", "object"),
        ("pose.orientation.x", "number"),
        ("pose.orientation.y", "number"),
        ("pose.orientation.z", "number"),
        ("pose.orientation.w", "number"),
    ];
    if schema == "foxglove.LaserScan" {
        f.extend([
            ("start_angle", "number"),
            ("end_angle", "number"),
            ("ranges", "array"),
            ("intensities", "array"),
        ]);
    }
    f
}

/// Walks a JSON schema the way Foxglove's reader does: every object must list `properties`,
/// only boolean/string/number/integer/object/array types, arrays of those. Returns
/// `path -> type` for every declared field.
fn walk(schema: &Value, prefix: &str, out: &mut BTreeMap<String, String>) {
    assert_eq!(schema["type"], "object", "{prefix}: not an object");
    let props = schema["properties"].as_object().unwrap_or_else(|| {
        panic!("{prefix}: an object without 'properties' (Foxglove rejects it)")
    });
    for (name, field) in props {
        let path = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        let ty = field["type"]
            .as_str()
            .unwrap_or_else(|| panic!("{path}: 'type' must be one string"));
        match ty {
            "boolean" | "string" | "number" | "integer" => {}
            "object" => walk(field, &path, out),
            "array" => {
                let item = field["items"]["type"].as_str().unwrap();
                assert!(
                    ["boolean", "string", "number", "integer"].contains(&item),
                    "{path}: array of {item}"
                );
            }
            other => panic!("{path}: type {other} is not read by Foxglove"),
        }
        out.insert(path, ty.to_string());
    }
}

/// Every field of a message value with its JSON type; `null` values are skipped.
fn message_fields(v: &Value, prefix: &str, out: &mut BTreeMap<String, String>) {
    for (name, field) in v.as_object().unwrap() {
        let path = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        let ty = match field {
            Value::Null => continue,
            Value::Bool(_) => "boolean",
            Value::String(_) => "string",
            Value::Number(n) if n.is_u64() || n.is_i64() => "integer",
            Value::Number(_) => "number",
            Value::Array(_) => "array",
            Value::Object(_) => {
                message_fields(field, &path, out);
                "object"
            }
        };
        out.insert(path, ty.to_string());
    }
}

fn recording() -> (tempfile::TempDir, std::path::PathBuf) {
    let g = ScanGeometry::centred(5, 1.0, 0.1, 4.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fox.mcap");
    let mut rec = McapRecorder::create(&path).unwrap();
    let mut meta = BTreeMap::new();
    meta.insert("seed".to_string(), "7".to_string());
    rec.write_metadata("goalseek.run", &meta).unwrap();
    for k in 0..3 {
        let mut scan = Scan::from_ranges(&g, &[1.5, 4.0, 2.0, 0.5, 3.25], 10.0 + k as f64);
        scan.status[3] = RayStatus::Error(7);
        scan.ranges_m[3] = f64::NAN;
        scan.intensities = Some(vec![1.0, 2.0, 3.0, 4.0, 5.0]);
        scan.sensor_time_ms = (k != 1).then_some(1000 + k);
        let t = Pose2::new(1.0, 2.0, 0.5);
        let e = Pose2::new(1.1, 2.1, 0.4);
        rec.record_scan(&g, &scan, Some(t), Some(e)).unwrap();
    }
    rec.finish().unwrap();
    (dir, path)
}

#[test]
fn schemas_are_foxglove_schemas_its_json_reader_accepts() {
    for (name, text) in recording_schemas() {
        let schema: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(schema["title"], name);
        let mut declared = BTreeMap::new();
        walk(&schema, "", &mut declared);
        for (field, ty) in foxglove_fields(name) {
            assert_eq!(
                declared.get(field).map(String::as_str),
                Some(ty),
                "{name}.{field}"
            );
        }
        assert_eq!(schema["properties"]["timestamp"]["title"], "time");
    }
}

#[test]
fn every_message_field_is_declared_with_its_type() {
    let (_dir, path) = recording();
    let bytes = std::fs::read(&path).unwrap();
    let schemas: BTreeMap<_, _> = recording_schemas()
        .into_iter()
        .map(|(n, t)| {
            let mut declared = BTreeMap::new();
            walk(&serde_json::from_str(&t).unwrap(), "", &mut declared);
            (n.to_string(), declared)
        })
        .collect();
    let mut seen = 0;
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let schema = msg.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "jsonschema");
        assert_eq!(msg.channel.message_encoding, "json");
        let declared = &schemas[&schema.name];
        let v: Value = serde_json::from_slice(&msg.data).unwrap();
        assert!(
            v.get("header").is_none(),
            "Foxglove would take it for a ROS message"
        );
        let mut fields = BTreeMap::new();
        message_fields(&v, "", &mut fields);
        for (field, ty) in &fields {
            let d = declared
                .get(field)
                .unwrap_or_else(|| panic!("{}: {field} not in the schema", schema.name));
            // An integer value is a valid JSON number.
            assert!(
                d == ty || (d == "number" && ty == "integer"),
                "{field}: {d} vs {ty}"
            );
        }
        seen += 1;
    }
    assert_eq!(seen, 9, "3 scans, 3 true poses, 3 estimated poses");
}

#[test]
fn the_file_has_the_summary_foxglove_seeks_with() {
    let (_dir, path) = recording();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(mcap::MAGIC) && bytes.ends_with(mcap::MAGIC));
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a summary section");
    let stats = summary.stats.expect("statistics");
    assert_eq!(stats.message_count, 9);
    assert_eq!(stats.channel_count, 3);
    assert_eq!(stats.schema_count, 2);
    assert_eq!(stats.metadata_count, 1);
    assert_eq!(stats.message_start_time, 10_000_000_000);
    assert_eq!(stats.message_end_time, 12_000_000_000);
    // Chunk indexes with message indexes let a player seek without reading the whole file.
    let with_messages: Vec<_> = summary
        .chunk_indexes
        .iter()
        .filter(|c| !c.message_index_offsets.is_empty())
        .collect();
    assert_eq!(with_messages.len(), 3, "{:?}", summary.chunk_indexes);
    assert!(
        with_messages
            .iter()
            .all(|c| c.message_index_offsets.len() == 3)
    );
    let mut topics: Vec<_> = summary.channels.values().map(|c| c.topic.clone()).collect();
    topics.sort();
    assert_eq!(topics, ["/pose_estimate", "/pose_truth", "/scan"]);
    let meta = read_mcap_metadata(&path).unwrap();
    assert_eq!(meta.len(), 1);
    assert_eq!(meta[0].0, "goalseek.run");
    assert_eq!(meta[0].1["seed"], "7");
}
