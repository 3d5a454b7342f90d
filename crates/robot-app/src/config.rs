//! Loading a `--config FILE` into the navigator's parameters.
//!
//! A run starts from a preset (`--method goalseek`, the default, or `--method paper`, the
//! paper as written) and a TOML file overrides any subset of its keys. Unknown keys, values of
//! the wrong type and values out of range are errors that name the key and its line. The keys
//! and defaults are listed in `docs/method.md`.

use std::path::Path;

use anyhow::{Context, bail};
pub use navigator::{Method, Params};

/// Loads a preset overridden by a TOML file. `method` on the command line wins over a
/// `method` key in the file; without either the preset is goalseek.
pub fn load(path: Option<&Path>, method: Option<Method>) -> anyhow::Result<Params> {
    load_over(path, method, |_| {})
}

/// [`load`] with the preset first changed by `adjust` (a command's own defaults); the file
/// still overrides them.
pub fn load_over(
    path: Option<&Path>,
    method: Option<Method>,
    adjust: impl Fn(&mut Params),
) -> anyhow::Result<Params> {
    match path {
        None => {
            let mut preset = Params::preset(method.unwrap_or_default());
            adjust(&mut preset);
            Ok(preset)
        }
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read config {}", p.display()))?;
            from_toml_str_over(&text, method, adjust)
                .with_context(|| format!("config {}", p.display()))
        }
    }
}

/// Parses TOML text over the preset (see [`load`]).
pub fn from_toml_str(text: &str, method: Option<Method>) -> anyhow::Result<Params> {
    from_toml_str_over(text, method, |_| {})
}

/// [`from_toml_str`] over the preset changed by `adjust` (see [`load_over`]).
pub fn from_toml_str_over(
    text: &str,
    method: Option<Method>,
    adjust: impl Fn(&mut Params),
) -> anyhow::Result<Params> {
    let user: toml::Table = toml::from_str(text)?;
    let file_method = match user.get("method") {
        None => None,
        Some(toml::Value::String(s)) => Some(
            s.parse::<Method>()
                .with_context(|| format!("line {}: key 'method'", line_of(text, "", "method")))?,
        ),
        Some(_) => bail!(
            "line {}: key 'method' must be a string",
            line_of(text, "", "method")
        ),
    };
    let mut preset = Params::preset(method.or(file_method).unwrap_or_default());
    adjust(&mut preset);
    let base = toml::Table::try_from(&preset).context("serialising the preset")?;
    let mut merged = base.clone();
    merge(&mut merged, &user, "", text)?;
    // The command line's method names the preset actually used.
    merged.insert(
        "method".into(),
        toml::Value::String(preset.method.to_string()),
    );
    let params: Params = match merged.try_into() {
        Ok(p) => p,
        Err(e) => {
            // A value of the right TOML type that the key does not take (an unknown name):
            // the first one that alone breaks the preset is named with its line.
            for (section, key, value) in leaves(&user, "") {
                let mut one = base.clone();
                let slot = match one.get_mut(&section).and_then(toml::Value::as_table_mut) {
                    Some(t) => t,
                    None if section.is_empty() => &mut one,
                    None => continue,
                };
                slot.insert(key.clone(), value.clone());
                if let Err(own) = one.try_into::<Params>() {
                    let path = if section.is_empty() {
                        key.clone()
                    } else {
                        format!("{section}.{key}")
                    };
                    bail!(
                        "line {}: '{path}': {}",
                        line_of(text, &section, &key),
                        own.message()
                    );
                }
            }
            return Err(e).context("config value of the wrong type");
        }
    };
    if let Err(e) = params.validate() {
        match &e {
            navigator::NavigatorError::InvalidParam { key, .. } => {
                let (section, name) = key.split_once('.').unwrap_or(("", key));
                match line_of(text, section, name) {
                    0 => bail!("{e}"),
                    line => bail!("line {line}: {e}"),
                }
            }
            _ => bail!("{e}"),
        }
    }
    Ok(params)
}

/// The parameters as TOML text (what `--config` accepts).
pub fn to_toml_string(params: &Params) -> String {
    toml::to_string_pretty(params).unwrap_or_default()
}

/// Overlays `user` onto `base`, refusing keys `base` does not have.
fn merge(
    base: &mut toml::Table,
    user: &toml::Table,
    prefix: &str,
    text: &str,
) -> anyhow::Result<()> {
    for (key, value) in user {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match (base.get_mut(key), value) {
            (None, _) => bail!("line {}: unknown key '{path}'", line_of(text, prefix, key)),
            (Some(toml::Value::Table(b)), toml::Value::Table(u)) => merge(b, u, &path, text)?,
            (Some(toml::Value::Table(_)), _) => bail!(
                "line {}: '{path}' must be a table ([{path}])",
                line_of(text, prefix, key)
            ),
            (Some(slot), v) => {
                if std::mem::discriminant(slot) != std::mem::discriminant(v)
                    && !matches!(
                        (&*slot, v),
                        (toml::Value::Float(_), toml::Value::Integer(_))
                    )
                {
                    bail!(
                        "line {}: '{path}' has the wrong type (expected {}, found {})",
                        line_of(text, prefix, key),
                        slot.type_str(),
                        v.type_str()
                    );
                }
                *slot = match (&*slot, v) {
                    (toml::Value::Float(_), toml::Value::Integer(i)) => {
                        toml::Value::Float(*i as f64)
                    }
                    _ => v.clone(),
                };
            }
        }
    }
    Ok(())
}

/// Every value the file sets that is not a table: (section, key, value).
fn leaves(table: &toml::Table, section: &str) -> Vec<(String, String, toml::Value)> {
    let mut out = Vec::new();
    for (key, value) in table {
        match value {
            toml::Value::Table(t) if section.is_empty() => out.extend(leaves(t, key)),
            _ if section.is_empty() && key == "method" => {}
            v => out.push((section.to_string(), key.clone(), v.clone())),
        }
    }
    out
}

/// The 1-based line where `key` is set inside table `section` ("" = top level); 0 if not found.
fn line_of(text: &str, section: &str, key: &str) -> usize {
    let full = if section.is_empty() {
        key.to_string()
    } else {
        format!("{section}.{key}")
    };
    let mut current = String::new();
    for (n, line) in text.lines().enumerate() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix('[') {
            current = rest
                .trim_start_matches('[')
                .trim_end_matches(']')
                .trim()
                .to_string();
            if current == full {
                return n + 1;
            }
            continue;
        }
        let is_key = |k: &str| {
            t.strip_prefix(k)
                .is_some_and(|r| r.trim_start().starts_with('='))
        };
        if (current == section && is_key(key)) || (current.is_empty() && is_key(&full)) {
            return n + 1;
        }
    }
    0
}
