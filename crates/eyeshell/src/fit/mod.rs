//! Calibration: the parameters of a growth scene that fit a measured growth curve
//! (`eyeshell fit`, `eyeshell.fit`).
//!
//! The numerics (the minimiser, the growth model at the observations, identifiability) are
//! eyeshell-core's `fit`, re-exported here; this module is the scene's side of them: which
//! keys are parameters and their ranges ([`FitParam`]), the data file ([`data`]), the fit
//! of a [`Scene`] ([`fit`]) and its report ([`report`]).
//!
//! The observations ([`data`]) are axial lengths yᵢ at times tᵢ with standard deviations σᵢ
//! (1 when the file gives none). The residuals are rᵢ = (L(tᵢ; p) − yᵢ)/σᵢ, L the model's
//! axial length from one growth run that records exactly the distinct observation times;
//! the cost is C = ½ Σ rᵢ². The Jacobian Jᵢⱼ = ∂L(tᵢ)/∂pⱼ / σᵢ is the run's forward
//! sensitivities (IDAS, [`crate::growth::dae::SensParam`]), not finite differences: one run
//! per iteration gives the residuals and the Jacobian together.
//!
//! The minimiser ([`lm`]) is Levenberg–Marquardt with Marquardt's scaling and projected
//! steps onto each key's validity range; identifiability is checked on the information
//! matrix JᵀJ at the start and at the estimate ([`identifiability`]); the standard errors
//! come from the Gauss–Newton covariance.

pub mod data;
pub mod report;

use nalgebra::{DMatrix, DVector};

pub use eyeshell_core::fit::{
    lm, Bounds, FitError, GrowthModel, ModelValues, IDENTIFIABILITY_THRESHOLD,
};

use crate::growth::dae::SensParam;
use crate::growth::{self, GrowthParams};
use crate::scene::keys::{self, KeyValue, Rule};
use crate::scene::Scene;
use crate::text::number;
use crate::{Error, Origin, Stage, Subject};

pub use data::{Observation, Observations};
pub use lm::{Convergence, FitOptions, IterationRecord};

/// A fitted parameter: its key and its validity range (from the scene key's rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitParam {
    pub param: SensParam,
    pub bounds: Bounds,
}

/// The range of a key's rule (`eyeshell keys`).
fn bounds_of_rule(rule: Rule) -> Bounds {
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

impl From<FitError> for Error {
    fn from(e: FitError) -> Self {
        match e {
            FitError::Growth(g) => g.into(),
            // A run that records nothing, or a failure the fit adds later: not the user's.
            e => Error::failed_by(Stage::Fit, e),
        }
    }
}

impl FitParam {
    /// The parameter of scene key `key`, with its range.
    ///
    /// # Errors
    /// [`crate::scene::sensitivity::SensitivityKeyError`] for a key that is not such a parameter.
    pub fn from_key(key: &str) -> Result<FitParam, crate::scene::sensitivity::SensitivityKeyError> {
        let param = crate::scene::sensitivity::sensitivity_param(key)?;
        let bounds = keys::find(crate::scene::names::sensitivity_key(param))
            .map_or(Bounds::NONE, |k| bounds_of_rule(k.rule));
        Ok(FitParam { param, bounds })
    }

    pub fn key(&self) -> &'static str {
        crate::scene::names::sensitivity_key(self.param)
    }

    /// The parameter's range in `scene`: its key's range narrowed by the limits that tie
    /// it to other keys (`Scene::validate`), so that a step never leaves what the scene
    /// accepts. pressure.dP stays below the cornea's limit, the largest admissible ΔP
    /// (docs/MODEL.md §3), an open bound: at the limit the cornea's stretch has an infinite
    /// derivative in ΔP, so neither the model nor its sensitivity can be evaluated there.
    pub fn in_scene(self, scene: &Scene) -> FitParam {
        let mut bounds = self.bounds;
        if self.param == SensParam::Pressure {
            let limit = crate::model::cornea::max_pressure(&scene.params.cornea);
            if bounds.upper.is_none_or(|hi| limit <= hi) {
                bounds.upper = Some(limit);
                bounds.upper_open = true;
            }
        }
        FitParam { bounds, ..self }
    }
}

/// Why `params` cannot be taken in `scene`, if they cannot: a parameter the model of the
/// scene does not have (fibres.D without fibres), or an integrator without sensitivities.
/// The one check of every caller (`grow --sensitivities`, `Scene::set_sensitivities`,
/// `fit`), made before any run; `what` names the option in the message.
pub fn check_params(scene: &Scene, params: &[FitParam], what: &str) -> Result<(), Error> {
    if let Some(why) = params
        .iter()
        .find_map(|p| p.param.check(&scene.params).err())
    {
        let key = params
            .iter()
            .find(|p| p.param.check(&scene.params).is_err())
            .map_or("", |p| p.key());
        return Err(Error::input(
            Subject::Key(key.into()),
            format!("{what}: {why} ({})", scene.origin),
        )
        .with_origin(Origin::Scene(scene.origin.clone())));
    }
    // What the growth's own surfaces and rule cannot differentiate (z_B of a computed
    // surface, or under a rule of dioptres): an input error now, not a failed run at t = 0.
    if let Some(g) = &scene.growth {
        if let Some((p, why)) = params
            .iter()
            .find_map(|p| Some((p, growth::sensitivity_unavailable(p.param, g)?)))
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
    if let Some(sp) = params.iter().find_map(|p| p.param.schedule_param()) {
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
    Ok(())
}

/// Parse `keys` (the `--fit` or `--sensitivities` list): each a parameter, each once.
/// `what` names the option in messages (`--fit`).
pub fn parse_keys(keys: &[impl AsRef<str>], what: &str) -> Result<Vec<FitParam>, Error> {
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
        let p = FitParam::from_key(key).map_err(|why| refuse(format!("{what}: {why}")))?;
        if params.iter().any(|q| q.param == p.param) {
            return Err(refuse(format!("{what}: {key} is listed twice")));
        }
        params.push(p);
    }
    Ok(params)
}

/// The value of parameter `p` in `scene`.
pub fn value_in(scene: &Scene, p: SensParam) -> f64 {
    match keys::find(p.key()).map(|k| k.get(scene)) {
        Some(KeyValue::Float(x)) => x,
        _ => f64::NAN,
    }
}

/// `scene` with the parameters set to `values`, validated (a combination the scene
/// refuses, e.g. beyond a cross-key limit, is an error naming it).
pub fn with_values(scene: &Scene, params: &[FitParam], values: &[f64]) -> Result<Scene, Error> {
    let mut s = scene.clone();
    for (p, &x) in params.iter().zip(values) {
        match keys::find(p.key()).map(|k| k.access) {
            Some(keys::Access::Float { set, .. }) => set(&mut s, x),
            _ => {
                return Err(Error::input(
                    Subject::Key(p.key().into()),
                    format!(
                        "{} is not a real-valued scene key: it cannot be fitted",
                        p.key()
                    ),
                ))
            }
        }
    }
    s.validate()?;
    Ok(s)
}

/// Run the growth of `scene` with the sensitivities to `params`, and read L and dL/dp at
/// the observation times of `data`.
pub fn evaluate(
    scene: &Scene,
    params: &[FitParam],
    data: &Observations,
) -> Result<ModelValues, Error> {
    evaluate_watched(scene, params, data, &mut |_| Ok(()))
}

/// [`evaluate`], calling `step(t)` after every step of the growth run: an error from it
/// stops the run there (a caller's Ctrl-C).
pub fn evaluate_watched(
    scene: &Scene,
    params: &[FitParam],
    data: &Observations,
    step: &mut growth::ProgressFn<'_>,
) -> Result<ModelValues, Error> {
    let Some(problem) = scene.growth_problem()? else {
        return Err(Error::input(
            Subject::Key("growth".into()),
            format!(
                "{}: the scene has no [growth] section (a fit needs a growth run)",
                scene.origin
            ),
        )
        .with_origin(Origin::Scene(scene.origin.clone())));
    };
    let times: Vec<f64> = data.rows.iter().map(|o| o.t).collect();
    let fitted: Vec<SensParam> = params.iter().map(|p| p.param).collect();
    let model = GrowthModel {
        problem: &problem,
        fitted: &fitted,
        times: &times,
    };
    Ok(model.evaluate(step)?)
}

/// The weighted residuals (L − y)/σ and Jacobian (∂L/∂p)/σ of `m` against `data`.
pub fn weighted(m: &ModelValues, data: &Observations) -> (DVector<f64>, DMatrix<f64>) {
    let y: Vec<f64> = data.rows.iter().map(|o| o.axial_length).collect();
    let sigma: Vec<Option<f64>> = data.rows.iter().map(|o| o.sigma).collect();
    eyeshell_core::fit::weighted(m, &y, &sigma)
}

/// Why χ² = Σ rᵢ² or the information matrix JᵀJ cannot be computed in floating point, if
/// so: a weighted residual or sensitivity whose square overflows (an axial length of 1e308
/// mm, or a σ of 1e-160 that makes the weights 1/σ overflow). Names the observation that
/// carries the largest value, as the data file gives it.
pub fn overflow(r: &DVector<f64>, j: &DMatrix<f64>, data: &Observations) -> Option<String> {
    let columns_finite = (0..j.ncols()).all(|c| j.column(c).norm_squared().is_finite());
    if r.norm_squared().is_finite() && columns_finite {
        return None;
    }
    let largest = |i: usize| j.row(i).iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let size = |i: usize| r[i].abs().max(largest(i));
    let i = (0..r.len()).max_by(|&a, &b| size(a).total_cmp(&size(b)))?;
    let o = &data.rows[i];
    Some(format!(
        "{}: observation {} (t = {}, axial_length = {} mm, σ = {}) gives the weighted residual (L − y)/σ = {} and weighted sensitivities (∂L/∂p)/σ up to {}: their squares overflow the largest floating-point number (about 1.8e308), so χ² and JᵀWJ cannot be computed; give the axial lengths and σ in mm",
        data.origin,
        i + 1,
        number(o.t),
        number(o.axial_length),
        o.sigma.map_or("1 (none given)".to_string(), |s| format!("{} mm", number(s))),
        crate::text::decimals6(r[i]),
        crate::text::decimals6(largest(i)),
    ))
}

/// Why the data cannot identify `params` at `values`, as one line naming them, or None
/// (eyeshell-core's `fit::identifiability` on the parameters' keys).
pub fn identifiability(j: &DMatrix<f64>, params: &[FitParam], values: &[f64]) -> Option<String> {
    let names: Vec<&str> = params.iter().map(|p| p.key()).collect();
    eyeshell_core::fit::identifiability(j, &names, values)
}

/// One observation against the fitted model.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ResidualRow {
    pub t: f64,
    /// The observation's age in the scene's time.unit (as the data gave it, or of its t);
    /// absent without a unit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub age: Option<f64>,
    pub axial_length: f64,
    /// σ as given (None: no sigma column).
    pub sigma: Option<f64>,
    /// The model's axial length at t.
    pub model: f64,
    /// model − data (mm).
    pub residual: f64,
    /// (model − data)/σ.
    pub weighted: f64,
}

/// The data file (or arrays) a fit used.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DataRecord {
    pub file: String,
    /// FNV-1a 64 of its bytes (16 hex digits).
    pub fnv1a64: String,
    pub observations: usize,
    pub distinct_times: usize,
    pub sigma: bool,
}

/// One fitted parameter in the report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParameterReport {
    pub key: String,
    pub initial: f64,
    pub estimate: f64,
    pub standard_error: f64,
    /// The validity range the steps were kept in.
    pub range: String,
    /// Whether the range holds the estimate: on a closed bound, or the data pull it beyond
    /// a bound (the Gauss–Newton step from it leaves the range: [`lm::held_by_bounds`]).
    /// Its standard error is then the unconstrained one and means little.
    pub at_bound: bool,
}

/// Everything a fit found: fit.json.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FitReport {
    pub scene: String,
    pub data: DataRecord,
    pub parameters: Vec<ParameterReport>,
    /// Correlation matrix of the estimates (rows and columns in the order of `parameters`).
    pub correlation: Vec<Vec<f64>>,
    /// Covariance s²(JᵀWJ)⁻¹ of the estimates.
    pub covariance: Vec<Vec<f64>>,
    /// How the covariance was scaled: "sigma" (s² = 1: σ taken as the data's known
    /// standard deviations) or "residual variance" (no σ: s² = Σ r²/(n − k)).
    pub covariance_scaling: &'static str,
    /// s².
    pub residual_variance: f64,
    /// Σ rᵢ² at the estimate (χ² when σ is given), and at the start.
    pub chi2: f64,
    pub initial_chi2: f64,
    /// n − k.
    pub degrees_of_freedom: usize,
    /// χ²/(n − k) (NaN when n = k): near 1 when the model and σ describe the data.
    pub reduced_chi2: f64,
    /// √(mean of (model − data)²), mm.
    pub rms_residual: f64,
    pub iterations: usize,
    /// Growth runs (each with its sensitivities): one per iteration and per rejected step.
    pub model_runs: usize,
    #[serde(serialize_with = "crate::rundir::record::convergence")]
    pub convergence: Convergence,
    /// Why the iteration stopped, in words.
    pub convergence_reason: String,
    #[serde(serialize_with = "crate::rundir::record::iteration_records")]
    pub history: Vec<IterationRecord>,
    pub residuals: Vec<ResidualRow>,
    pub wall_seconds: f64,
    /// Seconds in the growth runs.
    pub model_seconds: f64,
}

/// A finished fit: the report and the scene with the estimates.
#[derive(Clone, Debug)]
pub struct Fit {
    pub report: FitReport,
    pub scene: Scene,
}

impl Fit {
    /// The estimates, in the order of the parameters.
    pub fn estimates(&self) -> Vec<f64> {
        self.report.parameters.iter().map(|p| p.estimate).collect()
    }

    /// The standard errors, in the order of the parameters.
    pub fn standard_errors(&self) -> Vec<f64> {
        self.report
            .parameters
            .iter()
            .map(|p| p.standard_error)
            .collect()
    }
}

/// The least-squares problem of a fit: the scene with the parameters set (validated, so a
/// trial beyond a cross-key limit is refused), one growth run with sensitivities per
/// evaluation, weighted by the data's σ.
struct SceneProblem<'a, 's> {
    scene: &'a Scene,
    params: &'a [FitParam],
    data: &'a Observations,
    step: &'a mut growth::ProgressFn<'s>,
    has_sigma: bool,
    dof: usize,
    /// Seconds in the growth runs so far.
    model_seconds: f64,
    /// Whether `step` stopped a run (the caller's interruption): the fit ends there.
    stopped: bool,
}

impl lm::Problem for SceneProblem<'_, '_> {
    type Error = Error;

    fn names(&self) -> Vec<&str> {
        self.params.iter().map(|p| p.key()).collect()
    }

    fn bounds(&self) -> Vec<Bounds> {
        self.params.iter().map(|p| p.bounds).collect()
    }

    fn evaluate(&mut self, values: &[f64]) -> Result<lm::Evaluation, Error> {
        let s = with_values(self.scene, self.params, values)?;
        let step = &mut *self.step;
        let stopped = &mut self.stopped;
        let m = evaluate_watched(&s, self.params, self.data, &mut |t| {
            let heard = step(t);
            *stopped |= heard.is_err();
            heard
        })?;
        self.model_seconds += m.seconds;
        let (r, j) = weighted(&m, self.data);
        if let Some(why) = overflow(&r, &j, self.data) {
            return Err(
                Error::input(Subject::File(self.data.origin.clone().into()), why)
                    .with_origin(Origin::File(self.data.origin.clone().into())),
            );
        }
        Ok((r, j, m.axial_length))
    }

    fn stops(&self, _e: &Error) -> bool {
        self.stopped
    }

    fn variance(&self, chi2: f64) -> f64 {
        if self.has_sigma {
            1.0
        } else {
            chi2 / self.dof as f64
        }
    }
}

/// Fit `params` of `scene` to `data` (start values from the scene), calling `each` after
/// every iteration. Refused before any iteration when the scene or the data cannot give a
/// fit (no growth, not IDA, times beyond t_end, too few observations, an unidentifiable
/// parameter at the start), and after the last when the estimate is unidentifiable.
pub fn fit(
    scene: &Scene,
    data: &Observations,
    params: &[FitParam],
    options: &FitOptions,
    each: &mut dyn FnMut(&IterationRecord),
) -> Result<Fit, Error> {
    fit_watched(scene, data, params, options, each, &mut |_| Ok(()))
}

/// [`fit`], calling `step(t)` after every step of every growth run: an error from it stops
/// the fit there (a caller's Ctrl-C is acted on within a step, not after the whole fit).
pub fn fit_watched(
    scene: &Scene,
    data: &Observations,
    params: &[FitParam],
    options: &FitOptions,
    each: &mut dyn FnMut(&IterationRecord),
    step: &mut growth::ProgressFn<'_>,
) -> Result<Fit, Error> {
    let start = std::time::Instant::now();
    let g = fit_refusals(scene, params)?;
    let params: &[FitParam] = &params.iter().map(|p| p.in_scene(scene)).collect::<Vec<_>>();
    let data = &data.on_clock(g)?;
    data.check_times(g.t_end)?;
    let (n, k) = (data.rows.len(), params.len());
    let has_sigma = data.has_sigma();
    check_counts(data, n, k)?;
    let p0: Vec<f64> = params.iter().map(|p| value_in(scene, p.param)).collect();
    let dof = n - k;
    let variance = |chi2: f64| if has_sigma { 1.0 } else { chi2 / dof as f64 };
    let mut problem = SceneProblem {
        scene,
        params,
        data,
        step,
        has_sigma,
        dof,
        model_seconds: 0.0,
        stopped: false,
    };
    let outcome = lm::minimise(&mut problem, &p0, options, each).map_err(|e| match e {
        lm::LmError::Evaluation(e) => e,
        lm::LmError::Unidentifiable(why) => Error::input_about_nothing(why),
        lm::LmError::RankDeficient(why) => Error::failed(Stage::Fit, why),
        e => Error::failed(Stage::Fit, e.to_string()),
    })?;
    let model_seconds = problem.model_seconds;
    let names: Vec<&str> = params.iter().map(|p| p.key()).collect();
    if let Some(why) = identifiability(&outcome.jacobian, params, &outcome.values) {
        return Err(Error::input_about_nothing(format!(
            "at the estimate ({}): {why}",
            lm::show(&names, &outcome.values)
        )));
    }
    let chi2 = outcome.residuals.norm_squared();
    if !chi2.is_finite() || outcome.values.iter().any(|v| !v.is_finite()) {
        return Err(Error::failed(
            Stage::Fit,
            format!(
                "the fit ended at χ² = {} ({}): not a result",
                number(chi2),
                lm::show(&names, &outcome.values)
            ),
        ));
    }
    let (scaling, s2) = (
        if has_sigma {
            "sigma"
        } else {
            "residual variance"
        },
        variance(chi2),
    );
    let spread = Spread::at(&outcome, params, &names, s2)?;
    let residuals = residual_rows(data, &outcome, g);
    let rms = (residuals
        .iter()
        .map(|r| r.residual * r.residual)
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let bounds: Vec<Bounds> = params.iter().map(|p| p.bounds).collect();
    let held = lm::held_by_bounds(
        &bounds,
        &outcome.values,
        &outcome.residuals,
        &outcome.jacobian,
    );
    let parameters = params
        .iter()
        .enumerate()
        .map(|(a, p)| ParameterReport {
            key: p.key().to_string(),
            initial: p0[a],
            estimate: outcome.values[a],
            standard_error: spread.se[a],
            range: p.bounds.describe(),
            at_bound: held[a],
        })
        .collect();
    let fitted = with_values(scene, params, &outcome.values)?;
    let report = FitReport {
        scene: scene.origin.clone(),
        data: DataRecord {
            file: data.origin.clone(),
            fnv1a64: data.hash.clone(),
            observations: n,
            distinct_times: data.distinct_times(g.t_end).len(),
            sigma: has_sigma,
        },
        parameters,
        correlation: spread.correlation,
        covariance: spread.covariance,
        covariance_scaling: scaling,
        residual_variance: s2,
        chi2,
        initial_chi2: outcome.initial_chi2,
        degrees_of_freedom: dof,
        reduced_chi2: if dof > 0 { chi2 / dof as f64 } else { f64::NAN },
        rms_residual: rms,
        iterations: outcome.iterations,
        model_runs: outcome.evaluations,
        convergence: outcome.convergence,
        convergence_reason: match &outcome.last_refusal {
            Some(why) if outcome.convergence == Convergence::Refused => format!(
                "{} (the last: {})",
                outcome.convergence.describe(options),
                crate::text::excerpt(why, 300)
            ),
            _ => outcome.convergence.describe(options),
        },
        history: outcome.history,
        residuals,
        wall_seconds: start.elapsed().as_secs_f64(),
        model_seconds,
    };
    Ok(Fit {
        report,
        scene: fitted,
    })
}

/// What refuses a fit of `params` in `scene` before the data are read: no growth, not IDA,
/// no parameter, a parameter the scene cannot fit. The scene's growth model otherwise.
fn fit_refusals<'s>(scene: &'s Scene, params: &[FitParam]) -> Result<&'s GrowthParams, Error> {
    let Some(g) = &scene.growth else {
        return Err(Error::input(Subject::Key("growth".into()), format!(
            "{}: the scene has no [growth] section: a fit needs a growth run (set a growth key, e.g. growth.eta0)",
            scene.origin
        ))
        .with_origin(Origin::Scene(scene.origin.clone())));
    };
    if scene.growth_settings.integrator != growth::Integrator::Ida {
        return Err(Error::input(Subject::Key("solver.integrator".into()), format!(
            "a fit needs solver.integrator = \"ida\" (its Jacobian is IDAS's forward sensitivities; {} has \"{}\")",
            scene.origin,
            scene.growth_settings.integrator.name()
        ))
        .with_value(scene.growth_settings.integrator.name())
        .with_origin(Origin::Scene(scene.origin.clone())));
    }
    if params.is_empty() {
        return Err(Error::input(
            Subject::Argument("fit".into()),
            "no parameter to fit",
        ));
    }
    check_params(scene, params, "fit")?;
    Ok(g)
}

/// `n` observations fit `k` parameters: at least k with σ, k + 1 without (the residual
/// variance needs a degree of freedom).
fn check_counts(data: &Observations, n: usize, k: usize) -> Result<(), Error> {
    let has_sigma = data.has_sigma();
    if n < k || (!has_sigma && n == k) {
        return Err(Error::input(
            Subject::File(data.origin.clone().into()),
            format!(
                "{}: {n} observation{} for {k} parameter{}: a fit needs at least {}{}",
                data.origin,
                if n == 1 { "" } else { "s" },
                if k == 1 { "" } else { "s" },
                if has_sigma { k } else { k + 1 },
                if has_sigma {
                    ""
                } else {
                    " (without σ one more, for the residual variance)"
                },
            ),
        )
        .with_value(format!("{n} observations"))
        .with_origin(Origin::File(data.origin.clone().into())));
    }
    Ok(())
}

/// The spread of the estimate: the covariance s² (JᵀWJ)⁻¹, the standard errors and the
/// correlations.
struct Spread {
    se: Vec<f64>,
    correlation: Vec<Vec<f64>>,
    covariance: Vec<Vec<f64>>,
}

impl Spread {
    fn at(
        outcome: &lm::Outcome,
        params: &[FitParam],
        names: &[&str],
        s2: f64,
    ) -> Result<Spread, Error> {
        let k = params.len();
        let inverse = lm::GaussNewton::of(&outcome.jacobian)
            .and_then(|gn| gn.inverse_information())
            .ok_or_else(|| {
                Error::input_about_nothing(format!(
                    "the information matrix JᵀWJ at the estimate cannot be inverted ({})",
                    lm::show(names, &outcome.values)
                ))
            })?;
        let cov = inverse * s2;
        let se: Vec<f64> = (0..k).map(|a| cov[(a, a)].max(0.0).sqrt()).collect();
        if let Some(a) = (0..k).find(|&a| !se[a].is_finite()) {
            return Err(Error::failed(Stage::Fit, format!(
                "the standard error of {} at the estimate is {} ({}): the information matrix JᵀWJ is too close to singular to invert",
                params[a].key(),
                number(se[a]),
                lm::show(names, &outcome.values)
            )));
        }
        let correlation = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| {
                        if a == b {
                            1.0
                        } else {
                            cov[(a, b)] / (se[a] * se[b])
                        }
                    })
                    .collect()
            })
            .collect();
        let covariance = (0..k)
            .map(|a| (0..k).map(|b| cov[(a, b)]).collect())
            .collect();
        Ok(Spread {
            se,
            correlation,
            covariance,
        })
    }
}

/// The observations against the model at the estimate.
fn residual_rows(data: &Observations, outcome: &lm::Outcome, g: &GrowthParams) -> Vec<ResidualRow> {
    data.rows
        .iter()
        .zip(&outcome.model)
        .zip(outcome.residuals.iter())
        .map(|((o, &m), &w)| ResidualRow {
            t: o.t,
            age: g.age_of(o.t).map(|a| o.age.unwrap_or(a)),
            axial_length: o.axial_length,
            sigma: o.sigma,
            model: m,
            residual: m - o.axial_length,
            weighted: w,
        })
        .collect()
}

/// fit.json's text: the report as pretty JSON (non-finite numbers as null), newline-ended.
pub fn report_json(report: &FitReport) -> String {
    let mut text = serde_json::to_string_pretty(report).unwrap_or_default();
    text.push('\n');
    text
}

/// The model's axial length at `points` + 1 evenly spaced times in [0, t_end] (the fitted
/// curve of the plot): one growth run without sensitivities.
pub fn curve(scene: &Scene, points: usize) -> Result<Vec<(f64, f64)>, Error> {
    let Some(problem) = scene.growth_problem()? else {
        return Err(Error::input(
            Subject::Key("growth".into()),
            format!("{}: the scene has no [growth] section", scene.origin),
        )
        .with_origin(Origin::Scene(scene.origin.clone())));
    };
    let mut settings = problem.settings().clone();
    settings.output_times = vec![];
    settings.history_points = points.max(1);
    settings.sensitivities = vec![];
    let problem = (problem.to_builder().settings(settings).build()).map_err(|e| {
        Error::input(
            Subject::Argument("points".into()),
            format!("{}: {e}", scene.origin),
        )
        .with_value(points)
        .with_origin(Origin::Scene(scene.origin.clone()))
    })?;
    let mut out = Vec::with_capacity(points + 1);
    growth::run(
        &problem,
        &mut |sys, t, p| {
            out.push((t, sys.series(t, p)?.axial_length));
            Ok(())
        },
        &mut |_| Ok(()),
    )?;
    Ok(out)
}

#[cfg(test)]
mod tests;
