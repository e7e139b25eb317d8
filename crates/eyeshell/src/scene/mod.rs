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
pub mod names;
pub mod optics_toml;
pub mod sample;
pub mod sensitivity;
pub mod sweep;

mod parse;
pub(crate) use parse::indexed;
mod stimulus;
mod suggest;
mod validate;
mod view;

use parse::{flatten, source_key};

use std::collections::BTreeMap;
use std::path::Path;

use crate::bvp::settings::SolverSettings;
use crate::growth::{GrowthParams, GrowthSettings};
use crate::model::optics::{OpticsSpec, Source};
use crate::model::params::Params;
use crate::model::stimulus::Surface;
pub use keys::{Access, KeySpec, KeyValue, Rule, KEYS};
pub(crate) use parse::parse_table;
pub use parse::{read_scene_file, sections, MAX_SCENE_BYTES};
pub(crate) use suggest::{closest, unknown_key};
pub(crate) use view::{describe, show};

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
    /// growth.t_end and output.times as the scene writes them (ages with time.unit), from
    /// which [`Scene::growth`] and [`Scene::growth_settings`] hold them on the model's
    /// clock ([`Scene::sync_clock`]).
    pub written_clock: WrittenClock,
}

/// The times a scene writes, before they are put on the model's clock: with time.unit,
/// `output.times` are ages and the run lasts time.end − time.start, so the model's
/// t = age − time.start (docs/guide/years.md); without, they are the model's t as written.
#[derive(Clone, Debug, Default)]
pub struct WrittenClock {
    /// growth.t_end, if the scene gives it.
    pub t_end: Option<f64>,
    /// output.times, if the scene gives them.
    pub output_times: Option<Vec<f64>>,
    /// The age subtracted from the times of the optics' tables now (time.start with ages,
    /// else 0): the tables of [`Scene::optics`] are on the model's clock, these plus it are
    /// as written.
    pub optics_origin: f64,
    /// Whether the optics' tables are written over `t`, over `age` (both may be seen).
    pub optics_time_keys: (bool, bool),
}

/// Two scenes are equal when they run alike: what a run reads is on the model's clock in
/// [`Scene::growth`] and [`Scene::growth_settings`], which scenes are compared by; whether a
/// time was written or is the default only says how a later change of time.* moves it
/// (a scene written out by [`Scene::to_toml`] gives every time, and reads back equal).
impl PartialEq for WrittenClock {
    fn eq(&self, _: &WrittenClock) -> bool {
        true
    }
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
        // Every scene starts here: from the first on, core's messages name keys.
        names::speak_in_keys();
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
            written_clock: WrittenClock::default(),
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

    /// The value at fault as it was written, when one is.
    pub fn value(&self) -> Option<&str> {
        match self {
            SceneError::Invalid { value, .. } => Some(value),
            _ => None,
        }
    }

    /// Where the scene or value came from: the file's path, the override (`--set
    /// key=value`, a Python keyword), the text's name.
    pub fn origin(&self) -> &str {
        match self {
            SceneError::Read { path, .. } => path,
            SceneError::Syntax { origin, .. }
            | SceneError::UnknownKey { origin, .. }
            | SceneError::UnknownSection { origin, .. }
            | SceneError::WrongType { origin, .. }
            | SceneError::Invalid { origin, .. }
            | SceneError::BadOverride { origin, .. }
            | SceneError::IsSweep { origin }
            | SceneError::BadSweep { origin, .. } => origin,
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

    /// Put the written growth.t_end and output.times on the model's clock. With time.unit
    /// and both ages of the window, the run lasts time.end − time.start and each output
    /// time is its age less time.start (k = 1: every rate, η0 first, is per unit of
    /// time.unit, so moving the window keeps the growth per year); output times not written
    /// are the default fractions of that window. Without a unit, the written times are the
    /// model's t. Called by the setters of the five keys involved, so the result does not
    /// depend on the order they are set in.
    pub(crate) fn sync_clock(&mut self) {
        let Some(g) = self.growth.as_mut() else {
            return;
        };
        // A clock that cannot be used is left for validation to name (time.end before
        // time.start, say), not turned into a window it would blame on growth.t_end.
        let window = g.clock.window().filter(|_| g.clock.check().is_ok());
        let defaults = GrowthSettings::default().output_times;
        let written = &self.written_clock;
        let times = match window {
            Some((a0, a1)) => {
                g.t_end = a1 - a0;
                match &written.output_times {
                    Some(ages) => ages.iter().map(|a| a - a0).collect(),
                    None => defaults.iter().map(|f| f * (a1 - a0)).collect(),
                }
            }
            None => {
                g.t_end = written.t_end.unwrap_or(GrowthParams::default().t_end);
                written.output_times.clone().unwrap_or(defaults)
            }
        };
        self.growth_settings.output_times = times;
        // The optics' tables (ages with time.unit) onto the model's clock.
        let origin = window.map_or(0.0, |w| w.0);
        let by = self.written_clock.optics_origin - origin;
        if by != 0.0 && !self.optics().times().is_empty() {
            self.set_optics(|o| o.surfaces.iter_mut().for_each(|s| s.shift_times(by)));
        }
        self.written_clock.optics_origin = origin;
        let clock = crate::model::eye::TableClock {
            ages_from: window.map(|w| w.0),
        };
        if self.optics().table_clock != clock {
            self.set_optics(|o| o.table_clock = clock);
        }
    }

    /// Give the optics' surfaces as the scene writes them (tables over ages with time.unit)
    /// and put them on the model's clock ([`Scene::sync_clock`]).
    pub(crate) fn set_surfaces_as_written(
        &mut self,
        surfaces: Vec<crate::model::eye::SurfaceSpec>,
    ) {
        self.set_optics(|o| o.surfaces = surfaces);
        self.written_clock.optics_origin = 0.0;
        self.sync_clock();
    }

    /// The optics' surfaces as the scene writes them: their tables over ages with
    /// time.unit.
    pub(crate) fn surfaces_as_written(&self) -> Vec<crate::model::eye::SurfaceSpec> {
        let mut surfaces = self.optics().surfaces.clone();
        let by = self.written_clock.optics_origin;
        if by != 0.0 {
            surfaces.iter_mut().for_each(|s| s.shift_times(by));
        }
        surfaces
    }

    /// What the optics' tables' times are named when written: `age` in a scene that counts
    /// in ages, else `t`.
    pub(crate) fn table_time_key(&self) -> optics_toml::TimeKey {
        match self.growth.as_ref().and_then(|g| g.clock.window()) {
            Some(_) => optics_toml::TimeKey::Age,
            None => optics_toml::TimeKey::T,
        }
    }

    /// output.times as the scene writes them: ages with time.unit.
    pub(crate) fn written_output_times(&self) -> Vec<f64> {
        if let Some(times) = &self.written_clock.output_times {
            return times.clone();
        }
        let start = self
            .growth
            .as_ref()
            .and_then(|g| g.clock.window())
            .map_or(0.0, |w| w.0);
        let times = &self.growth_settings.output_times;
        times.iter().map(|t| t + start).collect()
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
        _ => Err(crate::Error::input(
            crate::Subject::Argument(JOBS_ENV.into()),
            format!(
                "{JOBS_ENV} = {:?} is not a thread count (an integer from 1 to 1024)",
                crate::text::excerpt(text, 40)
            ),
        )
        .with_value(text)
        .with_origin(crate::Origin::Environment(JOBS_ENV.into()))),
    }
}

#[cfg(test)]
mod tests;
