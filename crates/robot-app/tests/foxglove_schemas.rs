//! goalseek's default recording against the official Foxglove JSON schemas (npm
//! `@foxglove/schemas`, installed in `tests/tools` by `npm ci`): every message of a `sim`
//! recording validates (PyPI `jsonschema`, `mcap`), and the schemas embedded in the file carry
//! every official property with its type. Skipped with a notice when node, the npm package or the
//! Python packages are missing, except under CI (`CI` set), where that fails the test.

use std::path::Path;
use std::process::{Command, Stdio};

use serde_json::Value;

#[path = "common/python.rs"]
mod python;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");
const TOOLS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/tools");

fn tools_available() -> bool {
    let node = Path::new(TOOLS)
        .join("node_modules/@foxglove/schemas/package.json")
        .is_file()
        && Command::new("node")
            .arg("--version")
            .stdout(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
    node && python::imports("jsonschema, mcap.reader")
}

#[test]
#[allow(clippy::print_stdout)]
fn a_recording_validates_against_the_official_foxglove_schemas() {
    if !tools_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but the schema check's tools are missing (npm ci --prefix tests/tools; pip install jsonschema mcap)"
        );
        println!(
            "skipped: needs node with tests/tools/node_modules (npm ci --prefix tests/tools) and python3 with jsonschema and mcap"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("run.mcap");
    let out = dir.path().join("out");
    let o = Command::new(BIN)
        .args(["-q", "sim", "--seed", "2", "--record"])
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let scans = summary["scans"].as_u64().unwrap();

    let schemas = Command::new("node")
        .arg(Path::new(TOOLS).join("foxglove_schemas.cjs"))
        .args(["foxglove.LaserScan", "foxglove.PoseInFrame"])
        .output()
        .expect("node runs");
    assert!(
        schemas.status.success(),
        "{}",
        String::from_utf8_lossy(&schemas.stderr)
    );
    let schemas_file = dir.path().join("schemas.json");
    std::fs::write(&schemas_file, &schemas.stdout).unwrap();
    let check = Command::new("python3")
        .arg(Path::new(TOOLS).join("foxglove_schema_check.py"))
        .arg(&rec)
        .arg(&schemas_file)
        .output()
        .expect("python3 runs");
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let report: Value = serde_json::from_slice(&check.stdout).unwrap();
    println!("{report}");
    for (topic, schema) in [
        ("/scan", "foxglove.LaserScan"),
        ("/pose_estimate", "foxglove.PoseInFrame"),
        ("/pose_truth", "foxglove.PoseInFrame"),
    ] {
        let c = &report["channels"][topic];
        assert_eq!(c["schema"], schema, "{report}");
        // One message per scan the run took, each valid.
        assert_eq!(c["messages"].as_u64(), Some(scans), "{report}");
        assert_eq!(c["valid"], c["messages"], "{report}");
        assert_eq!(
            report["schema_mismatches"][schema],
            Value::Array(vec![]),
            "{report}"
        );
    }
}
