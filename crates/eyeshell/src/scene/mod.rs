//! Scenes: TOML files that set the parameters of one problem (docs/MODEL.md §8 gives the defaults).
//!
//! A scene is read in three steps, each reporting the first problem as one line that names
//! the origin (file or `--set` text) and the key:
//! 1. the file is parsed as TOML and every leaf is matched to a key of [`keys::KEYS`]
//!    (unknown keys and sections are errors, with the closest known key suggested);
//! 2. the `--set key=value` overrides are applied in order, after the file, so they win;
//! 3. the effective values are validated: each key's own range, then the limits that tie
//!    keys together (ΔP below the cornea's limit, ε below L = π·f·R0).
//!
//! Every key is optional; a missing key keeps the default of `params.rs`.
//!
//! Growth: a scene with any `growth.*` key (in the file or from `--set`) grows, with the
//! defaults of `growth/mod.rs` for the keys it does not give; a scene without one is a pure
//! elastic scene ([`Scene::growth`] is `None`), whose growth keys (solver.integrator, ...,
//! output.times, stimulus.*) are kept but not used, shown or summarised.

pub mod keys;
pub mod optics_toml;
pub mod sample;
pub mod sweep;

use std::collections::BTreeMap;
use std::path::Path;

use crate::bvp::settings::SolverSettings;
use crate::growth::{GrowthParams, GrowthSettings};
use crate::model::eye::{SurfaceSpec, MAX_SURFACES};
use crate::model::optics::{OpticsSpec, Source};
use crate::model::params::Params;
use crate::model::stimulus::{Surface, RED_OFFSET};
use crate::text::{decimals6, number};
pub use keys::{Access, KeySpec, KeyValue, Rule, KEYS};
use optics_toml::SurfaceToml;

/// Everything a scene sets: the physical parameters and the numerical settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub params: Params,
    pub solver: SolverSettings,
    /// Top-level `name`, if the scene gives one.
    pub name: Option<String>,
    /// Top-level `description`, if the scene gives one.
    pub description: Option<String>,
    /// Where the scene came from: the file path, or the origin given to `from_toml_str`.
    pub origin: String,
    /// The `--set` overrides applied on top of the file, in order.
    pub overrides: Vec<String>,
    /// The growth model: `Some` as soon as any `growth.*` key is given; `None` for a pure
    /// elastic scene. Its surfaces are those of [`Scene::stimulus`].
    pub growth: Option<GrowthParams>,
    /// The numerics of the time integration and the output times (used only with growth).
    pub growth_settings: GrowthSettings,
    /// The best-focus surfaces as the scene gives them (kept here too while the scene does
    /// not grow, so that `stimulus.*` keys do not turn growth on).
    pub stimulus: Stimulus,
}

/// The visual stimulus of a scene: the blue and red best-focus surfaces (docs/MODEL.md §6).
#[derive(Clone, Debug, PartialEq)]
pub struct Stimulus {
    pub blue: Surface,
    pub red: Surface,
    /// True while no `stimulus.red.*` key is given: the red surface is then the blue one
    /// pushed back by [`RED_OFFSET`], whatever the blue one is.
    pub red_follows_blue: bool,
    /// stimulus.source: the polynomial surfaces, or surfaces computed from `optics`.
    pub source: Source,
    /// The optics.* keys.
    pub optics: OpticsSpec,
}

impl Default for Stimulus {
    fn default() -> Self {
        Stimulus {
            blue: Surface::blue(),
            red: Surface::default_red(),
            red_follows_blue: true,
            source: Source::Polynomial,
            optics: OpticsSpec::default(),
        }
    }
}

impl Default for Scene {
    fn default() -> Self {
        Scene {
            params: Params::default(),
            solver: SolverSettings::default(),
            name: None,
            description: None,
            origin: "(defaults)".into(),
            overrides: Vec::new(),
            growth: None,
            growth_settings: GrowthSettings::default(),
            stimulus: Stimulus::default(),
        }
    }
}

/// A scene that cannot be used. Display is one line: origin, key, and what is wrong.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SceneError {
    #[error("{path}: cannot read the scene: {message}")]
    Read { path: String, message: String },
    #[error("{origin}: invalid TOML at line {line}, column {column}: {message}")]
    Syntax {
        origin: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{origin}: unknown key '{key}'{}", suggest(suggestion))]
    UnknownKey {
        origin: String,
        key: String,
        suggestion: Option<String>,
    },
    #[error("{origin}: unknown section [{section}]{}", suggest_section(suggestion))]
    UnknownSection {
        origin: String,
        section: String,
        suggestion: Option<String>,
    },
    #[error("{origin}: {key} must be {expected}, found {found}")]
    WrongType {
        origin: String,
        key: String,
        expected: String,
        found: String,
    },
    #[error("{}", invalid_line(origin, key, value, problem))]
    Invalid {
        origin: String,
        key: String,
        value: String,
        problem: String,
    },
    #[error("{origin}: {problem}")]
    BadOverride { origin: String, problem: String },
    #[error("{origin}: the scene declares a [sweep] of runs: {}", crate::text::advice(&crate::text::Advice::RunSweep { origin }))]
    IsSweep { origin: String },
    #[error("{origin}: [sweep] {problem}")]
    BadSweep { origin: String, problem: String },
}

impl SceneError {
    /// The scene key the error is about, when there is one.
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::UnknownKey { key, .. }
            | SceneError::WrongType { key, .. }
            | SceneError::Invalid { key, .. } => Some(key),
            SceneError::UnknownSection { section, .. } => Some(section),
            _ => None,
        }
    }
}

/// The most characters of an origin (a path, a `--set` text) and of a value an error shows:
/// a message is one line of at most about 300 characters however long the input.
const MAX_ORIGIN: usize = 100;
const MAX_VALUE: usize = 80;

/// The line an error of a key shows: about [`MAX_LINE`] characters at most, with the
/// command line's `eyeshell: error: ` before it, however long the input. The problem (the
/// explanation) is never cut: the origin and the value are shortened first to at most
/// [`MAX_ORIGIN`] and [`MAX_VALUE`] characters, then, if the line is still too long, to
/// their beginnings (the key and the problem name what is wrong).
fn invalid_line(origin: &str, key: &str, value: &str, problem: &str) -> String {
    let line = |o: usize, v: usize| {
        format!(
            "{}: {key} = {} {problem}",
            crate::text::excerpt(origin, o),
            crate::text::excerpt(value, v)
        )
    };
    let full = line(MAX_ORIGIN, MAX_VALUE);
    if full.chars().count() <= MAX_LINE {
        return full;
    }
    // An override's origin keeps its key (`--set optics.surfaces[1].thickness=…`); any
    // other (a file, a sweep's run) its first 48 characters.
    let keep = match origin.find('=') {
        Some(at) if origin[..at].matches(' ').count() <= 1 => origin[..at].chars().count() + 1,
        _ => 48,
    }
    .min(80);
    line(keep, 12)
}

/// The longest line [`invalid_line`] aims at (300 with the command line's prefix).
const MAX_LINE: usize = 280;

fn suggest(s: &Option<String>) -> String {
    s.as_ref()
        .map(|s| format!(" (did you mean '{s}'?)"))
        .unwrap_or_default()
}

fn suggest_section(s: &Option<String>) -> String {
    s.as_ref()
        .map(|s| format!(" (did you mean [{s}]?)"))
        .unwrap_or_default()
}

pub(crate) use crate::text::one_line;

/// The origin shown for an override (`--set key=value` on the command line).
fn override_origin(text: &str) -> String {
    // The key and the start of its value: a value may be kilobytes long (a list of lenses).
    let text = crate::text::excerpt(text, 72);
    crate::text::advice(&crate::text::Advice::Override { text: &text })
}

/// Which origin set each key last; a later set wins (sequence number first).
type Sources = BTreeMap<&'static str, (usize, String)>;

impl Scene {
    /// Read, override and validate the scene in `path`.
    pub fn from_file(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
        let (origin, text) = read_scene_file(path)?;
        Scene::from_toml_str(&text, &origin, overrides)
    }

    /// Parse `text` (named `origin` in messages), apply `overrides` (`key=value`), validate.
    /// A scene with a `[sweep]` table is refused: it is many scenes ([`sweep::Sweep`]).
    pub fn from_toml_str(
        text: &str,
        origin: &str,
        overrides: &[String],
    ) -> Result<Scene, SceneError> {
        let origin = one_line(origin);
        let table = parse_table(text, &origin)?;
        if table.contains_key(sweep::SWEEP) {
            return Err(SceneError::IsSweep { origin });
        }
        Scene::from_table(&table, &origin, &[], overrides)
    }

    /// The scene of the sweep file `path` without its `[sweep]` table (the scene every run
    /// starts from); a scene without one reads as [`Scene::from_file`] reads it.
    pub fn from_file_without_sweep(path: &Path) -> Result<Scene, SceneError> {
        let (origin, text) = read_scene_file(path)?;
        let mut table = parse_table(&text, &origin)?;
        table.remove(sweep::SWEEP);
        Scene::from_table(&table, &origin, &[], &[])
    }

    /// The scene of a parsed file `table` (no `[sweep]`), then `assignments` (key, value,
    /// origin) in order, then the `overrides`; validated.
    pub(crate) fn from_table(
        table: &toml::Table,
        origin: &str,
        assignments: &[(String, toml::Value, String)],
        overrides: &[String],
    ) -> Result<Scene, SceneError> {
        let mut scene = Scene {
            origin: origin.to_string(),
            ..Scene::default()
        };
        let mut sources = Sources::new();
        let mut leaves = Vec::new();
        flatten(table, "", origin, &mut leaves)?;
        for (key, value) in leaves {
            scene.set_from(&key, &value, origin, &mut sources)?;
        }
        for (key, value, from) in assignments {
            scene.set_from(key, value, from, &mut sources)?;
        }
        for text in overrides {
            scene.apply_override_from(text, &mut sources)?;
        }
        scene.validate_from(&sources)?;
        if let Err(e) = scene.trace_optics() {
            return Err(SceneError::Invalid {
                origin: scene.origin_of(&sources, &[source_key(&e.key), "optics.lenses"]),
                key: e.key.to_string(),
                value: e.value,
                problem: e.problem,
            });
        }
        Ok(scene)
    }

    /// The scene that sets each of `assignments` (key, value, origin) on the defaults, as
    /// written in a run's summary.json `parameters`; validated.
    pub fn from_parameters(
        assignments: &[(String, toml::Value, String)],
        origin: &str,
    ) -> Result<Scene, SceneError> {
        Scene::from_table(&toml::Table::new(), &one_line(origin), assignments, &[])
    }

    /// Set one key from a TOML value, checking the key and the type but not the range
    /// (call [`Scene::validate`] when done). `origin` names the source in messages.
    /// [`Scene::set`] is the checked form for library users.
    pub fn set_toml(
        &mut self,
        key: &str,
        value: &toml::Value,
        origin: &str,
    ) -> Result<(), SceneError> {
        self.set_from(key, value, origin, &mut Sources::new())
    }

    /// Apply one `key=value` override (value parsed as TOML, else taken as a string),
    /// without validating the range; call [`Scene::validate`] when done.
    pub fn apply_override(&mut self, text: &str) -> Result<(), SceneError> {
        self.apply_override_from(text, &mut Sources::new())
    }

    /// Apply `texts` (`key=value`, each as [`Scene::apply_override`]) in order, then
    /// validate: a value out of range is blamed on the override that set it (`--set`, or a
    /// front end's keyword), never on the scene file or "defaults", which did not.
    pub fn apply_overrides_and_validate(&mut self, texts: &[String]) -> Result<(), SceneError> {
        let mut sources = Sources::new();
        for text in texts {
            self.apply_override_from(text, &mut sources)?;
        }
        self.validate_from(&sources)
    }

    /// Check every key's range and the limits that tie keys together.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.validate_from(&Sources::new())
    }

    /// The growth model, turning growth on (with the defaults and the scene's surfaces) if
    /// the scene did not grow yet.
    pub fn growth_mut(&mut self) -> &mut GrowthParams {
        let st = &self.stimulus;
        let (blue, red, source, optics) = (st.blue, st.red, st.source, st.optics.clone());
        self.growth.get_or_insert_with(|| GrowthParams {
            blue,
            red,
            source,
            optics,
            ..GrowthParams::default()
        })
    }

    /// The blue best-focus surface in effect.
    pub fn blue(&self) -> Surface {
        self.growth.as_ref().map_or(self.stimulus.blue, |g| g.blue)
    }

    /// The red best-focus surface in effect.
    pub fn red(&self) -> Surface {
        self.growth.as_ref().map_or(self.stimulus.red, |g| g.red)
    }

    /// Change the blue surface; the red one follows it (pushed back by [`RED_OFFSET`]) as
    /// long as no red key was given.
    pub fn set_blue(&mut self, change: impl FnOnce(&mut Surface)) {
        self.edit_stimulus(|st| {
            change(&mut st.blue);
            if st.red_follows_blue {
                st.red = Surface {
                    offset: RED_OFFSET,
                    ..st.blue
                };
            }
        });
    }

    /// Change the red surface. The first red key starts from the default red surface
    /// (the published blue one pushed back by [`RED_OFFSET`]), not from the scene's blue.
    pub fn set_red(&mut self, change: impl FnOnce(&mut Surface)) {
        self.edit_stimulus(|st| {
            if st.red_follows_blue {
                st.red = Surface::default_red();
                st.red_follows_blue = false;
            }
            change(&mut st.red);
        });
    }

    /// The source of the stimulus's surfaces in effect.
    pub fn stimulus_source(&self) -> Source {
        self.growth
            .as_ref()
            .map_or(self.stimulus.source, |g| g.source)
    }

    /// The optics keys in effect.
    pub fn optics(&self) -> &OpticsSpec {
        self.growth
            .as_ref()
            .map_or(&self.stimulus.optics, |g| &g.optics)
    }

    /// Change the stimulus's source.
    pub fn set_stimulus_source(&mut self, source: Source) {
        self.edit_stimulus(|st| st.source = source);
    }

    /// Change the optics keys.
    pub fn set_optics(&mut self, change: impl FnOnce(&mut OpticsSpec)) {
        self.edit_stimulus(|st| change(&mut st.optics));
    }

    /// Edit the surfaces in effect (those of the growth model when the scene grows) and
    /// keep the two copies equal.
    fn edit_stimulus(&mut self, edit: impl FnOnce(&mut Stimulus)) {
        if let Some(g) = &self.growth {
            self.stimulus.blue = g.blue;
            self.stimulus.red = g.red;
            self.stimulus.source = g.source;
            self.stimulus.optics = g.optics.clone();
        }
        edit(&mut self.stimulus);
        if let Some(g) = &mut self.growth {
            g.blue = self.stimulus.blue;
            g.red = self.stimulus.red;
            g.source = self.stimulus.source;
            g.optics = self.stimulus.optics.clone();
        }
    }

    /// Trace the surfaces of a growing scene whose stimulus is computed from its optics
    /// (once: nothing is traced while the keys and the centre stay as they were traced).
    /// The error names the optics key to change.
    pub fn resolve_optics(&mut self) -> Result<(), SceneError> {
        self.trace_optics().map_err(|e| SceneError::Invalid {
            origin: self.origin_of_key(&e.key),
            key: e.key.to_string(),
            value: e.value,
            problem: e.problem,
        })
    }

    fn trace_optics(&mut self) -> Result<(), crate::model::optics::OpticsKeyError> {
        let Some(g) = &mut self.growth else {
            return Ok(());
        };
        if !g.is_resolved() {
            g.computed = Some(std::sync::Arc::new(
                g.optics.compute_over(g.blue.z_b, g.t_end)?,
            ));
        }
        crate::model::eyewear::refraction_table(&g.refraction_optics())?;
        Ok(())
    }

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
        let spec = keys::find(key)?;
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
            // is shown as a comment.
            let derived = self.stimulus.red_follows_blue && k.key.starts_with("stimulus.red.");
            match k.get(self) {
                KeyValue::Text(None) | KeyValue::Unset => {}
                v if derived => out.push_str(&format!("# {} = {v}  (follows blue)\n", k.key)),
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

    fn apply_override_from(&mut self, text: &str, sources: &mut Sources) -> Result<(), SceneError> {
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

    fn set_from(
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
            Access::Lenses { set, .. } => match optics_toml::parse_lenses(value) {
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
        let mut surfaces = self.optics().surfaces.clone();
        if surfaces.len() <= i {
            surfaces.resize(i + 1, SurfaceSpec::default());
        }
        surfaces[i]
            .set(i, name, value)
            .map_err(|e| surface_error(origin, e))?;
        self.set_optics(|o| o.surfaces = surfaces);
        Ok(())
    }

    /// Where the value of `key` came from: the last `--set` of it (or, for a surface's key,
    /// of any surface), else the scene's origin. For errors found after the scene was read
    /// (an optics key that cannot be traced).
    pub fn origin_of_key(&self, key: &str) -> String {
        let family = |k: &str| {
            if k.starts_with(SURFACES_KEY) {
                SURFACES_KEY.to_string()
            } else if k.starts_with(LENSES_KEY) {
                LENSES_KEY.to_string()
            } else {
                k.to_string()
            }
        };
        self.overrides
            .iter()
            .rev()
            .find(|text| {
                text.split_once('=')
                    .is_some_and(|(k, _)| family(k.trim()) == family(key))
            })
            .map(|text| override_origin(text.as_str()))
            .unwrap_or_else(|| self.origin.clone())
    }

    /// The origin of the most recent of `keys` to be set, else the scene's origin.
    fn origin_of(&self, sources: &Sources, keys: &[&str]) -> String {
        keys.iter()
            .filter_map(|k| sources.get(k))
            .max_by_key(|(n, _)| *n)
            .map(|(_, o)| o.clone())
            .unwrap_or_else(|| self.origin.clone())
    }

    fn validate_from(&self, sources: &Sources) -> Result<(), SceneError> {
        let invalid = |keys: &[&str], value: String, problem: String| SceneError::Invalid {
            origin: self.origin_of(sources, keys),
            key: keys[0].to_string(),
            value,
            problem,
        };
        for spec in KEYS {
            let check = match spec.get(self) {
                KeyValue::Float(x) => spec.rule.check_float(x),
                KeyValue::Count(n) => spec.rule.check_count(n),
                KeyValue::Floats(xs) => spec.rule.check_floats(&xs),
                _ => Ok(()),
            };
            if let Err(problem) = check {
                return Err(invalid(&[spec.key], show(&spec.get(self)), problem));
            }
        }
        // Limits that tie keys together; every key is finite and in its own range by now.
        let p = &self.params;
        let p_max = crate::model::cornea::max_pressure(&p.cornea);
        if p.dp > p_max {
            return Err(invalid(
                &["pressure.dP", "cornea.C", "cornea.H", "cornea.R0"],
                show(&KeyValue::Float(p.dp)),
                format!(
                    "is above the cornea's limit: the largest admissible ΔP is {} kPa \
                     (4 C_c H_c / R_c · (6/7) · 7^(-1/6) with cornea.C = {}, cornea.H = {}, cornea.R0 = {})",
                    decimals6(p_max),
                    number(p.cornea.c),
                    number(p.cornea.h),
                    number(p.cornea.r0)
                ),
            ));
        }
        let length = p.length();
        if self.solver.epsilon >= length {
            return Err(invalid(
                &["solver.epsilon", "geometry.R0", "geometry.fraction"],
                show(&KeyValue::Float(self.solver.epsilon)),
                format!(
                    "must be below the shell's length L = π·fraction·R0 = {} mm \
                     (geometry.fraction = {}, geometry.R0 = {})",
                    decimals6(length),
                    number(p.fraction),
                    number(p.r0)
                ),
            ));
        }
        self.validate_mesh(sources)?;
        self.validate_sizes(sources)?;
        if self.stimulus_source() == Source::Optics {
            // The whole run: growth.t_end, or the [0, 1] an elastic scene's eye is drawn over.
            let t_end = self.growth.as_ref().map_or(1.0, |g| g.t_end);
            if let Err(e) = self.optics().check_over(t_end) {
                return Err(SceneError::Invalid {
                    origin: self.origin_of(sources, &[source_key(&e.key)]),
                    key: e.key,
                    value: e.value,
                    problem: e.problem,
                });
            }
        }
        if self.growth.is_some() {
            let o = self.optics();
            if !o.lenses.is_empty() && self.stimulus_source() != Source::Optics {
                return Err(invalid(
                    &["optics.lenses"],
                    crate::model::eyewear::lenses_text(&o.lenses),
                    "need stimulus.source = \"optics\": the published surfaces are of the naked eye".into(),
                ));
            }
            if !(o.myopia_d >= -25.0 && o.myopia_d <= 0.0) {
                return Err(invalid(
                    &["stimulus.myopia_D"],
                    number(o.myopia_d),
                    "must lie in [-25, 0] D".into(),
                ));
            }
            if !(o.hyperopia_d >= 0.0 && o.hyperopia_d <= 25.0) {
                return Err(invalid(
                    &["stimulus.hyperopia_D"],
                    number(o.hyperopia_d),
                    "must lie in [0, 25] D".into(),
                ));
            }
            let (lo, hi, why) = o.wavelength_range();
            if !(o.refraction_wavelength >= lo && o.refraction_wavelength <= hi) {
                return Err(invalid(
                    &["optics.refraction_wavelength", "optics.eye"],
                    number(o.refraction_wavelength),
                    format!("must lie between {lo} and {hi} nm {why}"),
                ));
            }
        }
        if self.solver.richardson && self.growth.is_some() {
            return Err(invalid(
                &["solver.richardson"],
                show(&KeyValue::Bool(true)),
                "is for elastic solves only: a growth run is not extrapolated".into(),
            ));
        }
        if let Some(g) = &self.growth {
            // The clock and the schedule: each problem names its key and shows its value.
            if let Some((key, problem)) = (g.clock.check())
                .and_then(|()| g.clock.check_window(g.t_end))
                .and_then(|()| g.schedule.check())
                .and_then(|()| g.schedule.check_window(&g.clock, g.t_end))
                .err()
            {
                let value =
                    crate::scene::keys::find(key).map_or_else(String::new, |k| show(&k.get(self)));
                return Err(invalid(&[key], value, problem));
            }
            // A schedule runs the model on its own clock S(t) (growth/schedule.rs), which is
            // exact only while nothing but the rates depends on t: optics that change with
            // age read t itself.
            if !g.schedule.is_constant()
                && self.stimulus_source() == Source::Optics
                && !self.optics().times().is_empty()
            {
                return Err(invalid(
                    &["growth.schedule"],
                    show(&crate::scene::keys::find("growth.schedule").map_or(KeyValue::Unset, |k| k.get(self))),
                    "cannot be combined with optics that change with age (tables over t in optics.surfaces): the schedule runs the model on its own clock".into(),
                ));
            }
            let times = &self.growth_settings.output_times;
            if let Some(&last) = times.last().filter(|&&t| t > g.t_end) {
                return Err(invalid(
                    &["output.times", "growth.t_end"],
                    show(&KeyValue::Floats(times.clone())),
                    format!(
                        "must lie in (0, growth.t_end]: {} is after growth.t_end = {}",
                        number(last),
                        number(g.t_end)
                    ),
                ));
            }
        }
        Ok(())
    }
}

impl Scene {
    /// What a run of this scene will allocate and write, counted before it starts: the
    /// largest mesh any of its solves lays (with solver.richardson, the mesh halved twice)
    /// must fit [`crate::mesh::MAX_NODES`], which bounds a solve's memory
    /// ([`crate::mesh::BYTES_PER_NODE`] a node); a growth run's files together must fit
    /// [`crate::rundir::growth::MAX_RUN_BYTES`]. The mesh itself is valid by now.
    fn validate_sizes(&self, sources: &Sources) -> Result<(), SceneError> {
        use crate::mesh::{BYTES_PER_NODE, MAX_NODES};
        let invalid = |keys: &[&str], value: String, problem: String| SceneError::Invalid {
            origin: self.origin_of(sources, keys),
            key: keys[0].to_string(),
            value,
            problem,
        };
        let gb = |bytes: u64| format!("{:.1} GB", bytes as f64 / 1e9);
        // The nodes of the mesh solver.nodes lays (breakpoints at most 3 more).
        let planned = crate::bvp::solve::mesh_plan(&self.params, &self.solver)
            .map(|plan| plan.nodes(3))
            .unwrap_or(MAX_NODES);
        if self.solver.richardson {
            // Without solver.tol: solves on M, M halved and M halved twice (4M − 3 nodes).
            // With it, the adapted mesh M has at most ⌈max_nodes / 2⌉ nodes, so M halved
            // twice at most 2·max_nodes + 1.
            let (keys, value, finest, fix): (&[&str], usize, usize, String) = match self.solver.tol
            {
                None => (
                    &["solver.nodes", "solver.richardson"],
                    self.solver.nodes,
                    4 * planned.saturating_sub(1) + 1,
                    format!(
                        "solver.nodes at most about {}",
                        (MAX_NODES - 1) / 4 + 1 - (planned - self.solver.nodes.min(planned))
                    ),
                ),
                Some(_) => (
                    &["solver.max_nodes", "solver.richardson"],
                    self.solver.max_nodes,
                    2 * self.solver.max_nodes + 1,
                    format!("solver.max_nodes at most {}", (MAX_NODES - 1) / 2),
                ),
            };
            if finest > MAX_NODES {
                return Err(invalid(
                    keys,
                    value.to_string(),
                    format!(
                        "is too large with solver.richardson: its solve on the mesh halved twice would lay {finest} nodes, about {} of memory, more than the {MAX_NODES} nodes ({}) a solve may: give {fix}, or leave out solver.richardson",
                        gb(finest as u64 * BYTES_PER_NODE),
                        gb(MAX_NODES as u64 * BYTES_PER_NODE)
                    ),
                ));
            }
        }
        if self.growth.is_some() {
            use crate::rundir::growth::{planned_bytes, MAX_RUN_BYTES};
            let g = &self.growth_settings;
            // With solver.tol the mesh is chosen as the run starts: at most max_nodes.
            let (nodes, keys): (usize, &[&str]) = match self.solver.tol {
                None => (planned, &["output.times", "solver.nodes"]),
                Some(_) => (self.solver.max_nodes, &["output.times", "solver.max_nodes"]),
            };
            let bytes = planned_bytes(nodes, g.output_times.len(), g.history_points);
            if bytes > MAX_RUN_BYTES {
                return Err(invalid(
                    keys,
                    show(&KeyValue::Floats(g.output_times.clone())),
                    format!(
                        "would have the run write about {} ({} snapshot files of up to {nodes} nodes each, and the series), more than the {} a growth run may write: give fewer output.times or fewer nodes",
                        gb(bytes),
                        g.output_times.len() + 1,
                        gb(MAX_RUN_BYTES)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The mesh the solver will lay, counted before anything is allocated: every derived
    /// size (the shell's length, the pole's and the cornea's graded nodes, the total) must
    /// be finite and bounded (docs/MODEL.md §3–4, [`crate::mesh::plan`]).
    fn validate_mesh(&self, sources: &Sources) -> Result<(), SceneError> {
        use crate::mesh::MeshError;
        let Err(e) = crate::bvp::solve::mesh_plan(&self.params, &self.solver) else {
            return Ok(());
        };
        let (keys, value, problem): (&[&str], String, String) = match &e {
            MeshError::Interval { length, .. } => (
                &["geometry.R0", "geometry.fraction", "solver.epsilon"],
                number(self.params.r0),
                format!("makes the shell's length L = π·fraction·R0 = {} mm, which is not finite", number(*length)),
            ),
            MeshError::TooFewNodes { .. } | MeshError::TooManyNodes { .. } => (
                &["solver.nodes", "solver.epsilon", "material.bending", "solver.cornea_grading"],
                self.solver.nodes.to_string(),
                format!("is too large for the mesh: {e}"),
            ),
            MeshError::LayerUnresolvable { .. } => (
                &["material.bending", "solver.cornea_grading"],
                number(self.params.e_b),
                format!("is too small for this shell (ΔP, R0): {e}; raise material.bending or set solver.cornea_grading = false"),
            ),
        };
        Err(SceneError::Invalid {
            origin: self.origin_of(sources, keys),
            key: keys[0].to_string(),
            value,
            problem,
        })
    }
}

/// The key of the eye's surfaces.
const SURFACES_KEY: &str = "optics.surfaces";
/// The key of the lenses in front of the eye.
const LENSES_KEY: &str = "optics.lenses";

/// The table key under which the origin of `key` is recorded: a surface's own key
/// (`optics.surfaces[2].radius`) is recorded as the surfaces'.
fn source_key(key: &str) -> &'static str {
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
fn flatten(
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

pub(crate) fn unknown_key(origin: &str, key: &str) -> SceneError {
    SceneError::UnknownKey {
        origin: origin.to_string(),
        key: crate::text::excerpt(key, 80),
        suggestion: closest(key, KEYS.iter().map(|k| k.key)).map(str::to_string),
    }
}

/// The known name closest to `name`, if it is close enough to be a likely typo: same name
/// in another case, the same last component in another section, or a small edit distance.
pub(crate) fn closest<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_lowercase();
    let last = lower.rsplit('.').next().unwrap_or(&lower).to_string();
    let length = lower.chars().count();
    let limit = 2.max(length / 3);
    known
        .map(|k| {
            let kl = k.to_lowercase();
            let score = if kl == lower {
                0
            } else if kl.rsplit('.').next() == Some(last.as_str()) {
                1
            } else if kl.chars().count().abs_diff(length) > limit {
                // Too far apart in length to be within the limit: no need to measure (a
                // megabyte-long name would take seconds).
                usize::MAX
            } else {
                levenshtein(&lower, &kl)
            };
            (score, k)
        })
        .filter(|(score, _)| *score <= limit)
        .min_by_key(|(score, _)| *score)
        .map(|(_, k)| k)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
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

fn describe_string(s: &str) -> String {
    let short: String = s.chars().take(60).collect();
    let ell = if s.chars().count() > 60 { "…" } else { "" };
    format!("\"{}{ell}\"", short.escape_debug())
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

/// The environment variable giving a growth run's threads under solver.tol
/// ([`crate::bvp::settings::SolverSettings::threads`]) when `eyeshell grow --jobs` does not.
pub const JOBS_ENV: &str = "EYESHELL_JOBS";

/// [`JOBS_ENV`]'s value: None when unset or empty, else an integer from 1 to 1024.
pub fn jobs_from_env() -> Result<Option<usize>, crate::Error> {
    let Some(raw) = std::env::var_os(JOBS_ENV) else {
        return Ok(None);
    };
    let text = raw.to_string_lossy();
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    match text.parse::<usize>() {
        Ok(n) if (1..=1024).contains(&n) => Ok(Some(n)),
        _ => Err(crate::Error::Input(format!(
            "{JOBS_ENV} = {:?} is not a thread count (an integer from 1 to 1024)",
            crate::text::excerpt(text, 40)
        ))),
    }
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

#[cfg(test)]
mod tests;
