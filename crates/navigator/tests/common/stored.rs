//! A configuration stored before some keys existed, read back.

use navigator::Params;
use serde_json::Value;

/// goalseek's parameters stored without `keys` of the `table` section and read back, with the
/// values that were removed.
pub fn without(table: &str, keys: &[&str]) -> (Params, Vec<Value>) {
    let mut v = serde_json::to_value(Params::goalseek()).unwrap();
    let section = v[table].as_object_mut().unwrap();
    let removed = keys
        .iter()
        .map(|k| {
            section
                .remove(*k)
                .unwrap_or_else(|| panic!("{table}.{k} is stored"))
        })
        .collect();
    (serde_json::from_value(v).unwrap(), removed)
}
