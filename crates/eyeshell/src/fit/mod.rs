//! Calibration: the parameters of a growth scene that fit a measured growth curve
//! (`eyeshell fit`, `eyeshell.fit`).
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
pub mod lm;
pub mod report;

use nalgebra::{DMatrix, DVector};

use crate::growth::dae::SensParam;
use crate::growth::{self, SensitivityRow};
use crate::scene::keys::{self, KeyValue, Rule};
use crate::scene::Scene;
use crate::text::number;
use crate::Error;

pub use data::{Observation, Observations};
pub use lm::{Convergence, FitOptions, IterationRecord};

/// The smallest eigenvalue the correlation form of the information matrix (JᵀJ scaled to
/// a unit diagonal) may have, and the smallest share of the largest scaled column norm a
/// parameter's column may have: below either the data cannot tell the parameter (or a
/// combination of parameters) apart, and the fit is refused. An eigenvalue of 1e-8 is a
/// correlation of 1 − 1e-8 between two parameters: their standard errors would be 10⁴
/// times their separate ones.
pub const IDENTIFIABILITY_THRESHOLD: f64 = 1e-8;

/// A fitted parameter: its key and its validity range (from the scene key's rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitParam {
    pub param: SensParam,
    pub bounds: Bounds,
}

/// The range a parameter may take: a lower bound, open (> lo) or closed (≥ lo), or none;
/// and an upper bound likewise. Open bounds are approached, never reached ([`lm`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Bounds {
    pub lower: Option<f64>,
    pub lower_open: bool,
    pub upper: Option<f64>,
    pub upper_open: bool,
}

impl Bounds {
    pub const NONE: Bounds = Bounds {
        lower: None,
        lower_open: false,
        upper: None,
        upper_open: false,
    };

    /// The range of a key's rule (`eyeshell keys`).
    pub fn of_rule(rule: Rule) -> Bounds {
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

    /// The range as text: `> 0`, `[0, 1)`, `any`.
    pub fn describe(&self) -> String {
        let (lo, hi) = (self.lower.map(number), self.upper.map(number));
        match (lo, hi) {
            (None, None) => "any".into(),
            (Some(lo), None) => format!("{} {lo}", if self.lower_open { ">" } else { "≥" }),
            (None, Some(hi)) => format!("{} {hi}", if self.upper_open { "<" } else { "≤" }),
            (Some(lo), Some(hi)) => format!(
                "{}{lo}, {hi}{}",
                if self.lower_open { "(" } else { "[" },
                if self.upper_open { ")" } else { "]" }
            ),
        }
    }

    /// Whether `x` lies outside the range (on an open bound counts as outside).
    pub fn excludes(&self, x: f64) -> bool {
        let below = self
            .lower
            .is_some_and(|lo| x < lo || (self.lower_open && x <= lo));
        let above = self
            .upper
            .is_some_and(|hi| x > hi || (self.upper_open && x >= hi));
        below || above
    }
}

impl FitParam {
    /// The parameter of scene key `key`, with its range; a one-line refusal otherwise.
    pub fn from_key(key: &str) -> Result<FitParam, String> {
        let param = keys::sensitivity_param(key)?;
        let bounds = keys::find(param.key()).map_or(Bounds::NONE, |k| Bounds::of_rule(k.rule));
        Ok(FitParam { param, bounds })
    }

    pub fn key(&self) -> &'static str {
        self.param.key()
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
        return Err(Error::input(format!("{what}: {why} ({})", scene.origin)));
    }
    let integrator = scene.growth_settings.integrator;
    if integrator != growth::Integrator::Ida {
        return Err(Error::input(format!(
            "{what} need solver.integrator = \"ida\" ({} has \"{}\")",
            scene.origin,
            integrator.name()
        )));
    }
    Ok(())
}

/// Parse `keys` (the `--fit` or `--sensitivities` list): each a parameter, each once.
/// `what` names the option in messages (`--fit`).
pub fn parse_keys(keys: &[impl AsRef<str>], what: &str) -> Result<Vec<FitParam>, Error> {
    if keys.is_empty() {
        return Err(Error::input(format!("{what}: no parameter given")));
    }
    let mut params: Vec<FitParam> = Vec::with_capacity(keys.len());
    for key in keys {
        let key = key.as_ref().trim();
        let p = FitParam::from_key(key).map_err(|why| Error::input(format!("{what}: {why}")))?;
        if params.iter().any(|q| q.param == p.param) {
            return Err(Error::input(format!("{what}: {key} is listed twice")));
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
                return Err(Error::input(format!(
                    "{} is not a real-valued scene key: it cannot be fitted",
                    p.key()
                )))
            }
        }
    }
    s.validate()?;
    Ok(s)
}

/// The model at the observations: L(tᵢ) and ∂L(tᵢ)/∂pⱼ for every observation i (in the
/// order of `data`) and parameter j, from one growth run with forward sensitivities that
/// records the distinct observation times (and t = 0 and t_end, as every run does).
#[derive(Clone, Debug)]
pub struct ModelValues {
    pub axial_length: Vec<f64>,
    /// Row i, column j.
    pub jacobian: DMatrix<f64>,
    /// The run's wall time (s).
    pub seconds: f64,
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
    let Some(g) = &scene.growth else {
        return Err(Error::input(format!(
            "{}: the scene has no [growth] section (a fit needs a growth run)",
            scene.origin
        )));
    };
    let t_end = g.t_end;
    let times = data.distinct_times(t_end);
    let mut settings = scene.growth_settings.clone();
    settings.output_times = times
        .iter()
        .copied()
        .filter(|&t| t > 0.0 && t < t_end)
        .collect();
    settings.history_points = 0;
    settings.sensitivities = params.iter().map(|p| p.param).collect();
    // Per distinct time: L and its sensitivities (NaN until recorded).
    let k = params.len();
    let mut at: Vec<(f64, Vec<f64>)> = vec![(f64::NAN, vec![f64::NAN; k]); times.len()];
    let slot = |t: f64| times.iter().position(|&x| x == t);
    let mut take = |rows: &[SensitivityRow]| -> Result<(), growth::ObserverError> {
        if let Some(first) = rows.first() {
            if let Some(i) = slot(first.t) {
                at[i].0 = first.axial_length;
                for (j, r) in rows.iter().enumerate().take(k) {
                    at[i].1[j] = r.d_axial_length;
                }
            }
        }
        Ok(())
    };
    let start = std::time::Instant::now();
    growth::run_with(
        &scene.params,
        &scene.solver,
        g,
        &settings,
        &mut take,
        &mut |_, _, _| Ok(()),
        step,
    )?;
    let seconds = start.elapsed().as_secs_f64();
    let n = data.rows.len();
    let mut axial_length = Vec::with_capacity(n);
    let mut jacobian = DMatrix::zeros(n, k);
    for (i, obs) in data.rows.iter().enumerate() {
        // The distinct time this observation was merged into.
        let d = times
            .iter()
            .position(|&x| (x - obs.t).abs() <= 1e-9 * t_end)
            .expect("every observation time has its distinct time");
        let (l, dl) = &at[d];
        if !l.is_finite() || dl.iter().any(|x| !x.is_finite()) {
            return Err(Error::failed(format!(
                "the growth run recorded no finite axial length or sensitivity at t = {}",
                number(times[d])
            )));
        }
        axial_length.push(*l);
        for j in 0..k {
            jacobian[(i, j)] = dl[j];
        }
    }
    Ok(ModelValues {
        axial_length,
        jacobian,
        seconds,
    })
}

/// The weighted residuals (L − y)/σ and Jacobian (∂L/∂p)/σ of `m` against `data`.
pub fn weighted(m: &ModelValues, data: &Observations) -> (DVector<f64>, DMatrix<f64>) {
    let n = data.rows.len();
    let mut r = DVector::zeros(n);
    let mut j = m.jacobian.clone();
    for (i, obs) in data.rows.iter().enumerate() {
        let w = 1.0 / obs.sigma.unwrap_or(1.0);
        r[i] = (m.axial_length[i] - obs.axial_length) * w;
        for c in 0..j.ncols() {
            j[(i, c)] *= w;
        }
    }
    (r, j)
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

/// Why the data cannot identify the parameters, as one line naming them, or None.
///
/// Each column of J is scaled by the parameter's magnitude (|p|, or 1 at p = 0): a column
/// below [`IDENTIFIABILITY_THRESHOLD`] of the largest is a parameter the data do not depend
/// on. Otherwise the information matrix JᵀJ is scaled to a unit diagonal (its correlation
/// form, independent of the parameters' units) and its smallest eigenvalue compared with
/// the threshold; the parameters with the largest components of that eigenvector (at least
/// half the largest) are named.
pub fn identifiability(j: &DMatrix<f64>, params: &[FitParam], values: &[f64]) -> Option<String> {
    let k = params.len();
    let norms: Vec<f64> = (0..k)
        .map(|c| {
            j.column(c).norm()
                * if values[c] != 0.0 {
                    values[c].abs()
                } else {
                    1.0
                }
        })
        .collect();
    let top = norms.iter().fold(0.0_f64, |a, &b| a.max(b));
    let flat: Vec<&str> = (0..k)
        .filter(|&c| !(norms[c] > IDENTIFIABILITY_THRESHOLD * top))
        .map(|c| params[c].key())
        .collect();
    if !flat.is_empty() {
        return Some(format!(
            "the data cannot identify {}: the model's axial length at the observation times does not depend on {} (|p|·‖∂L/∂p / σ‖ below {IDENTIFIABILITY_THRESHOLD:e} of the largest parameter's); fix {} in the scene, or add observations where {} matter{}",
            flat.join(", "),
            if flat.len() == 1 { "it" } else { "them" },
            if flat.len() == 1 { "it" } else { "them" },
            if flat.len() == 1 { "it" } else { "they" },
            if flat.len() == 1 { "s" } else { "" },
        ));
    }
    if k < 2 {
        return None;
    }
    // The correlation form of JᵀWJ is (JD⁻¹)ᵀ(JD⁻¹), D the columns' norms: its eigenvalues
    // are the squared singular values of JD⁻¹, taken from J's SVD without forming JᵀJ
    // (whose smallest eigenvalue would carry the round-off of J's condition number squared).
    let d: Vec<f64> = (0..k).map(|c| j.column(c).norm()).collect();
    let scaled = DMatrix::from_fn(j.nrows(), k, |row, c| j[(row, c)] / d[c]);
    let svd = nalgebra::SVD::new(scaled, false, true);
    let v_t = svd.v_t.as_ref()?;
    let (i_min, lambda) = svd
        .singular_values
        .iter()
        .map(|s| s * s)
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    if lambda > IDENTIFIABILITY_THRESHOLD {
        return None;
    }
    let v = v_t.row(i_min).transpose();
    let vmax = v.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let mut order: Vec<usize> = (0..k).collect();
    // Largest components first, as printed (3 decimals); equal ones in the order of the keys,
    // so that round-off does not reorder the names.
    let shown = |c: usize| (v[c].abs() * 1e3).round();
    order.sort_by(|&a, &b| shown(b).total_cmp(&shown(a)).then(a.cmp(&b)));
    let named: Vec<&str> = order
        .iter()
        .filter(|&&c| v[c].abs() >= 0.5 * vmax)
        .map(|&c| params[c].key())
        .collect();
    let direction: Vec<String> = order
        .iter()
        .filter(|&&c| v[c].abs() >= 0.05)
        .map(|&c| format!("{:+.3} {}", v[c], params[c].key()))
        .collect();
    Some(format!(
        "the data cannot identify {}: the information matrix JᵀWJ is near-singular (smallest eigenvalue of its correlation form {:.2e} ≤ {IDENTIFIABILITY_THRESHOLD:e}, along {}): the data do not determine that combination of them; fix {} in the scene, or add observations that separate them",
        named.join(" from ").replace(" from ", if named.len() > 2 { ", " } else { " from " }),
        lambda.max(0.0),
        direction.join(" "),
        if named.len() == 1 { named[0].to_string() } else { format!("one of {}", named.join(", ")) },
    ))
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
    pub convergence: Convergence,
    /// Why the iteration stopped, in words.
    pub convergence_reason: String,
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
    let Some(g) = &scene.growth else {
        return Err(Error::input(format!(
            "{}: the scene has no [growth] section: a fit needs a growth run (set a growth key, e.g. growth.eta0)",
            scene.origin
        )));
    };
    if scene.growth_settings.integrator != growth::Integrator::Ida {
        return Err(Error::input(format!(
            "a fit needs solver.integrator = \"ida\" (its Jacobian is IDAS's forward sensitivities; {} has \"{}\")",
            scene.origin,
            scene.growth_settings.integrator.name()
        )));
    }
    if params.is_empty() {
        return Err(Error::input("no parameter to fit"));
    }
    check_params(scene, params, "fit")?;
    let params: &[FitParam] = &params.iter().map(|p| p.in_scene(scene)).collect::<Vec<_>>();
    let data = &data.on_clock(g)?;
    data.check_times(g.t_end)?;
    let (n, k) = (data.rows.len(), params.len());
    let has_sigma = data.has_sigma();
    if n < k || (!has_sigma && n == k) {
        return Err(Error::input(format!(
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
        )));
    }
    let p0: Vec<f64> = params.iter().map(|p| value_in(scene, p.param)).collect();
    let mut model_seconds = 0.0;
    let mut eval = |values: &[f64]| -> Result<lm::Evaluation, Error> {
        let s = with_values(scene, params, values)?;
        let m = evaluate_watched(&s, params, data, step)?;
        model_seconds += m.seconds;
        let (r, j) = weighted(&m, data);
        if let Some(why) = overflow(&r, &j, data) {
            return Err(Error::input(why));
        }
        Ok((r, j, m.axial_length))
    };
    let dof = n - k;
    let variance = |chi2: f64| if has_sigma { 1.0 } else { chi2 / dof as f64 };
    let outcome = lm::minimise(&mut eval, params, &p0, options, &variance, each)?;
    let names: Vec<&str> = params.iter().map(|p| p.key()).collect();
    if let Some(why) = identifiability(&outcome.jacobian, params, &outcome.values) {
        return Err(Error::input(format!(
            "at the estimate ({}): {why}",
            lm::show(&names, &outcome.values)
        )));
    }
    let chi2 = outcome.residuals.norm_squared();
    if !chi2.is_finite() || outcome.values.iter().any(|v| !v.is_finite()) {
        return Err(Error::failed(format!(
            "the fit ended at χ² = {} ({}): not a result",
            number(chi2),
            lm::show(&names, &outcome.values)
        )));
    }
    let (scaling, s2) = (
        if has_sigma {
            "sigma"
        } else {
            "residual variance"
        },
        variance(chi2),
    );
    let inverse = lm::GaussNewton::of(&outcome.jacobian)
        .and_then(|gn| gn.inverse_information())
        .ok_or_else(|| {
            Error::input(format!(
                "the information matrix JᵀWJ at the estimate cannot be inverted ({})",
                lm::show(&names, &outcome.values)
            ))
        })?;
    let cov = inverse * s2;
    let se: Vec<f64> = (0..k).map(|a| cov[(a, a)].max(0.0).sqrt()).collect();
    if let Some(a) = (0..k).find(|&a| !se[a].is_finite()) {
        return Err(Error::failed(format!(
            "the standard error of {} at the estimate is {} ({}): the information matrix JᵀWJ is too close to singular to invert",
            params[a].key(),
            number(se[a]),
            lm::show(&names, &outcome.values)
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
    let residuals: Vec<ResidualRow> = data
        .rows
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
        .collect();
    let rms = (residuals
        .iter()
        .map(|r| r.residual * r.residual)
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let held = lm::held_by_bounds(
        params,
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
            standard_error: se[a],
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
        correlation,
        covariance,
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

/// fit.json's text: the report as pretty JSON (non-finite numbers as null), newline-ended.
pub fn report_json(report: &FitReport) -> String {
    let mut text = serde_json::to_string_pretty(report).unwrap_or_default();
    text.push('\n');
    text
}

/// The model's axial length at `points` + 1 evenly spaced times in [0, t_end] (the fitted
/// curve of the plot): one growth run without sensitivities.
pub fn curve(scene: &Scene, points: usize) -> Result<Vec<(f64, f64)>, Error> {
    let Some(g) = &scene.growth else {
        return Err(Error::input(format!(
            "{}: the scene has no [growth] section",
            scene.origin
        )));
    };
    let mut settings = scene.growth_settings.clone();
    settings.output_times = vec![];
    settings.history_points = points.max(1);
    settings.sensitivities = vec![];
    let mut out = Vec::with_capacity(points + 1);
    growth::run(
        &scene.params,
        &scene.solver,
        g,
        &settings,
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
