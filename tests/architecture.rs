//! The layering of `docs/architecture.md`, checked against `cargo metadata`.
//!
//! Every dependency edge between workspace crates (normal, build and dev) must be listed
//! here; a new edge or a new crate fails this test until the drawing and this table agree.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each workspace package and the workspace packages it may depend on.
fn allowed() -> BTreeMap<&'static str, BTreeSet<&'static str>> {
    const BOTTOM: &[&str] = &["scan-types"];
    let all = [
        "scan-types",
        "urg-driver",
        "robot-base",
        "sim-laser",
        "scan-log",
        "expansion",
        "planner",
        "landmarks",
        "localiser",
        "navigator",
        "slam",
    ];
    let mut with_app = all.to_vec();
    with_app.push("robot-app");
    let table: &[(&str, &[&str])] = &[
        // Layer 0.
        ("scan-types", &[]),
        // Layer 1: sources, bases and the kernel, on scan-types only.
        ("urg-driver", BOTTOM),
        ("robot-base", BOTTOM),
        ("sim-laser", BOTTOM),
        ("scan-log", BOTTOM),
        ("expansion", BOTTOM),
        // Layer 2: the method's parts, each on scan-types; the planner chooses among rays
        // made safe by the expansion kernel.
        ("landmarks", &["scan-types"]),
        ("localiser", &["scan-types"]),
        ("planner", &["scan-types", "expansion"]),
        // Laser-only SLAM refines its correlative matches with the localiser's ICP.
        ("slam", &["scan-types", "localiser"]),
        // Layer 3: the loop, on the method's parts and the laser-only SLAM it can localise
        // with (no sensor, simulator or log).
        (
            "navigator",
            &[
                "scan-types",
                "expansion",
                "planner",
                "landmarks",
                "localiser",
                "slam",
            ],
        ),
        // Layer 4: the program, and the root package that owns tests/ and benches/.
        ("robot-app", &all),
        ("goalseek", &with_app),
    ];
    table
        .iter()
        .map(|(k, v)| (*k, v.iter().copied().collect()))
        .collect()
}

/// The standard output of `cargo ARGS` in the workspace, which must succeed.
fn cargo(args: &[&str]) -> Vec<u8> {
    let out = Command::new(env!("CARGO"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

fn metadata() -> serde_json::Value {
    let out = cargo(&[
        "metadata",
        "--format-version",
        "1",
        "--no-deps",
        "--offline",
    ]);
    serde_json::from_slice(&out).expect("cargo metadata prints JSON")
}

/// Workspace package name -> names of the workspace packages it depends on.
fn edges(meta: &serde_json::Value) -> BTreeMap<String, BTreeSet<String>> {
    let packages = meta["packages"].as_array().expect("packages array");
    let names: BTreeSet<String> = packages
        .iter()
        .map(|p| p["name"].as_str().unwrap().to_string())
        .collect();
    packages
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .unwrap()
                .iter()
                .map(|d| d["name"].as_str().unwrap().to_string())
                .filter(|n| names.contains(n))
                .collect();
            (p["name"].as_str().unwrap().to_string(), deps)
        })
        .collect()
}

#[test]
fn every_edge_is_allowed() {
    let allowed = allowed();
    let meta = metadata();
    let mut bad = Vec::new();
    for (pkg, deps) in edges(&meta) {
        let Some(ok) = allowed.get(pkg.as_str()) else {
            bad.push(format!(
                "{pkg}: not in the layering table (add it to docs/architecture.md and this test)"
            ));
            continue;
        };
        for d in deps {
            if !ok.contains(d.as_str()) {
                bad.push(format!("{pkg} -> {d} is not an allowed edge"));
            }
        }
    }
    assert!(bad.is_empty(), "layering violations:\n{}", bad.join("\n"));
}

/// The loop as a library carries no sensor, simulator, log, CLI, plotting, threading or
/// serial crate, directly or through another crate (dev-dependencies included).
#[test]
fn the_navigator_pulls_in_no_program_crate() {
    let out = cargo(&[
        "tree",
        "-p",
        "navigator",
        "--edges",
        "normal,build,dev",
        "--prefix",
        "none",
        "--offline",
    ]);
    let text = String::from_utf8_lossy(&out);
    let names: BTreeSet<&str> = text
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(
        names.contains("navigator") && names.contains("planner"),
        "{text}"
    );
    for banned in [
        "sim-laser",
        "urg-driver",
        "robot-base",
        "scan-log",
        "robot-app",
        "clap",
        "plotters",
        "rayon",
        "serialport",
    ] {
        assert!(
            !names.contains(banned),
            "navigator depends on {banned}:\n{text}"
        );
    }
}

#[test]
fn every_listed_crate_exists() {
    let meta = metadata();
    let present: BTreeSet<String> = edges(&meta).into_keys().collect();
    for name in allowed().keys() {
        assert!(
            present.contains(*name),
            "{name} is in the layering table but not in the workspace"
        );
    }
}

#[test]
fn the_checker_rejects_an_upward_edge() {
    // A hand-made metadata document with scan-types depending on planner must be caught.
    let fake = serde_json::json!({"packages": [
        {"name": "scan-types", "dependencies": [{"name": "planner"}]},
        {"name": "planner", "dependencies": [{"name": "scan-types"}]}
    ]});
    let e = edges(&fake);
    let allowed = allowed();
    let violations: Vec<_> = e
        .iter()
        .flat_map(|(p, ds)| ds.iter().map(move |d| (p.clone(), d.clone())))
        .filter(|(p, d)| !allowed[p.as_str()].contains(d.as_str()))
        .collect();
    assert_eq!(
        violations,
        vec![("scan-types".to_string(), "planner".to_string())]
    );
}
