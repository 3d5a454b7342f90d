//! The naming rule of docs/outputs.md, checked on a written JSON file: every key that does not
//! hold an object or an array of objects ends with a unit suffix, or is in the documented list
//! of unitless keys (counts, names, flags, scores). An object's keys are checked in turn.

/// Unit suffixes (docs/outputs.md, "Units").
pub const UNIT_SUFFIXES: [&str; 6] = ["_m", "_deg", "_rad", "_s", "_ms", "_share"];

/// Keys without a unit (docs/outputs.md, "Units"): counts, names, flags and the SPL score.
pub const UNITLESS: [&str; 24] = [
    "reached",
    "reason",
    "legs",
    "scans",
    "collisions",
    "method",
    "seed",
    "note",
    "spl",
    "leg",
    "end",
    "goals_tried",
    "goals_reached",
    "command",
    "group",
    "kind",
    "world",
    "pair",
    "runs",
    "spl_runs",
    "runs_with_collision",
    "median_legs",
    "reasons",
    "narrow_passages",
];

/// Object-valued keys whose own keys are data (reason names), not names to check.
const DATA_KEYED: [&str; 1] = ["reasons"];

/// The keys of `v` (with their paths) that break the rule.
pub fn keys_without_unit(v: &serde_json::Value) -> Vec<String> {
    let mut bad = Vec::new();
    walk(v, "", &mut bad);
    bad
}

fn walk(v: &serde_json::Value, path: &str, bad: &mut Vec<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                let here = format!("{path}.{k}");
                let named =
                    UNIT_SUFFIXES.iter().any(|s| k.ends_with(s)) || UNITLESS.contains(&k.as_str());
                let container = x.is_object()
                    || x.as_array()
                        .is_some_and(|a| a.iter().any(|e| e.is_object()));
                if !named && !container {
                    bad.push(here.clone());
                }
                if !DATA_KEYED.contains(&k.as_str()) {
                    walk(x, &here, bad);
                }
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                walk(x, &format!("{path}[{i}]"), bad);
            }
        }
        _ => {}
    }
}
