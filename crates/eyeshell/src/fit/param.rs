//! What a fit varies: scene keys of real numbers, each with its validity range, read from
//! and written to a scene. The keys with a forward sensitivity in the growth run
//! ([`SensParam`]) keep IDAS's derivative of the axial length; every other real-valued key
//! of the model (a surface's radius, a lens's power is not among them) is differentiated by
//! central differences of the scene run ([`super::joint`]).

use super::Bounds;
use crate::growth;
use crate::growth::dae::SensParam;
use crate::model::optics::Source;
use crate::scene::keys::{self, Access, KeyValue, Rule};
use crate::scene::Scene;
use crate::{Error, Origin, Subject};

/// A fitted parameter: its scene key, its forward sensitivity if the growth run has one,
/// and its validity range (from the key's rule).
#[derive(Clone, Debug, PartialEq)]
pub struct FitParam {
    key: String,
    /// IDAS's sensitivity of the axial length to it; None: differentiated by finite
    /// differences of the run.
    pub param: Option<SensParam>,
    pub bounds: Bounds,
}

/// The range of a key's rule (`eyeshell keys`).
pub(crate) fn bounds_of_rule(rule: Rule) -> Bounds {
    let b = Bounds::NONE;
    match rule {
        Rule::Positive => Bounds {
            lower: Some(0.0),
            lower_open: true,
            ..b
        },
        Rule::NonNegative => Bounds {
            lower: Some(0.0),
            ..b
        },
        Rule::OpenUnit => Bounds {
            lower: Some(0.0),
            lower_open: true,
            upper: Some(1.0),
            upper_open: true,
        },
        Rule::UnitFromZero => Bounds {
            lower: Some(0.0),
            upper: Some(1.0),
            upper_open: true,
            ..b
        },
        Rule::OpenHalfTurn => Bounds {
            lower: Some(0.0),
            lower_open: true,
            upper: Some(std::f64::consts::PI),
            upper_open: true,
        },
        _ => b,
    }
}

/// The keys of a surface a fit varies, with their ranges: the radius and conic take any
/// value (the scene refuses a flat radius of 0), the thickness and index are positive.
const SURFACE_FIT_KEYS: [(&str, Rule); 4] = [
    ("radius", Rule::Any),
    ("conic", Rule::Any),
    ("thickness", Rule::Positive),
    ("index", Rule::Positive),
];

/// Why a key cannot be fitted: one line naming it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{why}")]
pub struct FitKeyError {
    pub key: String,
    pub why: String,
}

/// Sections of settings, not of the model: the solver's numerics, the outputs, the clock.
const NOT_MODEL_SECTIONS: [&str; 3] = ["solver", "output", "time"];

impl FitParam {
    /// The parameter of a key with a forward sensitivity (what `--sensitivities` takes).
    ///
    /// # Errors
    /// [`crate::scene::sensitivity::SensitivityKeyError`] for a key that is not such a parameter.
    pub fn from_sensitivity_key(
        key: &str,
    ) -> Result<FitParam, crate::scene::sensitivity::SensitivityKeyError> {
        let param = crate::scene::sensitivity::sensitivity_param(key)?;
        let name = crate::scene::names::sensitivity_key(param);
        let bounds = keys::find(name).map_or(Bounds::NONE, |k| bounds_of_rule(k.rule));
        Ok(FitParam {
            key: name.to_string(),
            param: Some(param),
            bounds,
        })
    }

    /// The parameter of any real-valued key of the model: one with a forward sensitivity,
    /// a real key of the table, or a surface's radius, conic, thickness or index
    /// (`optics.surfaces[0].radius`). The error is one line naming the key.
    pub fn from_key(key: &str) -> Result<FitParam, FitKeyError> {
        FitParam::from_key_text(key).map_err(|why| FitKeyError {
            key: key.to_string(),
            why,
        })
    }

    /// [`FitParam::from_key`], its refusal as text.
    fn from_key_text(key: &str) -> Result<FitParam, String> {
        if let Ok(p) = FitParam::from_sensitivity_key(key) {
            return Ok(p);
        }
        if let Some(item) = crate::scene::indexed(key) {
            let item = item.map_err(|problem| format!("{key} {problem}"))?;
            let rule = (item.array == "optics.surfaces")
                .then(|| SURFACE_FIT_KEYS.iter().find(|(n, _)| *n == item.name))
                .flatten()
                .map(|(_, r)| *r)
                .ok_or_else(|| {
                    format!(
                        "{key} cannot be fitted: of the optics' arrays a fit varies a surface's {} (optics.surfaces[i].radius, ...), not a lens's keys",
                        SURFACE_FIT_KEYS.map(|(n, _)| n).join(", ")
                    )
                })?;
            return Ok(FitParam {
                key: format!("optics.surfaces[{}].{}", item.index, item.name),
                param: None,
                bounds: bounds_of_rule(rule),
            });
        }
        let Some(spec) = keys::find(key) else {
            return Err(crate::scene::sensitivity::sensitivity_param(key)
                .err()
                .map_or_else(|| format!("{key:?} is not a scene key"), |e| e.to_string()));
        };
        if key == "stimulus.red.offset" {
            return Err(crate::scene::sensitivity::sensitivity_param(key)
                .err()
                .map_or_else(String::new, |e| e.to_string()));
        }
        if let Some(section) = spec.section().filter(|s| NOT_MODEL_SECTIONS.contains(s)) {
            return Err(format!(
                "{key} is a setting of the {section}, not a parameter of the model: it cannot be fitted"
            ));
        }
        if !matches!(
            spec.access,
            Access::Float { .. } | Access::OptionalFloat { .. }
        ) {
            return Err(format!(
                "{key} is not a real-valued key ({}): a fit varies real numbers",
                spec.type_name()
            ));
        }
        Ok(FitParam {
            key: key.to_string(),
            param: None,
            bounds: bounds_of_rule(spec.rule),
        })
    }

    /// The scene key.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// Whether the growth run gives this parameter's sensitivity (else finite differences).
    pub fn has_sensitivity(&self) -> bool {
        self.param.is_some()
    }

    /// The parameter's range in `scene`: its key's range narrowed by the limits that tie
    /// it to other keys (`Scene::validate`), so that a step never leaves what the scene
    /// accepts. pressure.dP stays below the cornea's limit, the largest admissible ΔP
    /// (docs/MODEL.md §3), an open bound: at the limit the cornea's stretch has an infinite
    /// derivative in ΔP, so neither the model nor its sensitivity can be evaluated there.
    pub fn in_scene(&self, scene: &Scene) -> FitParam {
        let mut bounds = self.bounds;
        if self.param == Some(SensParam::Pressure) {
            let limit = crate::model::cornea::max_pressure(&scene.params.cornea);
            if bounds.upper.is_none_or(|hi| limit <= hi) {
                bounds.upper = Some(limit);
                bounds.upper_open = true;
            }
        }
        FitParam {
            bounds,
            ..self.clone()
        }
    }

    /// The parameter's value in `scene`: a surface key left to the built-in eye reads the
    /// eye's number. An error names the key that has no single number (unset, or a table
    /// over time).
    pub fn value_in(&self, scene: &Scene) -> Result<f64, Error> {
        let no_value = |why: &str| {
            Error::input(
                Subject::Key(self.key.clone()),
                format!(
                    "{} {why} in {}: a fit starts from a single number (give one with --set {}=…)",
                    self.key, scene.origin, self.key
                ),
            )
            .with_origin(Origin::Scene(scene.origin.clone()))
        };
        if let Some(Ok(item)) = crate::scene::indexed(&self.key) {
            let optics = scene.optics();
            let spec = optics.surfaces.get(item.index);
            use crate::model::eye::{EyeValue, MediumSpec};
            let given = spec.and_then(|s| match item.name {
                "radius" => s.radius.clone(),
                "conic" => s.conic.clone(),
                "thickness" => s.thickness.clone(),
                _ => match &s.medium {
                    Some(MediumSpec::Index(v)) => Some(v.clone()),
                    _ => None,
                },
            });
            return match given {
                Some(EyeValue::Fixed(x)) => Ok(x),
                Some(EyeValue::Table { .. }) => Err(no_value("is a table over time")),
                None if item.name == "index" => Err(no_value("has no index of its own")),
                None => {
                    let system = optics
                        .system()
                        .map_err(|e| no_value(&format!("cannot be read ({})", e.problem)))?;
                    let e = system
                        .elements
                        .get(item.index)
                        .ok_or_else(|| no_value("is beyond the eye's surfaces"))?;
                    Ok(match item.name {
                        "radius" => e.surface.radius,
                        "conic" => e.surface.conic,
                        _ => e.thickness,
                    })
                }
            };
        }
        match keys::find(&self.key).map(|k| k.get(scene)) {
            Some(KeyValue::Float(x)) => Ok(x),
            Some(KeyValue::Unset) => Err(no_value("is not set")),
            _ => Err(no_value("has no value")),
        }
    }

    /// Why the run of `scene` cannot use this parameter, if it cannot: an optics key when
    /// the stimulus is not computed from the optics (the run never reads it).
    pub fn unused_in(&self, scene: &Scene) -> Option<String> {
        let optics_key = self.key.starts_with("optics.");
        if optics_key && scene.stimulus_source() != Source::Optics {
            return Some(format!(
                "{} is not used by the run of {}: its stimulus is not computed from the optics (stimulus.source = \"{}\" in {}; the optics keys need \"optics\")",
                self.key,
                scene.origin,
                crate::model::optics::SOURCES[scene.stimulus_source() as usize],
                scene.origin_of_key("stimulus.source")
            ));
        }
        let spec = keys::find(&self.key)?;
        (!spec.applies_to(scene)).then(|| {
            format!(
                "{} is not used by the run of {} (no key of its section applies to this scene)",
                self.key, scene.origin
            )
        })
    }
}

/// The values of `params` in `scene`, in their order.
pub fn values_in(scene: &Scene, params: &[FitParam]) -> Result<Vec<f64>, Error> {
    params.iter().map(|p| p.value_in(scene)).collect()
}

/// Why `params` cannot be taken in `scene`, if they cannot: a parameter the model of the
/// scene does not have (fibres.D without fibres), or an integrator without sensitivities.
/// The one check of every caller (`grow --sensitivities`, `Scene::set_sensitivities`,
/// `fit`), made before any run; `what` names the option in the message.
pub fn check_params(scene: &Scene, params: &[FitParam], what: &str) -> Result<(), Error> {
    let sens: Vec<(&FitParam, SensParam)> =
        params.iter().filter_map(|p| Some((p, p.param?))).collect();
    if let Some((p, why)) = sens
        .iter()
        .find_map(|(p, s)| Some((p, s.check(&scene.params).err()?)))
    {
        return Err(Error::input(
            Subject::Key(p.key().into()),
            format!("{what}: {why} ({})", scene.origin),
        )
        .with_origin(Origin::Scene(scene.origin.clone())));
    }
    // What the growth's own surfaces and rule cannot differentiate (z_B of a computed
    // surface, or under a rule of dioptres): an input error now, not a failed run at t = 0.
    if let Some(g) = &scene.growth {
        if let Some((p, why)) = sens
            .iter()
            .find_map(|(p, s)| Some((p, growth::sensitivity_unavailable(*s, g)?)))
        {
            let origin = scene.origin_of_key("stimulus.source");
            return Err(Error::input(
                Subject::Key(p.key().into()),
                format!("{what}: {why} ({origin})"),
            )
            .with_origin(Origin::Scene(origin)));
        }
    }
    // A schedule's parameter is a parameter of its form alone: with another form the run
    // has no such parameter to differentiate by.
    let form = scene
        .growth
        .as_ref()
        .map_or(growth::schedule::Form::Constant, |g| g.schedule.form);
    if let Some(sp) = sens.iter().find_map(|(_, s)| s.schedule_param()) {
        if sp.form() != form {
            use growth::schedule::Form;
            return Err(Error::input(Subject::Key("growth.schedule".into()), format!(
                "{what}: {} needs growth.schedule = \"{}\" ({} has \"{}\"): the schedule has no such parameter",
                crate::scene::names::key_of(sp.quantity()),
                Form::NAMES[sp.form() as usize],
                scene.origin_of_key("growth.schedule"),
                Form::NAMES[form as usize]
            ))
            .with_value(Form::NAMES[form as usize])
            .with_origin(Origin::Scene(scene.origin_of_key("growth.schedule"))));
        }
    }
    let integrator = scene.growth_settings.integrator;
    if integrator != growth::Integrator::Ida {
        return Err(Error::input(
            Subject::Key("solver.integrator".into()),
            format!(
                "{what} need solver.integrator = \"ida\" ({} has \"{}\")",
                scene.origin,
                integrator.name()
            ),
        )
        .with_value(integrator.name())
        .with_origin(Origin::Scene(scene.origin.clone())));
    }
    // A key the run does not read, and one without a single start value: a fit could
    // never move the model with it.
    for p in params {
        if let Some(why) = p.unused_in(scene) {
            return Err(
                Error::input(Subject::Key(p.key().into()), format!("{what}: {why}"))
                    .with_origin(Origin::Scene(scene.origin.clone())),
            );
        }
        p.value_in(scene)?;
    }
    Ok(())
}

/// Parse `keys` with `parse` (each a parameter, each once). `what` names the option in
/// messages (`--fit`).
fn parse_with(
    keys: &[impl AsRef<str>],
    what: &str,
    parse: impl Fn(&str) -> Result<FitParam, String>,
) -> Result<Vec<FitParam>, Error> {
    if keys.is_empty() {
        return Err(Error::input(
            Subject::Argument(what.into()),
            format!("{what}: no parameter given"),
        )
        .with_origin(Origin::Argument));
    }
    let mut params: Vec<FitParam> = Vec::with_capacity(keys.len());
    for key in keys {
        let key = key.as_ref().trim();
        let refuse = |message: String| {
            Error::input(Subject::Key(key.into()), message)
                .with_value(key)
                .with_origin(Origin::Argument)
        };
        let p = parse(key).map_err(|why| refuse(format!("{what}: {why}")))?;
        if params.iter().any(|q| q.key == p.key) {
            return Err(refuse(format!("{what}: {key} is listed twice")));
        }
        params.push(p);
    }
    Ok(params)
}

/// Parse `keys` (the `--sensitivities` list): each a parameter with a forward
/// sensitivity, each once.
pub fn parse_keys(keys: &[impl AsRef<str>], what: &str) -> Result<Vec<FitParam>, Error> {
    parse_with(keys, what, |k| {
        FitParam::from_sensitivity_key(k).map_err(|e| e.to_string())
    })
}

/// Parse `keys` (the `--fit` list): each a real-valued key of the model
/// ([`FitParam::from_key`]), each once.
pub fn parse_fit_keys(keys: &[impl AsRef<str>], what: &str) -> Result<Vec<FitParam>, Error> {
    parse_with(keys, what, |k| FitParam::from_key(k).map_err(|e| e.why))
}

/// `scene` with the parameters set to `values`, validated and its optics traced again (a
/// combination the scene refuses, e.g. beyond a cross-key limit, is an error naming it).
pub fn with_values(scene: &Scene, params: &[FitParam], values: &[f64]) -> Result<Scene, Error> {
    let mut s = scene.clone();
    let all_plain = params.iter().all(|p| {
        !p.key.starts_with("optics.")
            && matches!(
                keys::find(&p.key).map(|k| k.access),
                Some(Access::Float { .. })
            )
    });
    if all_plain && scene.stimulus_source() != Source::Optics {
        // No optics to trace again: the keys' setters and one validation.
        for (p, &x) in params.iter().zip(values) {
            if let Some(Access::Float { set, .. }) = keys::find(&p.key).map(|k| k.access) {
                set(&mut s, x);
            }
        }
        s.validate()?;
        return Ok(s);
    }
    let assignments: Vec<(&str, String)> = params
        .iter()
        .zip(values)
        .map(|(p, x)| (p.key.as_str(), format!("{}", KeyValue::Float(*x))))
        .collect();
    s.set_all(assignments)?;
    Ok(s)
}

impl FitParam {
    /// The same key differentiated by finite differences of the run even where IDAS has
    /// its sensitivity (to check one against the other).
    pub fn by_differences(&self) -> FitParam {
        FitParam {
            param: None,
            ..self.clone()
        }
    }
}
