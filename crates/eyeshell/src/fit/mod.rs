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
pub mod joint;
pub mod param;
pub mod report;

use nalgebra::{DMatrix, DVector};

pub use eyeshell_core::fit::{
    lm, Bounds, FitError, GrowthModel, ModelValues, IDENTIFIABILITY_THRESHOLD,
};

use crate::growth::{self, GrowthParams};
use crate::scene::Scene;
use crate::text::number;
use crate::{Error, Origin, Stage, Subject};

pub use data::{Measured, Observation, Observations};
pub use joint::{Arm, Layout, FD_STEP};
pub use lm::{Convergence, FitOptions, IterationRecord};
pub use param::{
    check_params, parse_fit_keys, parse_keys, values_in, with_values, FitKeyError, FitParam,
};

impl From<FitError> for Error {
    fn from(e: FitError) -> Self {
        match e {
            FitError::Growth(g) => g.into(),
            // A run that records nothing, or a failure the fit adds later: not the user's.
            e => Error::failed_by(Stage::Fit, e),
        }
    }
}

/// Run the growth of `scene` with the sensitivities to `params` (those that have one),
/// and read L and dL/dp at the observation times of `data`.
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
    let times: Vec<f64> = data.rows.iter().map(|o| o.t).collect();
    let sens: Vec<_> = params.iter().filter_map(|p| p.param).collect();
    joint::run_model(scene, &sens, &times, false, step)
}

/// The weighted residuals (L − y)/σ and Jacobian (∂L/∂p)/σ of `m` against the axial
/// lengths of `data` (NaN where a row has none).
pub fn weighted(m: &ModelValues, data: &Observations) -> (DVector<f64>, DMatrix<f64>) {
    let y: Vec<f64> = (data.rows.iter())
        .map(|o| o.axial_length.unwrap_or(f64::NAN))
        .collect();
    let sigma: Vec<Option<f64>> = data.rows.iter().map(|o| o.sigma).collect();
    eyeshell_core::fit::weighted(m, &y, &sigma)
}

/// Why χ² = Σ rᵢ² or the information matrix JᵀJ cannot be computed in floating point, if
/// so: a weighted residual or sensitivity whose square overflows (an axial length of 1e308
/// mm, or a σ of 1e-160 that makes the weights 1/σ overflow). Names the observation that
/// carries the largest value, as the data file gives it.
pub fn overflow(
    r: &DVector<f64>,
    j: &DMatrix<f64>,
    arms: &[Arm],
    rows: &[joint::RowOf],
) -> Option<String> {
    let columns_finite = (0..j.ncols()).all(|c| j.column(c).norm_squared().is_finite());
    if r.norm_squared().is_finite() && columns_finite {
        return None;
    }
    let largest = |i: usize| j.row(i).iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let size = |i: usize| r[i].abs().max(largest(i));
    let i = (0..r.len()).max_by(|&a, &b| size(a).total_cmp(&size(b)))?;
    let row = rows[i];
    let data = &arms[row.arm].data;
    let o = &data.rows[row.obs];
    let (y, sigma) = o.value(row.what)?;
    let (column, unit) = (row.what.column(), row.what.unit());
    Some(format!(
        "{}: observation {} (t = {}, {column} = {} {unit}, σ = {}) gives the weighted residual (model − y)/σ = {} and weighted sensitivities (∂model/∂p)/σ up to {}: their squares overflow the largest floating-point number (about 1.8e308), so χ² and JᵀWJ cannot be computed; give the {column} and σ in {unit}",
        data.origin,
        row.obs + 1,
        number(o.t),
        number(y),
        sigma.map_or("1 (none given)".to_string(), |s| format!("{} {unit}", number(s))),
        crate::text::decimals6(r[i]),
        crate::text::decimals6(largest(i)),
    ))
}

/// Why the data cannot identify the parameters named `names` at `values`, as one line
/// naming them and what data would, or None (eyeshell-core's `fit::identifiability`).
pub fn identifiability(j: &DMatrix<f64>, names: &[&str], values: &[f64]) -> Option<String> {
    let why = eyeshell_core::fit::identifiability(j, names, values)?;
    Some(with_data_advice(&why, names))
}

/// `why` (a refusal naming unidentifiable parameters among `names`) followed by the data
/// that would identify those it names.
fn with_data_advice(why: &str, names: &[&str]) -> String {
    let named: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| {
            why.split("identify ")
                .nth(1)
                .and_then(|rest| rest.split(':').next())
                .is_some_and(|list| list.contains(*n))
        })
        .collect();
    let hints: Vec<String> = named
        .iter()
        .filter_map(|n| Some(format!("{n}: {}", identifying_data(n)?)))
        .collect();
    if hints.is_empty() {
        return why.to_string();
    }
    format!("{why}; data that would identify {}", hints.join("; "))
}

/// What observations determine key `name` (the bracketed arm of a per-arm key aside).
fn identifying_data(name: &str) -> Option<&'static str> {
    let key = name.split('[').next().unwrap_or(name);
    let key = if key.starts_with("optics.surfaces[") || name.starts_with("optics.surfaces[") {
        "optics.surfaces"
    } else {
        key
    };
    Some(match key {
        "growth.eta0" => "axial lengths at two or more times while the eye grows (η0 sets the rate)",
        "growth.Gamma" | "growth.delta" => {
            "axial lengths late in the growth, as the eye nears its limit (Γ and δ shape where and how fast it stops)"
        }
        "optics.surfaces" => {
            "refractions (a refraction_D column) at any time: the surfaces set the eye's power, which the axial length does not see"
        }
        "stimulus.blue.z_B" => "axial lengths of eyes whose blue surface differs (another arm, e.g. other lenses)",
        "pressure.dP" | "material.C" | "material.bending" | "geometry.R0" => {
            "the axial length at t = 0 and early in the growth (the loaded shell's size)"
        }
        _ if key.starts_with("growth.schedule") => {
            "axial lengths spread over the schedule's change (before, during and after it)"
        }
        _ => return None,
    })
}

/// One measurement against the fitted model.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ResidualRow {
    /// The arm's name (a joint fit of several scenes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm: Option<String>,
    pub t: f64,
    /// The observation's age in the scene's time.unit (as the data gave it, or of its t);
    /// absent without a unit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub age: Option<f64>,
    /// The axial length measured (mm), for a row of the axial length.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axial_length: Option<f64>,
    /// The refraction measured (D), for a row of the refraction.
    #[serde(rename = "refraction_D", skip_serializing_if = "Option::is_none")]
    pub refraction_d: Option<f64>,
    /// σ as given (None: no sigma column).
    pub sigma: Option<f64>,
    /// The model's value at t.
    pub model: f64,
    /// model − data (mm or D).
    pub residual: f64,
    /// (model − data)/σ.
    pub weighted: f64,
}

impl ResidualRow {
    /// What this row measures.
    pub fn measured(&self) -> Measured {
        match self.axial_length {
            Some(_) => Measured::AxialLength,
            None => Measured::Refraction,
        }
    }

    /// The value measured (mm or D).
    pub fn observed(&self) -> f64 {
        self.axial_length.or(self.refraction_d).unwrap_or(f64::NAN)
    }
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
    /// The quantities measured: axial_length and/or refraction_D.
    pub measured: Vec<Measured>,
}

/// One arm of a joint fit in the report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ArmRecord {
    pub name: String,
    pub scene: String,
    pub data: DataRecord,
}

/// One fitted parameter in the report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParameterReport {
    pub key: String,
    /// The arm whose own value this is (a per-arm key); absent for a shared key.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm: Option<String>,
    /// How its Jacobian column is taken: "IDAS sensitivity" or "finite differences" (or
    /// both: IDAS for the axial length, differences for the refraction).
    pub jacobian: &'static str,
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

impl ParameterReport {
    /// The key, and its arm in brackets for a per-arm key (`growth.Gamma[dual-focus]`).
    pub fn label(&self) -> String {
        match &self.arm {
            Some(a) => format!("{}[{a}]", self.key),
            None => self.key.clone(),
        }
    }
}

/// Everything a fit found: fit.json.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FitReport {
    /// The scene (each arm's, joined by ", ").
    pub scene: String,
    /// The data (of a joint fit: the files joined, the counts summed).
    pub data: DataRecord,
    /// Each arm of a joint fit (absent for the fit of one scene).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub arms: Vec<ArmRecord>,
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

/// A finished fit: the report and the scene with the estimates (of each arm, in order;
/// `scene` is the first's).
#[derive(Clone, Debug)]
pub struct Fit {
    pub report: FitReport,
    pub scene: Scene,
    pub scenes: Vec<Scene>,
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

/// The least-squares problem of a fit: each arm's scene with its parameters set
/// (validated, so a trial beyond a cross-key limit is refused), its runs per evaluation
/// ([`joint::stack`]), weighted by the data's σ.
struct JointProblem<'a, 's> {
    arms: &'a [Arm],
    layout: &'a Layout,
    names: Vec<String>,
    bounds: Vec<Bounds>,
    rows: Vec<joint::RowOf>,
    step: &'a mut growth::ProgressFn<'s>,
    has_sigma: bool,
    dof: usize,
    /// Growth runs so far, and their seconds.
    runs: (usize, f64),
    /// Whether `step` stopped a run (the caller's interruption): the fit ends there.
    stopped: bool,
}

impl lm::Problem for JointProblem<'_, '_> {
    type Error = Error;

    fn names(&self) -> Vec<&str> {
        self.names.iter().map(String::as_str).collect()
    }

    fn bounds(&self) -> Vec<Bounds> {
        self.bounds.clone()
    }

    fn evaluate(&mut self, values: &[f64]) -> Result<lm::Evaluation, Error> {
        let step = &mut *self.step;
        let stopped = &mut self.stopped;
        let (r, j, model) = joint::stack(
            self.arms,
            self.layout,
            values,
            &mut |t| {
                let heard = step(t);
                *stopped |= heard.is_err();
                heard
            },
            &mut self.runs,
        )?;
        if let Some(why) = overflow(&r, &j, self.arms, &self.rows) {
            let origin = self.arms[self.rows[0].arm].data.origin.clone();
            return Err(Error::input(Subject::File(origin.clone().into()), why)
                .with_origin(Origin::File(origin.into())));
        }
        Ok((r, j, model))
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
    let arm = Arm {
        name: None,
        scene: scene.clone(),
        data: data.clone(),
    };
    fit_arms(vec![arm], params, &[], options, each, step)
}

/// The joint fit of several arms (each a scene and its data): the keys `shared` take one
/// value in every arm, the keys `per_arm` one value in each; one Levenberg–Marquardt over
/// the stacked residuals of every arm. Start values: the first arm's scene for a shared
/// key, each arm's own for a per-arm key. Refused as [`fit`] is, and for arms of the
/// same name, a key both shared and per arm, refraction data of a scene that computes no
/// refraction.
pub fn fit_arms(
    arms: Vec<Arm>,
    shared: &[FitParam],
    per_arm: &[FitParam],
    options: &FitOptions,
    each: &mut dyn FnMut(&IterationRecord),
    step: &mut growth::ProgressFn<'_>,
) -> Result<Fit, Error> {
    let start = std::time::Instant::now();
    let arms = prepare_arms(arms, shared, per_arm)?;
    let layout = Layout {
        shared: shared.to_vec(),
        per_arm: per_arm.to_vec(),
        arms: arms.len(),
    };
    let rows = joint::rows_of(&arms);
    let (n, k) = (rows.len(), layout.len());
    let has_sigma = arms.iter().all(|a| a.data.has_sigma());
    check_counts(&arms, n, k, has_sigma)?;
    let p0: Vec<f64> = (0..k)
        .map(|g| {
            let (p, a) = layout.at(g);
            p.value_in(&arms[a.unwrap_or(0)].scene)
        })
        .collect::<Result<_, _>>()?;
    let dof = n - k;
    let names = joint::names(&layout, &arms);
    let mut problem = JointProblem {
        arms: &arms,
        layout: &layout,
        bounds: joint::bounds(&layout, &arms),
        names: names.clone(),
        rows: rows.clone(),
        step,
        has_sigma,
        dof,
        runs: (0, 0.0),
        stopped: false,
    };
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let outcome = lm::minimise(&mut problem, &p0, options, each).map_err(|e| match e {
        lm::LmError::Evaluation(e) => e,
        lm::LmError::Unidentifiable(why) => {
            Error::input_about_nothing(with_data_advice(&why, &name_refs))
        }
        lm::LmError::RankDeficient(why) => Error::failed(Stage::Fit, why),
        e => Error::failed(Stage::Fit, e.to_string()),
    })?;
    let (runs, model_seconds) = problem.runs;
    let bounds = problem.bounds.clone();
    if let Some(why) = identifiability(&outcome.jacobian, &name_refs, &outcome.values) {
        return Err(Error::input_about_nothing(format!(
            "at the estimate ({}): {why}",
            lm::show(&name_refs, &outcome.values)
        )));
    }
    let chi2 = outcome.residuals.norm_squared();
    if !chi2.is_finite() || outcome.values.iter().any(|v| !v.is_finite()) {
        return Err(Error::failed(
            Stage::Fit,
            format!(
                "the fit ended at χ² = {} ({}): not a result",
                number(chi2),
                lm::show(&name_refs, &outcome.values)
            ),
        ));
    }
    let s2 = if has_sigma { 1.0 } else { chi2 / dof as f64 };
    let spread = Spread::at(&outcome, &name_refs, s2)?;
    let parameters = parameter_reports(&layout, &arms, &bounds, &p0, &outcome, &spread.se);
    let local = layout.local();
    let scenes = (arms.iter().enumerate())
        .map(|(a, arm)| with_values(&arm.scene, &local, &layout.local_values(a, &outcome.values)))
        .collect::<Result<Vec<_>, _>>()?;
    let residuals = residual_rows(&arms, &rows, &outcome);
    let rms = (residuals
        .iter()
        .map(|r| r.residual * r.residual)
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let records: Vec<ArmRecord> = arms
        .iter()
        .map(|a| ArmRecord {
            name: a.name.clone().unwrap_or_default(),
            scene: a.scene.origin.clone(),
            data: data_record(a),
        })
        .collect();
    let single = arms.len() == 1 && arms[0].name.is_none();
    let report = FitReport {
        scene: (arms.iter().map(|a| a.scene.origin.as_str()))
            .collect::<Vec<_>>()
            .join(", "),
        data: combined_record(&records),
        arms: if single { vec![] } else { records },
        parameters,
        correlation: spread.correlation,
        covariance: spread.covariance,
        covariance_scaling: if has_sigma {
            "sigma"
        } else {
            "residual variance"
        },
        residual_variance: s2,
        chi2,
        initial_chi2: outcome.initial_chi2,
        degrees_of_freedom: dof,
        reduced_chi2: if dof > 0 { chi2 / dof as f64 } else { f64::NAN },
        rms_residual: rms,
        iterations: outcome.iterations,
        model_runs: runs,
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
        scene: scenes[0].clone(),
        scenes,
    })
}

/// Each parameter of the vector in the report: its key and arm, how its column was taken,
/// its start, estimate, standard error and range.
fn parameter_reports(
    layout: &Layout,
    arms: &[Arm],
    bounds: &[Bounds],
    p0: &[f64],
    outcome: &lm::Outcome,
    se: &[f64],
) -> Vec<ParameterReport> {
    let held = lm::held_by_bounds(
        bounds,
        &outcome.values,
        &outcome.residuals,
        &outcome.jacobian,
    );
    let refraction = arms.iter().any(|a| a.data.has(Measured::Refraction));
    (0..layout.len())
        .map(|g| {
            let (p, a) = layout.at(g);
            ParameterReport {
                key: p.key().to_string(),
                arm: a.and_then(|a| arms[a].name.clone()),
                jacobian: match (p.has_sensitivity(), refraction) {
                    (true, false) => "IDAS sensitivity",
                    (true, true) => {
                        "IDAS sensitivity (axial length), finite differences (refraction)"
                    }
                    (false, _) => "finite differences",
                },
                initial: p0[g],
                estimate: outcome.values[g],
                standard_error: se[g],
                range: bounds[g].describe(),
                at_bound: held[g],
            }
        })
        .collect()
}

/// The data record of one arm.
fn data_record(a: &Arm) -> DataRecord {
    let t_end = a.scene.growth.as_ref().map_or(f64::INFINITY, |g| g.t_end);
    DataRecord {
        file: a.data.origin.clone(),
        fnv1a64: a.data.hash.clone(),
        observations: a.data.rows.len(),
        distinct_times: a.data.distinct_times(t_end).len(),
        sigma: a.data.has_sigma(),
        measured: [Measured::AxialLength, Measured::Refraction]
            .into_iter()
            .filter(|&m| a.data.has(m))
            .collect(),
    }
}

/// The records of several arms as one: the files joined, the counts added (a single
/// arm's own record).
fn combined_record(records: &[ArmRecord]) -> DataRecord {
    if let [one] = records {
        return one.data.clone();
    }
    let join = |f: &dyn Fn(&DataRecord) -> String| {
        records
            .iter()
            .map(|r| f(&r.data))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut measured = vec![];
    for r in records {
        for m in &r.data.measured {
            if !measured.contains(m) {
                measured.push(*m);
            }
        }
    }
    DataRecord {
        file: join(&|d| d.file.clone()),
        fnv1a64: join(&|d| d.fnv1a64.clone()),
        observations: records.iter().map(|r| r.data.observations).sum(),
        distinct_times: records.iter().map(|r| r.data.distinct_times).sum(),
        sigma: records.iter().all(|r| r.data.sigma),
        measured,
    }
}

/// The arms checked and their data on their scenes' clocks: what refuses a fit before any
/// run (no growth, not IDA, a parameter the scene cannot fit, data outside the run,
/// refraction data of a scene without optics, two arms of one name, a key both shared and
/// per arm, a per-arm key with one arm).
fn prepare_arms(
    arms: Vec<Arm>,
    shared: &[FitParam],
    per_arm: &[FitParam],
) -> Result<Vec<Arm>, Error> {
    if shared.is_empty() && per_arm.is_empty() {
        return Err(Error::input(
            Subject::Argument("fit".into()),
            "no parameter to fit",
        ));
    }
    if arms.is_empty() {
        return Err(Error::input(
            Subject::Argument("arms".into()),
            "no arm to fit: give a scene and its data",
        ));
    }
    if let Some(p) = per_arm
        .iter()
        .find(|p| shared.iter().any(|q| q.key() == p.key()))
    {
        return Err(Error::input(
            Subject::Key(p.key().into()),
            format!(
                "{} is both fitted in common and per arm: name it once",
                p.key()
            ),
        )
        .with_origin(Origin::Argument));
    }
    if !per_arm.is_empty() && arms.len() < 2 {
        return Err(Error::input(
            Subject::Argument("per-arm".into()),
            format!(
                "{} is fitted per arm: a key of each arm's own needs two arms or more",
                per_arm[0].key()
            ),
        )
        .with_origin(Origin::Argument));
    }
    for (a, arm) in arms.iter().enumerate() {
        if let Some(name) = &arm.name {
            if arms[..a].iter().any(|b| b.name.as_deref() == Some(name)) {
                return Err(Error::input(
                    Subject::Argument("arm".into()),
                    format!("arm {name}: two arms have this name (each arm's is its own)"),
                )
                .with_value(name.clone())
                .with_origin(Origin::Argument));
            }
        }
    }
    let params: Vec<FitParam> = shared.iter().chain(per_arm).cloned().collect();
    arms.into_iter()
        .map(|arm| {
            let g = fit_refusals(&arm.scene, &params)?;
            let data = arm.data.on_clock(g)?;
            data.check_times(g.t_end)?;
            if data.has(Measured::Refraction) && g.source != crate::model::optics::Source::Optics {
                let origin = arm.scene.origin_of_key("stimulus.source");
                return Err(Error::input(Subject::File(data.origin.clone().into()), format!(
                    "{}: the data give refraction_D, but the scene computes no refraction: its stimulus is not from the optics (stimulus.source = \"{}\" in {origin}); set stimulus.source = \"optics\" or leave the refraction out",
                    data.origin,
                    crate::model::optics::SOURCES[g.source as usize]
                ))
                .with_origin(Origin::File(data.origin.clone().into())));
            }
            Ok(Arm { data, ..arm })
        })
        .collect()
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

/// `n` measurements fit `k` parameters: at least k with σ, k + 1 without (the residual
/// variance needs a degree of freedom); and without σ one quantity only.
fn check_counts(arms: &[Arm], n: usize, k: usize, has_sigma: bool) -> Result<(), Error> {
    let data = &arms[0].data;
    let origin = arms
        .iter()
        .map(|a| a.data.origin.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    if !has_sigma {
        let both = arms.iter().any(|a| a.data.has(Measured::AxialLength))
            && arms.iter().any(|a| a.data.has(Measured::Refraction));
        let some = arms.iter().any(|a| a.data.has_sigma());
        if both || some {
            let why = if some {
                "some files give σ and some do not"
            } else {
                "without σ, axial lengths (mm) and refractions (D) cannot share one residual variance"
            };
            return Err(Error::input(
                Subject::File(data.origin.clone().into()),
                format!("{origin}: {why}: a joint fit weighs every measurement by its σ, so give σ in every file"),
            )
            .with_origin(Origin::File(data.origin.clone().into())));
        }
    }
    if n < k || (!has_sigma && n == k) {
        return Err(Error::input(
            Subject::File(data.origin.clone().into()),
            format!(
                "{origin}: {n} observation{} for {k} parameter{}: a fit needs at least {}{}",
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
    fn at(outcome: &lm::Outcome, names: &[&str], s2: f64) -> Result<Spread, Error> {
        let k = names.len();
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
                names[a],
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

/// Each measurement against the model at the estimate, in the order of `rows`.
fn residual_rows(arms: &[Arm], rows: &[joint::RowOf], outcome: &lm::Outcome) -> Vec<ResidualRow> {
    rows.iter()
        .zip(&outcome.model)
        .zip(outcome.residuals.iter())
        .map(|((row, &m), &w)| {
            let arm = &arms[row.arm];
            let o = &arm.data.rows[row.obs];
            let (y, sigma) = o.value(row.what).unwrap_or((f64::NAN, None));
            let g = arm.scene.growth.as_ref();
            ResidualRow {
                arm: arm.name.clone(),
                t: o.t,
                age: g.and_then(|g| g.age_of(o.t)).map(|a| o.age.unwrap_or(a)),
                axial_length: (row.what == Measured::AxialLength).then_some(y),
                refraction_d: (row.what == Measured::Refraction).then_some(y),
                sigma,
                model: m,
                residual: m - y,
                weighted: w,
            }
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
#[cfg(test)]
mod tests_joint;
