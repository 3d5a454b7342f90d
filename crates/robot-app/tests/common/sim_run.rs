//! One `robot-app sim` run on a shared floor plan, for tests that replay a batch pair.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

/// The repository's root.
pub fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Whether `../shared/worlds/stage/FILE` is there (a note when it is not: the test skips).
pub fn stage_image_present(file: &str) -> bool {
    world_present(&format!("stage/{file}"))
}

/// Whether `../shared/worlds/PATH` is there (a note when it is not: the test skips).
#[allow(clippy::print_stdout)] // the note says why the test did nothing
pub fn world_present(path: &str) -> bool {
    let present = root().join("../shared/worlds").join(path).exists();
    if !present {
        println!("skipping: ../shared/worlds/{path} not found");
    }
    present
}

/// `summary.json` of `robot-app sim --world sim/floorplans/WORLD.toml ARGS --config` with
/// `config` written to `dir/NAME.toml`, its outputs in `dir/NAME`.
pub fn summary(dir: &Path, name: &str, world: &str, args: &[&str], config: &str) -> Value {
    let cfg = dir.join(format!("{name}.toml"));
    std::fs::write(&cfg, config).unwrap();
    let out = dir.join(name);
    let o = Command::new(BIN)
        .args(["-q", "sim", "--world"])
        .arg(root().join(format!("sim/floorplans/{world}.toml")))
        .args(args)
        .arg("--config")
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let s = std::fs::read(out.join("summary.json"))
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stderr)));
    serde_json::from_slice(&s).unwrap()
}
