//! Reading the `[sweep]` table: the listed runs, the grid's axes and the sample, and the
//! names the runs are given.

use crate::scene::sample::Sample;
use crate::scene::{closest, describe, keys, one_line, show, unknown_key, KeyValue, SceneError};

/// A key and the value a run gives it.
pub(super) type Assignment = (String, toml::Value);
/// A grid axis: a key and its values.
pub(super) type Axis = (String, Vec<toml::Value>);
/// A run before its scene is built: its name if listed, and its values.
pub(super) type Combination = (Option<String>, Vec<Assignment>);

/// One entry of `[[sweep.runs]]`: an optional name and the values it sets.
#[derive(Clone, Debug)]
pub(super) struct ListEntry {
    pub(super) name: Option<String>,
    pub(super) values: Vec<Assignment>,
}

/// The list entries, the grid axes (key, values) and the sample of a `[sweep]` table.
type Spec = (Vec<ListEntry>, Vec<Axis>, Option<Sample>);

/// The list entries, the grid axes (key, values) and the sample of a `[sweep]` table.
pub(super) fn parse_spec(spec: &toml::Table, origin: &str) -> Result<Spec, SceneError> {
    let bad = |problem: String| SceneError::BadSweep {
        origin: origin.to_string(),
        problem,
    };
    let mut list = Vec::new();
    let mut grid = Vec::new();
    let mut sample = None;
    for (name, value) in spec {
        match (name.as_str(), value) {
            ("sample", toml::Value::Table(t)) => {
                sample = Some(crate::scene::sample::parse(t, origin)?)
            }
            ("sample", v) => {
                return Err(bad(format!(
                    "sample must be a table ([sweep.sample]), found {}",
                    describe(v)
                )))
            }
            ("runs", toml::Value::Array(entries)) => {
                for (i, e) in entries.iter().enumerate() {
                    let toml::Value::Table(t) = e else {
                        return Err(bad(format!(
                            "runs[{}] must be a table of key = value, found {}",
                            i + 1,
                            describe(e)
                        )));
                    };
                    list.push(list_entry(t, i + 1, origin)?);
                }
                if entries.is_empty() {
                    return Err(bad("runs is empty: give at least one [[sweep.runs]]".into()));
                }
            }
            ("grid", toml::Value::Table(t)) => {
                for (key, v) in leaves(t, "", origin)? {
                    let toml::Value::Array(values) = v else {
                        return Err(bad(format!(
                            "grid.{key} must be a list of values, found {}",
                            describe(&v)
                        )));
                    };
                    if values.is_empty() {
                        return Err(bad(format!("grid.{key} is an empty list")));
                    }
                    grid.push((key, values));
                }
            }
            ("runs" | "grid", v) => {
                let expected = if name == "runs" {
                    "an array of tables ([[sweep.runs]])"
                } else {
                    "a table ([sweep.grid])"
                };
                return Err(bad(format!(
                    "{name} must be {expected}, found {}",
                    describe(v)
                )));
            }
            (other, _) => {
                let hint = closest(other, ["grid", "runs", "sample"].into_iter())
                    .map(|s| format!(" (did you mean '{s}'?)"))
                    .unwrap_or_default();
                return Err(bad(format!(
                    "unknown entry '{}'{hint}: a sweep has a grid and/or runs, or a sample",
                    one_line(other)
                )));
            }
        }
    }
    if sample.is_some() && !(list.is_empty() && grid.is_empty()) {
        // The population's statistics are over the cohort: a grid or list beside it would
        // mix cohorts (run one sampled sweep per setting instead).
        return Err(bad(
            "a sampled sweep ([sweep.sample]) has no [sweep.grid] or [[sweep.runs]]: give one sweep per setting".into(),
        ));
    }
    if list.is_empty() && grid.is_empty() && sample.is_none() {
        return Err(bad(
            "is empty: give [sweep.grid] and/or [[sweep.runs]], or [sweep.sample]".into(),
        ));
    }
    for (key, _) in &grid {
        if list.iter().any(|e| e.values.iter().any(|(k, _)| k == key)) {
            return Err(bad(format!("{key} is both in the grid and in the runs")));
        }
    }
    Ok((list, grid, sample))
}

/// A `[[sweep.runs]]` entry: `name` names the run, every other leaf is a scene key.
fn list_entry(t: &toml::Table, number: usize, origin: &str) -> Result<ListEntry, SceneError> {
    let bad = |problem: String| SceneError::BadSweep {
        origin: origin.to_string(),
        problem,
    };
    let mut name = None;
    let mut values = Vec::new();
    for (key, v) in leaves(t, "", origin)? {
        if key == "name" {
            match v {
                toml::Value::String(s) if valid_name(&s) => name = Some(s),
                v => {
                    return Err(bad(format!(
                        "runs[{number}].name must be a directory name of letters, digits and . _ = + - (at most 100), found {}",
                        describe(&v)
                    )))
                }
            }
        } else {
            values.push((key, v));
        }
    }
    Ok(ListEntry { name, values })
}

/// The leaves of a table as (dotted key, value); every key must be a scene key (or `name`).
fn leaves(
    t: &toml::Table,
    prefix: &str,
    origin: &str,
) -> Result<Vec<(String, toml::Value)>, SceneError> {
    let mut out = Vec::new();
    for (name, value) in t {
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        if keys::find(&key).is_some() || key == "name" {
            out.push((key, value.clone()));
        } else if let Some(item) = crate::scene::parse::indexed(&key) {
            // One item of an optics array, as `--set optics.lenses[0].power=…` sets it;
            // whether the item exists is the run's to say, once its scene is built.
            if let Err(problem) = item {
                return Err(SceneError::Invalid {
                    origin: format!("{origin}: [sweep]"),
                    key: crate::text::excerpt(&one_line(&key), 80),
                    value: crate::text::excerpt(&one_line(&value.to_string()), 40),
                    problem,
                });
            }
            out.push((key, value.clone()));
        } else if let toml::Value::Table(sub) = value {
            out.extend(leaves(sub, &key, origin)?);
        } else {
            return Err(unknown_key(&format!("{origin}: [sweep]"), &key));
        }
    }
    Ok(out)
}

/// The longest run name kept as it is; a longer one (many swept keys, long values) becomes
/// its first 80 bytes and a hash of the whole, so that `runs/<name>/` stays a legal file
/// name (255 bytes) with room for the temporary names beside it.
pub(super) const MAX_NAME: usize = 100;

pub(super) fn shorten(name: String) -> String {
    if name.len() <= MAX_NAME {
        return name;
    }
    // FNV-1a 64: stable across runs and platforms, so a resumed sweep finds its runs.
    let hash = crate::hash::fnv1a64(name.as_bytes());
    let mut cut = 80;
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    format!("{}-{hash:016x}", &name[..cut])
}

/// "Gamma=4_delta=2": the last component of each key and its value.
pub(super) fn generated_name(values: &[(String, toml::Value)]) -> String {
    if values.is_empty() {
        return "run".into();
    }
    values
        .iter()
        .map(|(k, v)| part(k, v))
        .collect::<Vec<_>>()
        .join("_")
}

pub(super) fn part(key: &str, v: &toml::Value) -> String {
    let last = key.rsplit('.').next().unwrap_or(key);
    let text: String = format!("{last}={}", show_value(v))
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._=+-".contains(c) {
                c
            } else {
                '-'
            }
        })
        .collect();
    text.chars().take(100).collect()
}

/// A value as in tables and run names: numbers without ".0", strings without quotes.
pub fn show_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => one_line(s),
        toml::Value::Float(x) => show(&KeyValue::Float(*x)),
        toml::Value::Array(items) => items.iter().map(show_value).collect::<Vec<_>>().join("+"),
        other => one_line(&other.to_string()),
    }
}

fn valid_name(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= 100
        && !s.starts_with('.')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "._=+-".contains(c))
}

/// `name`, or `name-2`, `name-3`, ... if a run already has it (`taken`: a set, so that
/// naming n runs is linear in n, not quadratic).
pub(super) fn unique(name: String, taken: &std::collections::HashSet<String>) -> String {
    if !taken.contains(&name) {
        return name;
    }
    (2..)
        .map(|k| format!("{name}-{k}"))
        .find(|n| !taken.contains(n))
        .unwrap_or(name)
}
