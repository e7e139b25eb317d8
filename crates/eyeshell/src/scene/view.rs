//! A scene read back: its keys and values, as TOML, as JSON and as messages show them.

use std::path::Path;

use super::keys::{self, KeySpec, KeyValue, KEYS};
use super::Scene;
use crate::text::number;

impl Scene {
    /// The keys in use: every elastic key, and the growth keys when the scene grows.
    pub fn keys(&self) -> impl Iterator<Item = &'static KeySpec> + '_ {
        KEYS.iter().filter(move |k| k.applies_to(self))
    }

    /// The effective value of every key in use, in table order.
    pub fn entries(&self) -> Vec<(&'static str, KeyValue)> {
        self.keys().map(|k| (k.key, k.get(self))).collect()
    }

    /// Whether key `key` is read by nothing in this scene: the schedule's parameters of
    /// another form, the schedule itself when constant, the time unit when there is none.
    /// Written files leave such keys out, so that the files of scenes that do not use
    /// schedules or ages stay byte for byte as they were.
    pub fn idle(&self, key: &str) -> bool {
        use crate::growth::schedule::{Form, TimeUnit};
        let Some(g) = &self.growth else {
            return false;
        };
        let form = g.schedule.form;
        match key {
            "growth.schedule" => form == Form::Constant,
            "growth.schedule_tau" => form != Form::Exponential,
            "growth.schedule_centre" | "growth.schedule_width" => form != Form::Logistic,
            "growth.schedule_times" | "growth.schedule_factors" => form != Form::Table,
            "time.unit" => g.clock.unit == TimeUnit::None,
            _ => false,
        }
    }

    /// Why nothing in this scene reads key `key` (None when something does): a key the
    /// scene does not use ([`KeySpec::applies_to`]) or an idle one ([`Scene::idle`]), in
    /// words naming the key that would turn it on. A sweep refuses to sweep a key that no
    /// run reads: its runs would all be the same eye under different labels.
    pub fn not_in_effect(&self, key: &str) -> Option<String> {
        // One item's key (optics.lenses[0].power) is read as its array is.
        let spec = keys::find(key).or_else(|| {
            let item = super::parse::indexed(key)?.ok()?;
            keys::find(item.array)
        })?;
        if spec.applies_to(self) && !self.idle(key) {
            return None;
        }
        let growing = self.growth.is_some();
        let why = match key {
            "stimulus.myopia_D" | "stimulus.hyperopia_D" => {
                "it is read only with stimulus.classify = \"dioptres\" in a growing scene"
            }
            "stimulus.source" => "it is read only by a growing scene",
            "growth.schedule" => "the schedule is constant (a factor of 1)",
            "growth.schedule_tau" => "it is read only with growth.schedule = \"exponential\"",
            "growth.schedule_centre" | "growth.schedule_width" => {
                "it is read only with growth.schedule = \"logistic\""
            }
            "growth.schedule_times" | "growth.schedule_factors" => {
                "it is read only with growth.schedule = \"table\""
            }
            "time.unit" => "the scene counts no ages",
            _ if spec.section() == Some("optics") && growing => {
                "the optics keys are read only with stimulus.source = \"optics\" (the stimulus computed from the eye's optics)"
            }
            _ if spec.growth && !growing => "it is read only by a growing scene",
            _ => "nothing in this scene reads it",
        };
        Some(format!("{key} is not in effect: {why}"))
    }

    /// The effective parameters (every key in use but the metadata and the unset keys) as a
    /// JSON object: the growth keys only when the scene grows.
    pub fn parameters_json(&self) -> serde_json::Value {
        // An unset key is left out: it has no value (and the files of scenes that do not
        // use it stay as they were).
        let map = self
            .keys()
            .filter(|k| k.is_parameter() && !self.idle(k.key))
            .map(|k| (k.key, k.get(self)))
            .filter(|(_, v)| *v != KeyValue::Unset)
            .map(|(k, v)| (k.to_string(), v.to_json()))
            .collect::<serde_json::Map<_, _>>();
        serde_json::Value::Object(map)
    }

    /// The effective scene as TOML (dotted keys), which reads back to the same scene (the
    /// growth keys only when the scene grows). A key nothing reads is left out at its
    /// default, so that the files of scenes that do not use it stay byte for byte as they
    /// were, and written when it holds another value: a scene carries it (a sweep's run of
    /// the polynomial stimulus with optics.pupil = 2 beside runs of the computed one), and
    /// the text must give that scene back.
    pub fn to_toml(&self) -> String {
        let mut out = String::new();
        let default = Scene::default();
        let written = |k: &&KeySpec| {
            (k.applies_to(self) && !self.idle(k.key))
                || (!(k.growth && self.growth.is_none()) && k.get(self) != k.get(&default))
        };
        for k in KEYS.iter().filter(written) {
            // A red surface that follows the blue one is derived, not given: written as a
            // key it would be given (and stop following) when the text is read back, so it
            // is shown as a comment; so is a cornea whose radius follows geometry.R0.
            let derived = self.stimulus.red_follows_blue && k.key.starts_with("stimulus.red.");
            let sized = self.params.cornea_follows_radius && k.key == "cornea.R0";
            // So are a run's length and output times that follow the ages of its window.
            let ages = self
                .growth
                .as_ref()
                .is_some_and(|g| g.clock.window().is_some());
            let written = &self.written_clock;
            let windowed = ages
                && ((k.key == "growth.t_end" && written.t_end.is_none())
                    || (k.key == "output.times" && written.output_times.is_none()));
            match k.get(self) {
                KeyValue::Text(None) | KeyValue::Unset => {}
                v if derived => out.push_str(&format!("# {} = {v}  (follows blue)\n", k.key)),
                v if sized => out.push_str(&format!("# {} = {v}  (follows geometry.R0)\n", k.key)),
                v if windowed => out.push_str(&format!(
                    "# {} = {v}  (follows time.start and time.end)\n",
                    k.key
                )),
                v => out.push_str(&format!("{} = {}\n", k.key, v)),
            }
        }
        out
    }

    /// The physics this scene's model contains (docs/MODEL.md §2–6): membrane, thickness, growth.
    pub fn components(&self) -> crate::model::components::Components {
        crate::model::components::Components::of(&self.params, self.growth.is_some())
    }

    /// The scene's name: `name` if given, else the file stem of the origin.
    pub fn display_name(&self) -> String {
        self.name.clone().unwrap_or_else(|| {
            Path::new(&self.origin)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| self.origin.clone())
        })
    }
}

/// A value as shown in messages: like TOML, but whole numbers without ".0" (`C = -1`).
/// The most items of a list a message shows.
const SHOWN_ITEMS: usize = 6;

pub(crate) fn show(v: &KeyValue) -> String {
    match v {
        KeyValue::Float(x) => number(*x),
        // A long list (output.times may hold a thousand) as its ends and its length: a
        // message stays one readable line.
        KeyValue::Floats(xs) if xs.len() > SHOWN_ITEMS => format!(
            "[{}, …, {}] ({} values)",
            xs[..SHOWN_ITEMS - 1]
                .iter()
                .map(|x| number(*x))
                .collect::<Vec<_>>()
                .join(", "),
            number(xs[xs.len() - 1]),
            xs.len()
        ),
        KeyValue::Floats(xs) => format!(
            "[{}]",
            xs.iter()
                .map(|x| show(&KeyValue::Float(*x)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        v => v.to_string(),
    }
}

/// A TOML value as "type value" for messages, on one line.
pub(crate) fn describe(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => format!("string {}", describe_string(s)),
        toml::Value::Integer(i) => format!("integer {i}"),
        toml::Value::Float(x) => format!("float {}", show(&KeyValue::Float(*x))),
        toml::Value::Boolean(b) => format!("boolean {b}"),
        toml::Value::Datetime(d) => format!("datetime {d}"),
        toml::Value::Array(_) => "an array".into(),
        toml::Value::Table(_) => "a table".into(),
    }
}

pub(super) fn describe_string(s: &str) -> String {
    let short: String = s.chars().take(60).collect();
    let ell = if s.chars().count() > 60 { "…" } else { "" };
    format!("\"{}{ell}\"", short.escape_debug())
}
