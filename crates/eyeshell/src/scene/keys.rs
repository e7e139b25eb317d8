//! The table of scene keys: the one place where a key's name, type, default, documentation,
//! range and setter live. Parsing, `--set`, validation messages, `eyeshell keys`, `eyeshell
//! check` and the parameters in summary.json are all driven by [`KEYS`].
//!
//! To add a key, add one [`KeySpec`] here (and the field it sets); nothing else needs to change.

use super::Scene;
use crate::bvp::settings::{LinearSolverKind, Scheme};
use crate::growth::schedule::{Form, TimeUnit};
use crate::growth::settings::{DaeLinear, GrowthParams, Integrator};
use crate::growth::ThicknessLaw;
use crate::model::eye::SurfaceSpec;
use crate::model::eyewear::{lenses_toml, LensSpec, CLASSIFY};
use crate::model::optics::{Source, EYES, FOCUS_NAMES, SOURCES};
use crate::model::params::Thickness;
use crate::scene::optics_toml::SurfaceToml;

/// How a key is read from and written to a [`Scene`]; the variant is the key's type.
#[derive(Clone, Copy)]
pub enum Access {
    /// A real number; TOML integers are accepted too (`dP = 2`).
    Float {
        get: fn(&Scene) -> f64,
        set: fn(&mut Scene, f64),
    },
    /// A non-negative integer.
    Count {
        get: fn(&Scene) -> usize,
        set: fn(&mut Scene, usize),
    },
    /// `true` or `false`.
    Bool {
        get: fn(&Scene) -> bool,
        set: fn(&mut Scene, bool),
    },
    /// One of a fixed list of strings; get/set work with the index into `names`.
    Choice {
        names: &'static [&'static str],
        get: fn(&Scene) -> usize,
        set: fn(&mut Scene, usize),
    },
    /// A real number that may be left unset (the key's default is no value: the feature
    /// it bounds is off); TOML integers are accepted too.
    OptionalFloat {
        get: fn(&Scene) -> Option<f64>,
        set: fn(&mut Scene, f64),
    },
    /// Free text (scene metadata, not a parameter of the model).
    Text {
        get: fn(&Scene) -> Option<String>,
        set: fn(&mut Scene, String),
    },
    /// A list of real numbers (`[0.1, 0.2, 1.0]`); TOML integers are accepted too, and a
    /// single number is a list of one.
    Floats {
        get: fn(&Scene) -> Vec<f64>,
        set: fn(&mut Scene, Vec<f64>),
    },
    /// Eyewear: an array of lens tables (`[[optics.lenses]]`), each checked as it is read.
    Lenses {
        get: fn(&Scene) -> Vec<LensSpec>,
        set: fn(&mut Scene, Vec<LensSpec>),
    },
    /// The eye's surfaces: an array of tables (`[[optics.surfaces]]`), each a surface's keys
    /// (model/eye.rs); one of them is set alone as `optics.surfaces[i].key`.
    Surfaces {
        get: fn(&Scene) -> Vec<SurfaceSpec>,
        set: fn(&mut Scene, Vec<SurfaceSpec>),
    },
}

/// The admissible range of a single key (cross-key limits are checked in `Scene::validate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// No range restriction (floats must still be finite).
    Any,
    /// > 0.
    Positive,
    /// ≥ 0.
    NonNegative,
    /// An integer ≥ n.
    AtLeast(usize),
    /// An integer in [lo, hi]: counts that size an allocation or a loop are bounded.
    Count(usize, usize),
    /// Strictly between 0 and 1.
    OpenUnit,
    /// At least 0 and below 1.
    UnitFromZero,
    /// An angle strictly between 0 and π.
    OpenHalfTurn,
    /// A list of 1 to n positive numbers in strictly increasing order (times, each one a
    /// file written: the length is bounded).
    PositiveIncreasing(usize),
    /// A span of time at least [`MIN_T_END`].
    Duration,
    /// A list of at most n finite numbers.
    List(usize),
}

// The shortest growth run: growth owns it (its schedules check against it too).
pub use crate::growth::settings::MIN_T_END;

impl Rule {
    /// A short description for `eyeshell keys`.
    pub fn describe(self) -> String {
        match self {
            Rule::Any => String::new(),
            Rule::Positive => "> 0".into(),
            Rule::NonNegative => ">= 0".into(),
            Rule::AtLeast(n) => format!(">= {n}"),
            Rule::Count(lo, hi) => format!("{lo} to {hi}"),
            Rule::OpenUnit => "in (0, 1)".into(),
            Rule::UnitFromZero => "in [0, 1)".into(),
            Rule::OpenHalfTurn => "in (0, π)".into(),
            Rule::PositiveIncreasing(n) => {
                format!("1 to {n} values, each > 0, strictly increasing")
            }
            Rule::Duration => format!(">= {}", crate::text::number(MIN_T_END)),
            Rule::List(n) => format!("at most {n} values"),
        }
    }

    /// Whether `x` keeps this rule.
    ///
    /// # Errors
    /// The [`RuleError`] it breaks; its Display ends a sentence "KEY = x ...".
    pub fn check_float(self, x: f64) -> Result<(), RuleError> {
        if !x.is_finite() {
            return Err(RuleError::NotFinite);
        }
        match self {
            // x is finite here, so plain comparisons are exact.
            Rule::Positive if x <= 0.0 => Err(RuleError::NotPositive),
            Rule::NonNegative if x < 0.0 => Err(RuleError::Negative),
            Rule::AtLeast(n) if x < n as f64 => Err(RuleError::BelowLeast { least: n }),
            Rule::Count(lo, hi) if x < lo as f64 || x > hi as f64 => {
                Err(RuleError::OutOfRange { lo, hi })
            }
            Rule::OpenUnit if x <= 0.0 || x >= 1.0 => Err(RuleError::NotInOpenUnit),
            Rule::UnitFromZero if !(0.0..1.0).contains(&x) => Err(RuleError::NotInUnitFromZero),
            Rule::OpenHalfTurn if x <= 0.0 || x >= std::f64::consts::PI => {
                Err(RuleError::NotInOpenHalfTurn)
            }
            Rule::PositiveIncreasing(_) if x <= 0.0 => Err(RuleError::NotPositive),
            Rule::Duration if x < MIN_T_END => Err(RuleError::TooShort),
            _ => Ok(()),
        }
    }

    /// Whether the list `xs` keeps this rule. Lists are never sorted for the user: an
    /// unsorted list is an error, since it is more likely a typo than a wish.
    ///
    /// # Errors
    /// The [`RuleError`] it breaks, naming the item (counted from 1).
    pub fn check_floats(self, xs: &[f64]) -> Result<(), RuleError> {
        if let Rule::List(max) = self {
            if xs.len() > max {
                return Err(RuleError::TooManyValues { len: xs.len(), max });
            }
        }
        if let Rule::PositiveIncreasing(max) = self {
            if xs.is_empty() {
                return Err(RuleError::NoTimes);
            }
            if xs.len() > max {
                return Err(RuleError::TooManyTimes { len: xs.len(), max });
            }
        }
        for (i, &x) in xs.iter().enumerate() {
            if !x.is_finite() {
                return Err(RuleError::NotFiniteItem { item: i + 1, x });
            }
            if matches!(self, Rule::PositiveIncreasing(_)) {
                if x <= 0.0 {
                    return Err(RuleError::NotPositiveItem { item: i + 1, x });
                }
                if i > 0 && x <= xs[i - 1] {
                    return Err(RuleError::NotIncreasing {
                        x,
                        previous: xs[i - 1],
                    });
                }
            }
        }
        Ok(())
    }

    /// Whether the count `n` keeps this rule.
    ///
    /// # Errors
    /// The [`RuleError`] it breaks.
    pub fn check_count(self, n: usize) -> Result<(), RuleError> {
        match self {
            Rule::AtLeast(m) if n < m => Err(RuleError::BelowLeast { least: m }),
            Rule::Count(lo, hi) if n < lo || n > hi => Err(RuleError::OutOfRange { lo, hi }),
            Rule::Positive if n == 0 => Err(RuleError::NotPositive),
            _ => Ok(()),
        }
    }
}

/// How a value breaks its key's [`Rule`]; Display ends a sentence "KEY = value ...".
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RuleError {
    #[error("must be a finite number")]
    NotFinite,
    #[error("must be positive")]
    NotPositive,
    #[error("must be non-negative")]
    Negative,
    #[error("must be at least {least}")]
    BelowLeast { least: usize },
    #[error("must lie between {lo} and {hi}")]
    OutOfRange { lo: usize, hi: usize },
    #[error("must lie strictly between 0 and 1")]
    NotInOpenUnit,
    #[error("must lie in [0, 1)")]
    NotInUnitFromZero,
    #[error("must lie strictly between 0 and π (radians)")]
    NotInOpenHalfTurn,
    /// A growth run shorter than [`MIN_T_END`].
    #[error("must be at least {}: the integrators multiply times by their steps, and for a shorter run that product underflows", crate::text::number(MIN_T_END))]
    TooShort,
    #[error("lists {len} values, more than the {max} allowed")]
    TooManyValues { len: usize, max: usize },
    #[error("must list at least one time")]
    NoTimes,
    #[error("lists {len} times, more than the {max} allowed (each time is a snapshot file of every node): for a curve at many times use output.history_points")]
    TooManyTimes { len: usize, max: usize },
    #[error("must hold finite numbers only (item {item} is {})", crate::text::number(*.x))]
    NotFiniteItem { item: usize, x: f64 },
    #[error("must hold positive numbers only (item {item} is {})", crate::text::number(*.x))]
    NotPositiveItem { item: usize, x: f64 },
    #[error("must be strictly increasing (they are not sorted for you): {} follows {}", crate::text::number(*.x), crate::text::number(*.previous))]
    NotIncreasing { x: f64, previous: f64 },
}

/// One scene key.
#[derive(Clone, Copy)]
pub struct KeySpec {
    /// The dotted key, `section.name` (or a bare top-level name).
    pub key: &'static str,
    /// Type and accessors.
    pub access: Access,
    /// Admissible range.
    pub rule: Rule,
    /// One-line documentation (units, meaning, docs/MODEL.md section).
    pub doc: &'static str,
    /// A key of the growth model or of its numerics: shown, written and summarised only
    /// when the scene grows (a scene without `growth.*` keys is a pure elastic scene).
    pub growth: bool,
}

/// A typed value of a scene key.
#[derive(Clone, Debug, PartialEq)]
pub enum KeyValue {
    Float(f64),
    Count(usize),
    Bool(bool),
    Choice(&'static str),
    Text(Option<String>),
    Floats(Vec<f64>),
    Lenses(Vec<LensSpec>),
    /// An [`Access::Surfaces`] key: one TOML table a surface.
    Tables(Vec<toml::Value>),
    /// An [`Access::OptionalFloat`] key left unset.
    Unset,
}

impl KeyValue {
    /// The value as JSON (non-finite floats become null, as JSON has no NaN).
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            KeyValue::Float(x) => serde_json::Number::from_f64(*x)
                .map(serde_json::Value::Number)
                .unwrap_or(serde_json::Value::Null),
            KeyValue::Count(n) => serde_json::Value::from(*n),
            KeyValue::Bool(b) => serde_json::Value::Bool(*b),
            KeyValue::Choice(s) => serde_json::Value::from(*s),
            KeyValue::Text(Some(s)) => serde_json::Value::from(s.as_str()),
            KeyValue::Text(None) | KeyValue::Unset => serde_json::Value::Null,
            KeyValue::Floats(xs) => {
                serde_json::Value::Array(xs.iter().map(|x| KeyValue::Float(*x).to_json()).collect())
            }
            // An array of objects, which summary.json's reader turns back into TOML tables.
            KeyValue::Lenses(l) => format!("v = {}", lenses_toml(l))
                .parse::<toml::Table>()
                .ok()
                .and_then(|t| serde_json::to_value(&t["v"]).ok())
                .unwrap_or(serde_json::Value::Null),
            KeyValue::Tables(ts) => serde_json::Value::Array(ts.iter().map(toml_to_json).collect()),
        }
    }
}

/// The value as a TOML literal that reads back to the same value (floats keep a `.` or an
/// exponent and all their digits).
impl std::fmt::Display for KeyValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KeyValue::Float(x) if x.is_nan() => f.write_str("nan"),
            KeyValue::Float(x) if x.is_infinite() => {
                f.write_str(if *x > 0.0 { "inf" } else { "-inf" })
            }
            KeyValue::Float(x) => write!(f, "{x:?}"),
            KeyValue::Count(n) => write!(f, "{n}"),
            KeyValue::Bool(b) => write!(f, "{b}"),
            KeyValue::Choice(s) => write!(f, "\"{s}\""),
            KeyValue::Text(Some(s)) => write!(f, "{}", toml::Value::String(s.clone())),
            KeyValue::Text(None) | KeyValue::Unset => f.write_str("(none)"),
            KeyValue::Floats(xs) => {
                f.write_str("[")?;
                for (i, x) in xs.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{}", KeyValue::Float(*x))?;
                }
                f.write_str("]")
            }
            KeyValue::Lenses(l) => f.write_str(&lenses_toml(l)),
            KeyValue::Tables(ts) => write!(f, "{}", toml::Value::Array(ts.clone())),
        }
    }
}

/// A TOML value as JSON; non-finite floats, which JSON lacks, as the strings "inf", "-inf"
/// and "nan", which a surface's keys read back (a plane's radius is inf).
fn toml_to_json(v: &toml::Value) -> serde_json::Value {
    match v {
        toml::Value::Float(x) if !x.is_finite() => {
            serde_json::Value::from(KeyValue::Float(*x).to_string())
        }
        toml::Value::Float(x) => KeyValue::Float(*x).to_json(),
        toml::Value::Integer(i) => serde_json::Value::from(*i),
        toml::Value::String(s) => serde_json::Value::from(s.as_str()),
        toml::Value::Boolean(b) => serde_json::Value::Bool(*b),
        toml::Value::Datetime(d) => serde_json::Value::from(d.to_string()),
        toml::Value::Array(a) => serde_json::Value::Array(a.iter().map(toml_to_json).collect()),
        toml::Value::Table(t) => serde_json::Value::Object(
            t.iter()
                .map(|(k, v)| (k.clone(), toml_to_json(v)))
                .collect(),
        ),
    }
}

impl KeySpec {
    /// The key's type as shown by `eyeshell keys`.
    pub fn type_name(&self) -> String {
        match self.access {
            Access::Float { .. } | Access::OptionalFloat { .. } => "float".into(),
            Access::Count { .. } => "integer".into(),
            Access::Bool { .. } => "bool".into(),
            Access::Choice { names, .. } => names
                .iter()
                .map(|n| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(" | "),
            Access::Text { .. } => "string".into(),
            Access::Floats { .. } => "list of floats".into(),
            Access::Lenses { .. } => "array of lens tables".into(),
            Access::Surfaces { .. } => "array of surface tables".into(),
        }
    }

    /// The key's value in `scene`.
    pub fn get(&self, scene: &Scene) -> KeyValue {
        match self.access {
            Access::Float { get, .. } => KeyValue::Float(get(scene)),
            Access::OptionalFloat { get, .. } => {
                get(scene).map_or(KeyValue::Unset, KeyValue::Float)
            }
            Access::Count { get, .. } => KeyValue::Count(get(scene)),
            Access::Bool { get, .. } => KeyValue::Bool(get(scene)),
            Access::Choice { names, get, .. } => KeyValue::Choice(names[get(scene)]),
            Access::Text { get, .. } => KeyValue::Text(get(scene)),
            Access::Floats { get, .. } => KeyValue::Floats(get(scene)),
            Access::Lenses { get, .. } => KeyValue::Lenses(get(scene)),
            // No surface tables is no value: the built-in eye as its source gives it.
            Access::Surfaces { get, .. } => match get(scene) {
                s if s.is_empty() => KeyValue::Unset,
                s => KeyValue::Tables(
                    s.iter()
                        .map(|s| s.to_toml_with(scene.table_time_key()))
                        .collect(),
                ),
            },
        }
    }

    /// The key's default: its value in `Scene::default()` (the Default impls in params.rs).
    pub fn default_value(&self) -> KeyValue {
        self.get(&Scene::default())
    }

    /// True for keys that are parameters of the problem (not scene metadata).
    pub fn is_parameter(&self) -> bool {
        !matches!(self.access, Access::Text { .. })
    }

    /// True when the key is in use in `scene`: every elastic key, and the growth keys
    /// when the scene grows.
    pub fn applies_to(&self, scene: &Scene) -> bool {
        // The optics keys, and the source that turns them on, apply only to a stimulus
        // computed from them or to an eye the scene sets: a scene of the published surfaces
        // shows and summarises them as it did before they existed.
        if matches!(self.key, "stimulus.myopia_D" | "stimulus.hyperopia_D") {
            return scene.growth.is_some() && scene.optics().classify == 1;
        }
        if self.key == "stimulus.source" {
            return scene.growth.is_some() && scene.stimulus_source() == Source::Optics;
        }
        // In a growing scene the optics apply to a computed stimulus only; a scene that does
        // not grow keeps an eye of its own for `eyeshell optics`.
        if self.section() == Some("optics") {
            return match scene.growth {
                Some(_) => scene.stimulus_source() == Source::Optics,
                None => *scene.optics() != crate::model::optics::OpticsSpec::default(),
            };
        }
        !self.growth || scene.growth.is_some()
    }

    /// The section of a dotted key (`material` for `material.C`), if any.
    pub fn section(&self) -> Option<&'static str> {
        self.key.split_once('.').map(|(s, _)| s)
    }
}

/// Look a key up by its exact name.
pub fn find(key: &str) -> Option<&'static KeySpec> {
    KEYS.iter().find(|k| k.key == key)
}

/// The most Newton iterations one solve may be allowed (each may also spend a bounded
/// number of residual evaluations in its line search).
pub const MAX_NEWTON: usize = 10_000;
/// The most explicit Euler steps (each an elastic solve: a million take hours already).
pub const MAX_STEPS: usize = 1_000_000;
/// The most history rows (history.csv: about 100 bytes each).
pub const MAX_HISTORY_POINTS: usize = 1_000_000;
/// The most output times (snapshot files) of a growth run; the bytes they take together
/// are bounded too ([`crate::plan::MAX_RUN_BYTES`]).
pub const MAX_OUTPUT_TIMES: usize = 1_000;

const THICKNESS: &[&str] = &["uniform", "nonuniform"];
const SCHEMES: &[&str] = &["trapezoid", "hermite-simpson"];
const LINEAR: &[&str] = &["band", "klu", "block"];
/// The most points of a schedule table.
pub const MAX_SCHEDULE_POINTS: usize = 1000;

const THICKNESS_LAWS: &[&str] = &["none", "mass"];
const INTEGRATORS: &[&str] = &Integrator::NAMES;
const SOURCE_NAMES: &[&str] = &SOURCES;
/// The names `stimulus.rule` takes.
const RULES: [&str; 3] = crate::model::rule::CATALOGUE;
const EYE_NAMES: &[&str] = &EYES;
const FOCI: &[&str] = &FOCUS_NAMES;

/// The growth parameters of `s`, or their defaults when the scene does not grow.
fn growth(s: &Scene) -> GrowthParams {
    s.growth.clone().unwrap_or_default()
}

/// Every scene key, in the order they are listed and validated.
pub static KEYS: &[KeySpec] = &[
    KeySpec {
        key: "name",
        access: Access::Text { get: |s| s.name.clone(), set: |s, v| s.name = Some(v) },
        rule: Rule::Any,
        doc: "name of the scene (defaults to the file name)",
        growth: false,
    },
    KeySpec {
        key: "description",
        access: Access::Text { get: |s| s.description.clone(), set: |s, v| s.description = Some(v) },
        rule: Rule::Any,
        doc: "free-text description of the scene",
        growth: false,
    },
    KeySpec {
        key: "pressure.dP",
        access: Access::Float { get: |s| s.params.dp, set: |s, v| s.params.dp = v },
        rule: Rule::NonNegative,
        doc: "pressure difference ΔP (kPa); at most the cornea's limit (docs/MODEL.md §3)",
        growth: false,
    },
    KeySpec {
        key: "material.C",
        access: Access::Float { get: |s| s.params.c, set: |s, v| s.params.c = v },
        rule: Rule::Positive,
        doc: "neo-Hookean modulus C of the sclera (kPa) (docs/MODEL.md §2)",
        growth: false,
    },
    KeySpec {
        key: "material.bending",
        access: Access::Float { get: |s| s.params.e_b, set: |s, v| s.params.e_b = v },
        rule: Rule::Positive,
        doc: "bending stiffness E_b (kPa·mm³) (docs/MODEL.md §2)",
        growth: false,
    },
    KeySpec {
        key: "material.thickness",
        access: Access::Choice {
            names: THICKNESS,
            get: |s| match s.params.thickness {
                Thickness::Uniform => 0,
                Thickness::NonUniform => 1,
            },
            set: |s, i| {
                s.params.thickness = if i == 0 { Thickness::Uniform } else { Thickness::NonUniform }
            },
        },
        rule: Rule::Any,
        doc: "thickness profile H(Σ): uniform H0, or the paper's two-piece tanh profile (docs/MODEL.md §4)",
        growth: false,
    },
    KeySpec {
        key: "material.H0",
        access: Access::Float { get: |s| s.params.h0, set: |s, v| s.params.h0 = v },
        rule: Rule::Positive,
        doc: "uniform thickness H0 (mm), used when material.thickness = \"uniform\" (docs/MODEL.md §4)",
        growth: false,
    },
    KeySpec {
        key: "fibres.D",
        access: Access::Float { get: |s| s.params.d, set: |s, v| s.params.d = v },
        rule: Rule::NonNegative,
        doc: "fibre stiffness D (kPa); 0 means no fibres (docs/MODEL.md §2)",
        growth: false,
    },
    KeySpec {
        key: "cornea.C",
        access: Access::Float { get: |s| s.params.cornea.c, set: |s, v| s.params.cornea.c = v },
        rule: Rule::Positive,
        doc: "cornea's neo-Hookean modulus C_c (kPa) (docs/MODEL.md §3)",
        growth: false,
    },
    KeySpec {
        key: "cornea.H",
        access: Access::Float { get: |s| s.params.cornea.h, set: |s, v| s.params.cornea.h = v },
        rule: Rule::Positive,
        doc: "cornea's thickness H_c (mm) (docs/MODEL.md §3)",
        growth: false,
    },
    KeySpec {
        key: "cornea.R0",
        access: Access::Float {
            get: |s| s.params.cornea.r0,
            set: |s, v| {
                s.params.cornea.r0 = v;
                s.params.cornea_follows_radius = false;
            },
        },
        rule: Rule::Positive,
        doc: "cornea's radius R_c (mm), geometry.R0 unless given (docs/MODEL.md §3)",
        growth: false,
    },
    KeySpec {
        key: "geometry.R0",
        access: Access::Float { get: |s| s.params.r0, set: |s, v| s.params.set_radius(v) },
        rule: Rule::Positive,
        doc: "radius R0 of the unloaded shell (mm): the eye's size, the shell's length π·fraction·R0 and the cornea's radius unless cornea.R0 is given (docs/MODEL.md §1)",
        growth: false,
    },
    KeySpec {
        key: "geometry.fraction",
        access: Access::Float { get: |s| s.params.fraction, set: |s, v| s.params.fraction = v },
        rule: Rule::OpenUnit,
        doc: "fraction f of the sphere that is sclera: L = π·f·R0 (docs/MODEL.md §1)",
        growth: false,
    },
    KeySpec {
        key: "solver.nodes",
        access: Access::Count { get: |s| s.solver.nodes, set: |s, v| s.solver.nodes = v },
        rule: Rule::Count(5, crate::mesh::MAX_NODES),
        doc: "number of uniform nodes on [ε, L]; breakpoint, pole and cornea nodes come on top (at most 1000000 nodes in all)",
        growth: false,
    },
    KeySpec {
        key: "solver.epsilon",
        access: Access::Float { get: |s| s.solver.epsilon, set: |s, v| s.solver.epsilon = v },
        rule: Rule::Positive,
        doc: "pole truncation ε (mm), 0 < ε < L (docs/MODEL.md §3)",
        growth: false,
    },
    KeySpec {
        key: "solver.scheme",
        access: Access::Choice {
            names: SCHEMES,
            get: |s| match s.solver.scheme {
                Scheme::Trapezoid => 0,
                Scheme::HermiteSimpson => 1,
            },
            set: |s, i| {
                s.solver.scheme = if i == 0 { Scheme::Trapezoid } else { Scheme::HermiteSimpson }
            },
        },
        rule: Rule::Any,
        doc: "finite-difference scheme: trapezoid (order 2) or Hermite–Simpson (order 4)",
        growth: false,
    },
    KeySpec {
        key: "solver.linear",
        access: Access::Choice {
            names: LINEAR,
            get: |s| match s.solver.linear {
                LinearSolverKind::Band => 0,
                LinearSolverKind::Klu => 1,
                LinearSolverKind::Block => 2,
            },
            set: |s, i| {
                s.solver.linear = match i {
                    0 => LinearSolverKind::Band,
                    1 => LinearSolverKind::Klu,
                    _ => LinearSolverKind::Block,
                }
            },
        },
        rule: Rule::Any,
        doc: "direct linear solver of the Newton matrix: SUNDIALS band LU, KLU, or block (the almost-block-diagonal LU of 5×5 node blocks)",
        growth: false,
    },
    KeySpec {
        key: "solver.newton_tol",
        access: Access::Float { get: |s| s.solver.newton_tol, set: |s, v| s.solver.newton_tol = v },
        rule: Rule::Positive,
        doc: "KINSOL's tolerance on the scaled residual (max norm)",
        growth: false,
    },
    KeySpec {
        key: "solver.max_newton",
        access: Access::Count { get: |s| s.solver.max_newton, set: |s, v| s.solver.max_newton = v },
        rule: Rule::Count(1, MAX_NEWTON),
        doc: "the most Newton iterations per solve",
        growth: false,
    },
    KeySpec {
        key: "solver.pole_grading",
        access: Access::Bool { get: |s| s.solver.pole_grading, set: |s, v| s.solver.pole_grading = v },
        rule: Rule::Any,
        doc: "insert geometrically graded nodes next to the pole (docs/MODEL.md §3 trap)",
        growth: false,
    },
    KeySpec {
        key: "solver.cornea_grading",
        access: Access::Bool { get: |s| s.solver.cornea_grading, set: |s, v| s.solver.cornea_grading = v },
        rule: Rule::Any,
        doc: "grade the nodes next to the cornea when the bending layer √(E_b/t_s) is thinner than the spacing (small E_b)",
        growth: false,
    },
    KeySpec {
        key: "solver.max_seconds",
        access: Access::OptionalFloat { get: |s| s.solver.max_seconds, set: |s, v| s.solver.max_seconds = Some(v) },
        rule: Rule::Positive,
        doc: "wall-clock bound (s) on each elastic solve and on each growth run as a whole: a solve still running then stops with an error saying where (KINSOL's, CVODE's and IDA's callbacks check it); a growth run keeps what it wrote; unset: no bound",
        growth: false,
    },
    KeySpec {
        key: "solver.tol",
        access: Access::OptionalFloat { get: |s| s.solver.tol, set: |s, v| s.solver.tol = Some(v) },
        rule: Rule::OpenUnit,
        doc: "the global error asked for: the mesh is adapted until the estimated error of each of κ, α_s, r, θ, Q (absolute, in fields.csv's units) is at most tol (Richardson on the halved mesh); in a growth scene (mm) it bounds the global error of the lengths of series.csv and the snapshots' r and z at every output time, choosing the mesh and solver.rtol/atol together (solver.nodes, solver.rtol and solver.atol are then ignored; docs/guide/accuracy.md); unset: solver.nodes lays the mesh",
        growth: false,
    },
    KeySpec {
        key: "solver.max_nodes",
        access: Access::Count { get: |s| s.solver.max_nodes, set: |s, v| s.solver.max_nodes = v },
        rule: Rule::Count(5, crate::mesh::MAX_NODES),
        doc: "with solver.tol: the most nodes the adapted (reported) mesh may have",
        growth: false,
    },
    KeySpec {
        key: "solver.richardson",
        access: Access::Bool { get: |s| s.solver.richardson, set: |s, v| s.solver.richardson = v },
        rule: Rule::Any,
        doc: "report Richardson's extrapolation of the solutions on a mesh and on it halved (order 6 with Hermite–Simpson, on the halved mesh's nodes), with its error estimated from the mesh halved twice; with solver.tol the mesh is adapted to it, without on the mesh of solver.nodes",
        growth: false,
    },
    KeySpec {
        key: "growth.eta0",
        access: Access::Float { get: |s| growth(s).eta0, set: |s, v| s.growth_mut().eta0 = v },
        rule: Rule::NonNegative,
        doc: "η0, the largest growth rate (docs/MODEL.md §4–5), per unit of the model's t, or with time.unit per unit of that (per year: the paper's η0 over a window of T years is η0/T per year); any growth.* key turns growth on",
        growth: true,
    },
    KeySpec {
        key: "growth.Gamma",
        access: Access::Float { get: |s| growth(s).gamma, set: |s, v| s.growth_mut().gamma = v },
        rule: Rule::Any,
        doc: "Γ (mm): the growth capacity falls to half at Σ = Γ; any sign, outside [0, L] too (docs/MODEL.md §4)",
        growth: true,
    },
    KeySpec {
        key: "growth.delta",
        access: Access::Float { get: |s| growth(s).delta, set: |s, v| s.growth_mut().delta = v },
        rule: Rule::Positive,
        doc: "δ (mm): the width of the fall of the growth capacity (docs/MODEL.md §4)",
        growth: true,
    },
    KeySpec {
        key: "growth.kink_width",
        access: Access::Float { get: |s| growth(s).kink_width, set: |s, v| s.growth_mut().kink_width = v },
        rule: Rule::UnitFromZero,
        doc: "round the [·]⁺ kinks of the growth laws (r − ρ and the depth in mm, α_s − 1) over this width (below 1: wider rounds away the laws themselves) with a C¹ quadratic; 0, the default, keeps the model's exact kinks (docs/MODEL.md §5): an option for measuring what the kinks cost the integrators",
        growth: true,
    },
    KeySpec {
        key: "growth.t_end",
        access: Access::Float { get: |s| growth(s).t_end, set: |s, v| { s.written_clock.t_end = Some(v); s.growth_mut().t_end = v; s.sync_clock() } },
        rule: Rule::Duration,
        doc: "end of the growth run (dimensionless time; the paper's t ∈ [0, 1], docs/MODEL.md §8); with time.unit the run lasts time.end − time.start and this key, if given, must equal it",
        growth: true,
    },
    KeySpec {
        key: "growth.thickness_law",
        access: Access::Choice {
            names: THICKNESS_LAWS,
            get: |s| match growth(s).thickness_law {
                ThicknessLaw::None => 0,
                ThicknessLaw::Mass => 1,
            },
            set: |s, i| {
                s.growth_mut().thickness_law = if i == 0 { ThicknessLaw::None } else { ThicknessLaw::Mass }
            },
        },
        rule: Rule::Any,
        doc: "unloaded thickness under growth: none (ζ = H, the paper's) or mass (ζ = H/(γ_s γ_φ)) (docs/MODEL.md §5)",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule",
        access: Access::Choice {
            names: &Form::NAMES,
            get: |s| growth(s).schedule.form as usize,
            set: |s, i| s.growth_mut().schedule.form = Form::ALL[i],
        },
        rule: Rule::Any,
        doc: "a factor s ≥ 0 on η0 over time (docs/MODEL.md §11): constant (s = 1, the paper's), exponential (s = exp(−(age − time.start)/growth.schedule_tau)), logistic (s = 1/(1 + exp((age − growth.schedule_centre)/growth.schedule_width))) or table (growth.schedule_times, growth.schedule_factors, interpolated monotonically and C¹)",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule_tau",
        access: Access::Float { get: |s| growth(s).schedule.tau, set: |s, v| s.growth_mut().schedule.tau = v },
        rule: Rule::Positive,
        doc: "the time constant of growth.schedule = \"exponential\", in time.unit (t without one)",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule_centre",
        access: Access::Float { get: |s| growth(s).schedule.centre, set: |s, v| s.growth_mut().schedule.centre = v },
        rule: Rule::Any,
        doc: "the age at which growth.schedule = \"logistic\" has fallen to half, in time.unit (t without one)",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule_width",
        access: Access::Float { get: |s| growth(s).schedule.width, set: |s, v| s.growth_mut().schedule.width = v },
        rule: Rule::Positive,
        doc: "the width of the fall of growth.schedule = \"logistic\", in time.unit (t without one)",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule_times",
        access: Access::Floats { get: |s| growth(s).schedule.times.clone(), set: |s, v| s.growth_mut().schedule.times = v },
        rule: Rule::List(MAX_SCHEDULE_POINTS),
        doc: "the ages (in time.unit; t without one) of growth.schedule = \"table\", strictly increasing; the factor is held beyond them",
        growth: true,
    },
    KeySpec {
        key: "growth.schedule_factors",
        access: Access::Floats { get: |s| growth(s).schedule.factors.clone(), set: |s, v| s.growth_mut().schedule.factors = v },
        rule: Rule::List(MAX_SCHEDULE_POINTS),
        doc: "the factors on η0 at growth.schedule_times, each finite, ≥ 0 and at most 1e6",
        growth: true,
    },
    KeySpec {
        key: "time.unit",
        access: Access::Choice {
            names: &TimeUnit::NAMES,
            get: |s| growth(s).clock.unit as usize,
            set: |s, i| { s.growth_mut().clock.unit = TimeUnit::ALL[i]; s.sync_clock() },
        },
        rule: Rule::Any,
        doc: "what ages are counted in: none (the model's dimensionless t), years or days; with a unit every time the scene writes is an age (time.start, time.end, output.times, the schedule's times, fit data), the run lasts time.end − time.start, every rate is per unit (growth.eta0 per year), and the outputs' t is the age less time.start, beside an age column",
        growth: true,
    },
    KeySpec {
        key: "time.start",
        access: Access::OptionalFloat { get: |s| growth(s).clock.start, set: |s, v| { s.growth_mut().clock.start = Some(v); s.sync_clock() } },
        rule: Rule::Any,
        doc: "the age (in time.unit) at which the run starts (t = 0)",
        growth: true,
    },
    KeySpec {
        key: "time.end",
        access: Access::OptionalFloat { get: |s| growth(s).clock.end, set: |s, v| { s.growth_mut().clock.end = Some(v); s.sync_clock() } },
        rule: Rule::Any,
        doc: "the age (in time.unit) at which the run ends, after time.start: the run lasts time.end − time.start",
        growth: true,
    },
    KeySpec {
        key: "solver.integrator",
        access: Access::Choice {
            names: INTEGRATORS,
            get: |s| s.growth_settings.integrator as usize,
            set: |s, i| s.growth_settings.integrator = [Integrator::Cvode, Integrator::Euler, Integrator::Ida][i],
        },
        rule: Rule::Any,
        doc: "time integrator of the growth: IDA (BDF on the coupled DAE of growth and equilibrium, one Newton per step), CVODE (BDF on the growth alone, an elastic solve per right side) or the published explicit Euler",
        growth: true,
    },
    KeySpec {
        key: "solver.dae_linear",
        access: Access::Choice {
            names: &DaeLinear::NAMES,
            get: |s| s.growth_settings.dae_linear as usize,
            set: |s, i| s.growth_settings.dae_linear = DaeLinear::ALL[i],
        },
        rule: Rule::Any,
        doc: "linear solver of IDA's Newton matrix: schur-block (the default: eliminate the growth unknowns point by point, almost-block-diagonal LU of the rest; a matrix whose growth block is too small to eliminate unpivoted goes to KLU, counted as linear_fallbacks in summary.json), schur (the same, band LU of the rest), schur-klu (the same, KLU of the rest), band (band LU of the whole system, interleaved) or klu",
        growth: true,
    },
    KeySpec {
        key: "solver.rtol",
        access: Access::Float { get: |s| s.growth_settings.rtol, set: |s, v| s.growth_settings.rtol = v },
        rule: Rule::OpenUnit,
        doc: "the integrators' (IDA's, CVODE's) relative tolerance (ignored with solver.tol, which chooses it)",
        growth: true,
    },
    KeySpec {
        key: "solver.atol",
        access: Access::Float { get: |s| s.growth_settings.atol, set: |s, v| s.growth_settings.atol = v },
        rule: Rule::Positive,
        doc: "the integrators' (IDA's, CVODE's) absolute tolerance (ignored with solver.tol, which chooses it)",
        growth: true,
    },
    KeySpec {
        key: "solver.steps",
        access: Access::Count { get: |s| s.growth_settings.steps, set: |s, v| s.growth_settings.steps = v },
        rule: Rule::Count(1, MAX_STEPS),
        doc: "number of explicit Euler steps to growth.t_end (solver.integrator = \"euler\"; the paper used 200)",
        growth: true,
    },
    KeySpec {
        key: "output.times",
        access: Access::Floats { get: |s| s.written_output_times(), set: |s, v| { s.written_clock.output_times = Some(v.clone()); s.growth_settings.output_times = v; s.sync_clock() } },
        rule: Rule::PositiveIncreasing(MAX_OUTPUT_TIMES),
        doc: "times of the growth snapshots, strictly increasing: in (0, growth.t_end], or with time.unit ages in (time.start, time.end] (by default 0.1, 0.2, 0.4 and 1 of the window); the start is always written",
        growth: true,
    },
    KeySpec {
        key: "output.history_points",
        access: Access::Count { get: |s| s.growth_settings.history_points, set: |s, v| s.growth_settings.history_points = v },
        rule: Rule::Count(0, MAX_HISTORY_POINTS),
        doc: "also record axial length, refraction and class at this many evenly spaced times (history.csv, no snapshots): curves of axial length against t; 0: no history.csv",
        growth: true,
    },
    KeySpec {
        key: "stimulus.blue.P1",
        access: Access::Float { get: |s| s.blue().p1, set: |s, v| s.set_blue(|c| c.p1 = v) },
        rule: Rule::Any,
        doc: "blue best-focus surface: P1 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); setting any stimulus.blue.* and no stimulus.red.* makes red follow blue, pushed back by 0.655",
        growth: true,
    },
    KeySpec {
        key: "stimulus.blue.P2",
        access: Access::Float { get: |s| s.blue().p2, set: |s, v| s.set_blue(|c| c.p2 = v) },
        rule: Rule::Any,
        doc: "blue best-focus surface: P2 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); setting any stimulus.blue.* and no stimulus.red.* makes red follow blue, pushed back by 0.655",
        growth: true,
    },
    KeySpec {
        key: "stimulus.blue.P3",
        access: Access::Float { get: |s| s.blue().p3, set: |s, v| s.set_blue(|c| c.p3 = v) },
        rule: Rule::Any,
        doc: "blue best-focus surface: P3 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); setting any stimulus.blue.* and no stimulus.red.* makes red follow blue, pushed back by 0.655",
        growth: true,
    },
    KeySpec {
        key: "stimulus.blue.z_B",
        access: Access::Float { get: |s| s.blue().z_b, set: |s, v| s.set_blue(|c| c.z_b = v) },
        rule: Rule::Any,
        doc: "blue best-focus surface: z (mm) of the polar centre on the axis (docs/MODEL.md §6); setting any stimulus.blue.* and no stimulus.red.* makes red follow blue, pushed back by 0.655",
        growth: true,
    },
    KeySpec {
        key: "stimulus.blue.phi_max",
        access: Access::Float { get: |s| s.blue().phi_max, set: |s, v| s.set_blue(|c| c.phi_max = v) },
        rule: Rule::OpenHalfTurn,
        doc: "blue best-focus surface: largest polar angle φ_max (rad) the surface is defined for (docs/MODEL.md §6); setting any stimulus.blue.* and no stimulus.red.* makes red follow blue, pushed back by 0.655",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.P1",
        access: Access::Float { get: |s| s.red().p1, set: |s, v| s.set_red(|c| c.p1 = v) },
        rule: Rule::Any,
        doc: "red best-focus surface: P1 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); default: the blue surface's",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.P2",
        access: Access::Float { get: |s| s.red().p2, set: |s, v| s.set_red(|c| c.p2 = v) },
        rule: Rule::Any,
        doc: "red best-focus surface: P2 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); default: the blue surface's",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.P3",
        access: Access::Float { get: |s| s.red().p3, set: |s, v| s.set_red(|c| c.p3 = v) },
        rule: Rule::Any,
        doc: "red best-focus surface: P3 (mm) of R(φ) = P1 φ⁴ + P2 φ² + P3 (docs/MODEL.md §6); default: the blue surface's",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.z_B",
        access: Access::Float { get: |s| s.red().z_b, set: |s, v| s.set_red(|c| c.z_b = v) },
        rule: Rule::Any,
        doc: "red best-focus surface: z (mm) of the polar centre on the axis (docs/MODEL.md §6); default: the blue surface's",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.phi_max",
        access: Access::Float { get: |s| s.red().phi_max, set: |s, v| s.set_red(|c| c.phi_max = v) },
        rule: Rule::OpenHalfTurn,
        doc: "red best-focus surface: largest polar angle φ_max (rad) the surface is defined for (docs/MODEL.md §6); default: the blue surface's",
        growth: true,
    },
    KeySpec {
        key: "stimulus.red.offset",
        access: Access::Float { get: |s| s.red().offset, set: |s, v| s.set_red(|c| c.offset = v) },
        rule: Rule::Any,
        doc: "red surface pushed back along its polar rays by this (mm): 0.655, the Indiana eye's 400–600 nm chromatic aberration (docs/MODEL.md §6)",
        growth: true,
    },
    KeySpec {
        key: "stimulus.source",
        access: Access::Choice { names: SOURCE_NAMES, get: |s| s.stimulus_source() as usize, set: |s, v| s.set_stimulus_source(if v == 1 { Source::Optics } else { Source::Polynomial }) },
        rule: Rule::Any,
        doc: "where the best-focus surfaces come from: polynomial (stimulus.blue.* and stimulus.red.*, the published blue surface) or optics (computed once per run from the schematic eye of optics.*: the first wavelength's surface is the stimulus, the second's the red one, both about stimulus.blue.z_B; docs/guide/optics.md)",
        growth: true,
    },
    KeySpec {
        key: "optics.eye",
        access: Access::Choice { names: EYE_NAMES, get: |s| s.optics().eye, set: |s, v| s.set_optics(|o| o.eye = v) },
        rule: Rule::Any,
        doc: "schematic eye of stimulus.source = \"optics\" and `eyeshell optics` (docs/optics.md cites each), or custom: the eye of [[optics.surfaces]]",
        growth: true,
    },
    KeySpec {
        key: "optics.pupil",
        access: Access::Float { get: |s| s.optics().pupil, set: |s, v| s.set_optics(|o| o.pupil = v) },
        rule: Rule::Positive,
        doc: "pupil diameter (mm), at most 10; the pupil lies where the eye's source puts it",
        growth: true,
    },
    KeySpec {
        key: "optics.wavelengths",
        access: Access::Floats { get: |s| s.optics().wavelengths.clone(), set: |s, v| s.set_optics(|o| o.wavelengths = v) },
        rule: Rule::Any,
        doc: "wavelengths (nm, within the eye's dispersion: 380 to 1100 for atchison-2006, 380 to 750 for the others, 300 to 1200 for custom): the first is the stimulus's (blue), the second, longer, the classification's (red): growth needs both; `eyeshell optics` takes one or more (optics.json's chromatic aberration is between the first two)",
        growth: true,
    },
    KeySpec {
        key: "optics.focus",
        access: Access::Choice { names: FOCI, get: |s| s.optics().focus, set: |s, v| s.set_optics(|o| o.focus = v) },
        rule: Rule::Any,
        doc: "best-focus criterion: mean-sphere (the mean of the sagittal and tangential vergences, what peripheral refraction measures), strehl (the paper's stated criterion: the largest Strehl ratio, midway between the focal lines while the astigmatism is below about a wave over the pupil, on the sagittal line beyond: from 10° with a 3 mm pupil, 33° with 1 mm, docs/optics.md), sagittal (the sagittal focal line: the one the paper's published blue surface follows) or tangential",
        growth: true,
    },
    KeySpec {
        key: "optics.pupil_position",
        access: Access::OptionalFloat { get: |s| s.optics().pupil_position, set: |s, v| s.set_optics(|o| o.pupil_position = Some(v)) },
        rule: Rule::Positive,
        doc: "the pupil's (aperture stop's) distance from the corneal apex (mm), in a homogeneous medium inside the eye; unset: a built-in eye's source's (on the lens's front vertex, which it follows when the surfaces change); a custom eye must give it",
        growth: true,
    },
    KeySpec {
        key: "optics.surfaces",
        access: Access::Surfaces { get: |s| s.surfaces_as_written(), set: |s, v| s.set_surfaces_as_written(v) },
        rule: Rule::Any,
        doc: "[[optics.surfaces]], one table a surface from the cornea back: radius (mm, inf for a plane), conic, aspheric (r⁴, r⁶, ... terms), thickness (mm to the next surface; the last one's to the retina) and the medium behind it: index, cauchy = [a, b, c, d] (λ in µm) or sellmeier = { b = [..], c = [..] }. The surfaces of optics.eye = \"custom\", or overrides of a built-in eye's (in its surface order; a key left out keeps the source's). radius, conic, thickness and index may be tables over the growth's time, { t = [0, 0.5, 1], value = [7.4, 7.7, 7.8] } (in a scene with time.unit, over ages: { age = [8, 9, 11], value = [...] }). One key alone: optics.surfaces[i].key (i from 0) (docs/guide/optics.md)",
        growth: true,
    },
    KeySpec {
        key: "optics.max_field",
        access: Access::Float { get: |s| s.optics().max_field, set: |s, v| s.set_optics(|o| o.max_field = v) },
        rule: Rule::Positive,
        doc: "largest field angle traced (degrees in air, 5 to 80, one field a degree): φ_max is where the computed surface ends (40° reaches about 0.45 rad)",
        growth: true,
    },
    KeySpec {
        key: "optics.lenses",
        access: Access::Lenses { get: |s| s.optics().lenses.clone(), set: |s, v| s.set_optics(|o| o.lenses = v) },
        rule: Rule::Any,
        doc: "eyewear, [[optics.lenses]] tables (at most 4, counted from 0 in messages): kind = \"spectacle\" (vertex mm in front of the corneal apex, default 12) or \"contact\" (on the cornea), and one of power (D; or power = \"prescribe\": the eye's own correction, the naked eye's refraction_D at t = 0 converted to the lens's place, plus over = D if given), zones = [{ radius, power }, ...] (rings out to each radius, mm; a zone may hold lenslets = { power, fill }: a share fill of its light through segments of that power), table = [{ radius, power }, ...] (smooth), or a real spectacle lens front_radius, back_radius, thickness, index; needs stimulus.source = \"optics\". One key alone: optics.lenses[i].key (i from 0; i = the count adds a lens) (docs/guide/eyewear.md)",
        growth: true,
    },
    KeySpec {
        key: "optics.refraction_wavelength",
        access: Access::Float { get: |s| s.optics().refraction_wavelength, set: |s, v| s.set_optics(|o| o.refraction_wavelength = v) },
        rule: Rule::Positive,
        doc: "wavelength (nm) of refraction_D, the spectacle power at 12 mm that brings the naked eye's on-axis best focus onto the retina (with stimulus.source = \"polynomial\" the refraction is the default optics' at 555 nm)",
        growth: true,
    },
    KeySpec {
        key: "stimulus.rule",
        access: Access::Choice { names: &RULES, get: |s| growth(s).stimulus.keys.rule, set: |s, v| s.growth_mut().stimulus.set_keys(|k| k.rule = v) },
        rule: Rule::Any,
        doc: "what drives growth, g_v = [drive]⁺ (docs/MODEL.md §6, docs/guide/hypotheses.md): blue-surface (the paper's: the depth of the blue surface behind the retina, mm), defocus (stimulus.baseline + stimulus.hyperopic_gain·D⁺ − stimulus.myopic_gain·D⁻, D the defocus in dioptres at the stimulus wavelength through the lenses worn, positive when the image lies behind the retina) or chromatic (stimulus.chromatic_gain in front of the blue surface, none behind the red one, in proportion between)",
        growth: true,
    },
    KeySpec {
        key: "stimulus.baseline",
        access: Access::Float { get: |s| growth(s).stimulus.keys.baseline, set: |s, v| s.growth_mut().stimulus.set_keys(|k| k.baseline = v) },
        rule: Rule::Any,
        doc: "stimulus.rule = \"defocus\": the drive (mm) at zero defocus, what keeps an eye growing when its image is in focus (near work, little time outdoors); 0 by default",
        growth: true,
    },
    KeySpec {
        key: "stimulus.hyperopic_gain",
        access: Access::Float { get: |s| growth(s).stimulus.keys.hyperopic_gain, set: |s, v| s.growth_mut().stimulus.set_keys(|k| k.hyperopic_gain = v) },
        rule: Rule::NonNegative,
        doc: "stimulus.rule = \"defocus\": the drive (mm per dioptre) of hyperopic defocus (the image behind the retina); 0.37, the reciprocal of the Atchison 2006 eye's 2.7 D/mm, drives a hyperopic eye as the paper's rule does",
        growth: true,
    },
    KeySpec {
        key: "stimulus.myopic_gain",
        access: Access::Float { get: |s| growth(s).stimulus.keys.myopic_gain, set: |s, v| s.growth_mut().stimulus.set_keys(|k| k.myopic_gain = v) },
        rule: Rule::NonNegative,
        doc: "stimulus.rule = \"defocus\": how strongly myopic defocus (the image in front of the retina) slows growth (mm per dioptre); 0.37 by default",
        growth: true,
    },
    KeySpec {
        key: "stimulus.chromatic_gain",
        access: Access::Float { get: |s| growth(s).stimulus.keys.chromatic_gain, set: |s, v| s.growth_mut().stimulus.set_keys(|k| k.chromatic_gain = v) },
        rule: Rule::NonNegative,
        doc: "stimulus.rule = \"chromatic\": the drive (mm) while the retina lies in front of the blue surface; 0.655 by default, the default red surface's distance behind the blue one",
        growth: true,
    },
    KeySpec {
        key: "stimulus.region",
        access: Access::Choice { names: &crate::model::rule::Region::NAMES, get: |s| growth(s).stimulus.region as usize, set: |s, v| s.growth_mut().stimulus.region = if v == 1 { crate::model::rule::Region::Integrated } else { crate::model::rule::Region::Local } },
        rule: Rule::Any,
        doc: "where the rule acts: local (each retinal point's own drive, the paper's) or integrated (the drive averaged over the retina's area from the pole to stimulus.max_field drives every point: the periphery acts on the pole; docs/MODEL.md §6)",
        growth: true,
    },
    KeySpec {
        key: "stimulus.max_field",
        access: Access::Float { get: |s| growth(s).stimulus.max_field, set: |s, v| s.growth_mut().stimulus.max_field = v },
        rule: Rule::Positive,
        doc: "stimulus.region = \"integrated\": the region's edge, the polar angle (degrees) about the stimulus surface's centre, at most where the surface is defined (33.6° for the published one, about 26° for a surface computed to a 40° field); 25 by default",
        growth: true,
    },
    KeySpec {
        key: "stimulus.classify",
        access: Access::Choice { names: &CLASSIFY, get: |s| s.optics().classify, set: |s, v| s.set_optics(|o| o.classify = v) },
        rule: Rule::Any,
        doc: "how the class is decided: surfaces (the paper's: hyperopic in front of blue, myopic behind red) or dioptres (refraction_D above stimulus.hyperopia_D is hyperopic, below stimulus.myopia_D myopic)",
        growth: true,
    },
    KeySpec {
        key: "stimulus.myopia_D",
        access: Access::Float { get: |s| s.optics().myopia_d, set: |s, v| s.set_optics(|o| o.myopia_d = v) },
        rule: Rule::Any,
        doc: "with stimulus.classify = \"dioptres\": a refraction_D below this (D, in [-25, 0]) is myopic",
        growth: true,
    },
    KeySpec {
        key: "stimulus.hyperopia_D",
        access: Access::Float { get: |s| s.optics().hyperopia_d, set: |s, v| s.set_optics(|o| o.hyperopia_d = v) },
        rule: Rule::Any,
        doc: "with stimulus.classify = \"dioptres\": a refraction_D above this (D, in [0, 25]) is hyperopic",
        growth: true,
    },
];
