//! Reading a scene: the TOML file and the `--set` overrides, each leaf matched to its key
//! and set on the scene, with the origin of every key recorded for the errors.

use std::path::Path;

use super::keys;
use super::keys::{Access, KeySpec, Rule, KEYS};
use super::optics_toml::SurfaceToml;
use super::suggest::{closest, unknown_key};
use super::view::{describe, describe_string};
use super::{Scene, SceneError, Sources};
use crate::model::eye::{SurfaceSpec, MAX_SURFACES};
use crate::text::one_line;

/// The origin shown for an override (`--set key=value` on the command line).
pub(super) fn override_origin(text: &str) -> String {
    // The key and the start of its value: a value may be kilobytes long (a list of lenses).
    let text = crate::text::excerpt(text, 72);
    crate::text::advice(&crate::text::Advice::Override { text: &text })
}

impl Scene {
    pub(super) fn apply_override_from(
        &mut self,
        text: &str,
        sources: &mut Sources,
    ) -> Result<(), SceneError> {
        let origin = override_origin(text);
        let Some((key, value)) = text.split_once('=') else {
            return Err(SceneError::BadOverride {
                origin,
                problem: "an override must have the form key=value (e.g. pressure.dP=2)".into(),
            });
        };
        let (key, value) = (key.trim(), value.trim());
        if key.is_empty() {
            return Err(SceneError::BadOverride {
                origin,
                problem: "the key before '=' is empty".into(),
            });
        }
        // A value that is not a TOML literal is a bare string: solver.scheme=trapezoid.
        let parsed = value
            .parse::<toml::Value>()
            .unwrap_or_else(|_| toml::Value::String(value.to_string()));
        self.set_from(key, &parsed, &origin, sources)?;
        self.overrides.push(text.to_string());
        Ok(())
    }

    pub(super) fn set_from(
        &mut self,
        key: &str,
        value: &toml::Value,
        origin: &str,
        sources: &mut Sources,
    ) -> Result<(), SceneError> {
        if let Some(rest) = key
            .strip_prefix(SURFACES_KEY)
            .and_then(|r| r.strip_prefix('['))
        {
            self.set_one_surface_key(key, rest, value, origin)?;
            let seq = sources.values().map(|(n, _)| *n).max().unwrap_or(0) + 1;
            sources.insert(SURFACES_KEY, (seq, origin.to_string()));
            return Ok(());
        }
        // The surfaces' items are set above: an item here is a lens's.
        if let Some(item) = indexed(key) {
            self.set_one_lens_key(key, item, value, origin)?;
            let seq = sources.values().map(|(n, _)| *n).max().unwrap_or(0) + 1;
            sources.insert(LENSES_KEY, (seq, origin.to_string()));
            return Ok(());
        }
        let Some(spec) = find_key(key) else {
            return Err(unknown_key(origin, key));
        };
        let wrong = |expected: &str| SceneError::WrongType {
            origin: origin.to_string(),
            key: spec.key.to_string(),
            expected: expected.to_string(),
            found: describe(value),
        };
        match spec.access {
            Access::Float { set, .. } | Access::OptionalFloat { set, .. } => match value {
                toml::Value::Float(x) => set(self, *x),
                toml::Value::Integer(i) => set(self, *i as f64),
                _ => return Err(wrong("a number")),
            },
            Access::Count { set, .. } => match value {
                toml::Value::Integer(i) if *i >= 0 => {
                    set(self, usize::try_from(*i).unwrap_or(usize::MAX))
                }
                toml::Value::Integer(i) => {
                    let problem = match spec.rule {
                        Rule::AtLeast(n) => format!("must be at least {n}"),
                        Rule::Count(lo, hi) => format!("must lie between {lo} and {hi}"),
                        _ => "must be non-negative".to_string(),
                    };
                    return Err(SceneError::Invalid {
                        origin: origin.to_string(),
                        key: spec.key.to_string(),
                        value: i.to_string(),
                        problem,
                    });
                }
                _ => return Err(wrong("an integer")),
            },
            Access::Bool { set, .. } => match value {
                toml::Value::Boolean(b) => set(self, *b),
                _ => return Err(wrong("true or false")),
            },
            Access::Choice { names, set, .. } => {
                let choices = names
                    .iter()
                    .map(|n| format!("\"{n}\""))
                    .collect::<Vec<_>>()
                    .join(", ");
                match value {
                    toml::Value::String(s) => match names.iter().position(|n| n == s) {
                        Some(i) => set(self, i),
                        None => {
                            return Err(SceneError::Invalid {
                                origin: origin.to_string(),
                                key: spec.key.to_string(),
                                value: describe_string(s),
                                problem: format!("must be one of {choices}"),
                            })
                        }
                    },
                    _ => return Err(wrong(&format!("one of {choices}"))),
                }
            }
            Access::Text { set, .. } => match value {
                toml::Value::String(s) => set(self, s.clone()),
                _ => return Err(wrong("a string")),
            },
            Access::Lenses { set, .. } => match super::optics_toml::parse_lenses(value) {
                Ok(lenses) => set(self, lenses),
                Err(e) => {
                    return Err(SceneError::Invalid {
                        origin: origin.to_string(),
                        key: e.key,
                        value: e.value,
                        problem: e.problem,
                    })
                }
            },
            Access::Surfaces { set, .. } => {
                let toml::Value::Array(items) = value else {
                    return Err(wrong("an array of surface tables ([[optics.surfaces]])"));
                };
                let mut surfaces = Vec::with_capacity(items.len().min(MAX_SURFACES + 1));
                for (i, item) in items.iter().enumerate().take(MAX_SURFACES + 1) {
                    surfaces.push(
                        SurfaceSpec::from_toml(i, item).map_err(|e| surface_error(origin, e))?,
                    );
                }
                self.written_clock.optics_time_keys = super::optics_toml::time_keys_in(value);
                set(self, surfaces)
            }
            Access::Floats { set, .. } => {
                let expected = "a list of numbers (e.g. [0.1, 0.5, 1.0])";
                let number = |v: &toml::Value| match v {
                    toml::Value::Float(x) => Some(*x),
                    toml::Value::Integer(i) => Some(*i as f64),
                    _ => None,
                };
                match value {
                    toml::Value::Array(items) => {
                        let mut xs = Vec::with_capacity(items.len());
                        for (i, item) in items.iter().enumerate() {
                            match number(item) {
                                Some(x) => xs.push(x),
                                None => {
                                    return Err(SceneError::WrongType {
                                        origin: origin.to_string(),
                                        key: format!("{}[{}]", spec.key, i + 1),
                                        expected: "a number".into(),
                                        found: describe(item),
                                    })
                                }
                            }
                        }
                        set(self, xs)
                    }
                    v => match number(v) {
                        Some(x) => set(self, vec![x]),
                        None => return Err(wrong(expected)),
                    },
                }
            }
        }
        let seq = sources.values().map(|(n, _)| *n).max().unwrap_or(0) + 1;
        sources.insert(spec.key, (seq, origin.to_string()));
        Ok(())
    }

    /// `optics.surfaces[i].name = value`: one key of one surface (`rest` is `i].name`); the
    /// surfaces before it are added empty if there are fewer (a built-in eye's keep the
    /// source's numbers; a custom eye's must be given).
    fn set_one_surface_key(
        &mut self,
        key: &str,
        rest: &str,
        value: &toml::Value,
        origin: &str,
    ) -> Result<(), SceneError> {
        let parsed = rest
            .split_once("].")
            .and_then(|(i, name)| Some((i.trim().parse::<usize>().ok()?, name.trim())));
        let Some((i, name)) = parsed.filter(|(i, _)| *i < MAX_SURFACES) else {
            return Err(SceneError::Invalid {
                origin: origin.to_string(),
                key: crate::text::excerpt(&one_line(key), 80),
                value: describe(value),
                problem: format!(
                    "is not a surface's key: write optics.surfaces[i].key with i from 0 to {} and key one of {}",
                    MAX_SURFACES - 1,
                    crate::model::eye::SURFACE_KEYS.join(", ")
                ),
            });
        };
        // The surfaces as written (ages with time.unit) with the new value among them.
        let mut surfaces = self.surfaces_as_written();
        if surfaces.len() <= i {
            surfaces.resize(i + 1, SurfaceSpec::default());
        }
        surfaces[i]
            .set(i, name, value)
            .map_err(|e| surface_error(origin, e))?;
        let (t, age) = super::optics_toml::time_keys_in(value);
        let keys = &mut self.written_clock.optics_time_keys;
        *keys = (keys.0 || t, keys.1 || age);
        self.set_surfaces_as_written(surfaces);
        Ok(())
    }

    /// `optics.lenses[i].name = value`: one key of one lens (its other keys kept), or the
    /// first key of a lens added after the scene's last.
    fn set_one_lens_key(
        &mut self,
        key: &str,
        item: Result<Indexed<'_>, String>,
        value: &toml::Value,
        origin: &str,
    ) -> Result<(), SceneError> {
        let invalid = |key: String, value: String, problem: String| SceneError::Invalid {
            origin: origin.to_string(),
            key,
            value,
            problem,
        };
        let shown = || crate::text::excerpt(&one_line(key), 80);
        let item = item.map_err(|problem| invalid(shown(), describe(value), problem))?;
        let mut lenses = self.optics().lenses.clone();
        if item.index > lenses.len() {
            return Err(invalid(
                shown(),
                describe(value),
                format!(
                    "is not a lens of the scene: it wears {} (optics.lenses[0] to [{}]), and a lens added comes next, as optics.lenses[{}]",
                    match lenses.len() { 1 => "1 lens".to_string(), n => format!("{n} lenses") },
                    lenses.len().saturating_sub(1),
                    lenses.len()
                ),
            ));
        }
        let lens = super::optics_toml::set_lens_key(&lenses, item.index, item.name, value)
            .map_err(|e| invalid(e.key, e.value, e.problem))?;
        match lenses.get_mut(item.index) {
            Some(l) => *l = lens,
            None => lenses.push(lens),
        }
        self.set_optics(|o| o.lenses = lenses);
        Ok(())
    }
}

/// One key of one item of an optics array, `optics.surfaces[i].name` or
/// `optics.lenses[i].name`: the array's key, i and the item's key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Indexed<'a> {
    pub array: &'static str,
    pub index: usize,
    pub name: &'a str,
}

impl Indexed<'_> {
    /// Whether the item's key takes a real number (what a sample draws).
    pub fn is_real(&self) -> bool {
        let real: &[&str] = if self.array == SURFACES_KEY {
            &["radius", "conic", "thickness", "index"]
        } else {
            &[
                "vertex",
                "power",
                "over",
                "front_radius",
                "back_radius",
                "thickness",
                "index",
            ]
        };
        real.contains(&self.name)
    }
}

/// `key` read as an [`Indexed`] key: None when it names no item of an optics array (it
/// does not begin `optics.surfaces[` or `optics.lenses[`); else the item, or the problem
/// with it (no index, an index beyond the array's most, a name that is not an item's key)
/// as the line `--set` would give.
pub(crate) fn indexed(key: &str) -> Option<Result<Indexed<'_>, String>> {
    let (array, names, most): (&'static str, &[&str], usize) =
        if key.starts_with(&format!("{SURFACES_KEY}[")) {
            (SURFACES_KEY, &crate::model::eye::SURFACE_KEYS, MAX_SURFACES)
        } else if key.starts_with(&format!("{LENSES_KEY}[")) {
            (
                LENSES_KEY,
                &super::optics_toml::LENS_KEYS,
                crate::model::eyewear::MAX_LENSES,
            )
        } else {
            return None;
        };
    let item = if array == SURFACES_KEY {
        "surface"
    } else {
        "lens"
    };
    let problem = || {
        format!(
            "is not a {item}'s key: write {array}[i].key with i from 0 to {} and key one of {}",
            most - 1,
            names.join(", ")
        )
    };
    let rest = &key[array.len() + 1..];
    let parsed = rest
        .split_once("].")
        .and_then(|(i, name)| Some((i.trim().parse::<usize>().ok()?, name.trim())))
        .filter(|(i, name)| *i < most && names.contains(name));
    Some(
        parsed
            .map(|(index, name)| Indexed { array, index, name })
            .ok_or_else(problem),
    )
}

/// The key of the eye's surfaces.
pub(super) const SURFACES_KEY: &str = "optics.surfaces";
/// The key of the lenses in front of the eye.
pub(super) const LENSES_KEY: &str = "optics.lenses";

/// The table key under which the origin of `key` is recorded: a surface's own key
/// (`optics.surfaces[2].radius`) is recorded as the surfaces'.
pub(super) fn source_key(key: &str) -> &'static str {
    if key.starts_with(LENSES_KEY) {
        return LENSES_KEY;
    }
    KEYS.iter()
        .find(|k| k.key == key)
        .map_or(SURFACES_KEY, |k| k.key)
}

/// A surface key's error as the scene's.
fn surface_error(origin: &str, e: crate::model::eye::SurfaceKeyError) -> SceneError {
    SceneError::Invalid {
        origin: origin.to_string(),
        key: e.key,
        value: e.value,
        problem: e.problem,
    }
}

/// Parse scene text as TOML; a syntax error names the line and column.
pub(crate) fn parse_table(text: &str, origin: &str) -> Result<toml::Table, SceneError> {
    text.parse().map_err(|e: toml::de::Error| {
        let (line, column) = line_column(text, e.span().map(|s| s.start).unwrap_or(0));
        SceneError::Syntax {
            origin: origin.to_string(),
            line,
            column,
            message: crate::text::excerpt(e.message(), 200),
        }
    })
}

/// Look a key up; a key given with the wrong case is not accepted (but is suggested).
fn find_key(key: &str) -> Option<&'static KeySpec> {
    keys::find(key)
}

/// The known sections (`pressure`, `material`, ..., and nested ones such as
/// `stimulus.blue`), in table order.
pub fn sections() -> Vec<&'static str> {
    let mut out: Vec<&'static str> = Vec::new();
    for k in KEYS {
        for (i, _) in k.key.match_indices('.') {
            let s = &k.key[..i];
            if !out.contains(&s) {
                out.push(s);
            }
        }
    }
    out
}

/// Collect the leaves of `table` as (dotted key, value), rejecting unknown keys and sections.
pub(super) fn flatten(
    table: &toml::Table,
    prefix: &str,
    origin: &str,
    out: &mut Vec<(String, toml::Value)>,
) -> Result<(), SceneError> {
    for (name, value) in table {
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        if find_key(&key).is_some() {
            out.push((key, value.clone()));
            continue;
        }
        let is_section = KEYS.iter().any(|k| k.key.starts_with(&format!("{key}.")));
        match value {
            toml::Value::Table(sub) if is_section => flatten(sub, &key, origin, out)?,
            toml::Value::Table(_) => {
                return Err(SceneError::UnknownSection {
                    origin: origin.to_string(),
                    suggestion: closest(&key, sections().into_iter()).map(str::to_string),
                    section: crate::text::excerpt(&key, 80),
                })
            }
            _ if is_section => {
                return Err(SceneError::WrongType {
                    origin: origin.to_string(),
                    key: one_line(&key),
                    expected: format!("a table ([{key}])"),
                    found: describe(value),
                })
            }
            _ => return Err(unknown_key(origin, &key)),
        }
    }
    Ok(())
}

/// 1-based line and column (in characters) of byte offset `at` in `text`.
fn line_column(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let before = text.get(..at).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before
        .rsplit('\n')
        .next()
        .map(|l| l.chars().count())
        .unwrap_or(0)
        + 1;
    (line, column)
}

/// The most bytes a scene file may have (a sweep listing 10⁵ runs by hand is a few MB): a
/// larger file, or a device that never ends, is refused before it is read into memory.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;

/// A scene file's name as messages show it, and its text (at most [`MAX_SCENE_BYTES`]).
pub fn read_scene_file(path: &Path) -> Result<(String, String), SceneError> {
    use std::io::Read;
    let origin = one_line(&path.display().to_string());
    let failed = |message: String| SceneError::Read {
        path: origin.clone(),
        message,
    };
    let file = std::fs::File::open(path).map_err(|e| failed(one_line(&e.to_string())))?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| failed(one_line(&e.to_string())))?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(failed(format!(
            "longer than {} MB, too long for a scene",
            MAX_SCENE_BYTES >> 20
        )));
    }
    let text = String::from_utf8(bytes).map_err(|_| failed("not UTF-8 text".into()))?;
    Ok((origin, text))
}
