//! Calibration's numerics: the parameters of a growth model that fit a measured growth curve.
//!
//! The observations are axial lengths yᵢ at times tᵢ with standard deviations σᵢ (1 when
//! none are given). The residuals are rᵢ = (L(tᵢ; p) − yᵢ)/σᵢ, L the model's axial length
//! from one growth run that records exactly the distinct observation times; the cost is
//! C = ½ Σ rᵢ². The Jacobian Jᵢⱼ = ∂L(tᵢ)/∂pⱼ / σᵢ is the run's forward sensitivities
//! (IDAS, [`crate::growth::dae::SensParam`]), not finite differences: one run per
//! iteration gives the residuals and the Jacobian together ([`GrowthModel`]).
//!
//! The minimiser ([`lm`]) is Levenberg–Marquardt with Marquardt's scaling and projected
//! steps onto each parameter's range ([`Bounds`]), generic over the problem
//! ([`lm::Problem`]); identifiability is checked on the information matrix JᵀJ at the
//! start and at the estimate ([`identifiability`]); the standard errors come from the
//! Gauss–Newton covariance ([`lm::GaussNewton`]).
//!
//! Which scene keys are parameters, their ranges, the data file and the report are the
//! `eyeshell` crate's (`eyeshell::fit`), which builds a [`GrowthModel`] from a scene.

pub mod lm;

use nalgebra::{DMatrix, DVector};

use crate::growth::dae::SensParam;
use crate::growth::{self, GrowthError, SensitivityRow};
use crate::text::number;

/// The smallest eigenvalue the correlation form of the information matrix (JᵀJ scaled to
/// a unit diagonal) may have, and the smallest share of the largest scaled column norm a
/// parameter's column may have: below either the data cannot tell the parameter (or a
/// combination of parameters) apart, and the fit is refused. An eigenvalue of 1e-8 is a
/// correlation of 1 − 1e-8 between two parameters: their standard errors would be 10⁴
/// times their separate ones.
pub const IDENTIFIABILITY_THRESHOLD: f64 = 1e-8;

/// The range a parameter may take: a lower bound, open (> lo) or closed (≥ lo), or none;
/// and an upper bound likewise. Open bounds are approached, never reached ([`lm`]).
#[derive(Clone, Copy, Debug, PartialEq)]
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

/// Why a growth model could not be evaluated at the observations.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// The growth run failed.
    #[error(transparent)]
    Growth(#[from] GrowthError),
    /// The run ended without a finite value at an observation time.
    #[error("the growth run recorded no finite axial length or sensitivity at t = {}", number(*.t))]
    NotRecorded { t: f64 },
}

/// The distinct times among `times`, sorted: times within 1e-9 `t_end` of each other are one.
pub fn distinct_times(times: &[f64], t_end: f64) -> Vec<f64> {
    let mut times = times.to_vec();
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * t_end);
    times
}

/// The model at the observations: L(tᵢ) and ∂L(tᵢ)/∂pⱼ for every observation i (in the
/// order of the observations) and parameter j, from one growth run with forward
/// sensitivities that records the distinct observation times (and t = 0 and t_end, as
/// every run does).
#[derive(Clone, Debug)]
pub struct ModelValues {
    pub axial_length: Vec<f64>,
    /// The pole's refraction of the naked eye (D) at each observation, as series.csv's
    /// refraction_D: NaN where the run computes none (a stimulus not from optics).
    pub refraction_d: Vec<f64>,
    /// Row i, column j.
    pub jacobian: DMatrix<f64>,
    /// The run's wall time (s).
    pub seconds: f64,
}

/// The growth model of a fit: the growth problem (an eye, its growth and solver settings),
/// the parameters fitted and the observation times (in the model's time, in the order of
/// the data).
#[derive(Clone, Copy, Debug)]
pub struct GrowthModel<'a> {
    pub problem: &'a crate::problem::GrowthProblem,
    pub fitted: &'a [SensParam],
    pub times: &'a [f64],
    /// Whether to read the refraction too (each output time's series row: an elastic
    /// solve there, which moves the integrator's later steps by round-off), else NaN.
    pub refraction: bool,
}

impl GrowthModel<'_> {
    /// Run the growth with the sensitivities to the fitted parameters and read L and dL/dp
    /// at the observation times, calling `step(t)` after every step of the run: an error
    /// from it stops the run there (a caller's Ctrl-C).
    pub fn evaluate(&self, step: &mut growth::ProgressFn<'_>) -> Result<ModelValues, FitError> {
        let t_end = self.problem.growth().t_end;
        let times = distinct_times(self.times, t_end);
        let mut settings = self.problem.settings().clone();
        settings.output_times = times
            .iter()
            .copied()
            .filter(|&t| t > 0.0 && t < t_end)
            .collect();
        settings.history_points = 0;
        settings.sensitivities = self.fitted.to_vec();
        // Per distinct time: L, its sensitivities and the refraction (NaN until recorded).
        let k = self.fitted.len();
        let mut at: Vec<(f64, Vec<f64>, f64)> =
            vec![(f64::NAN, vec![f64::NAN; k], f64::NAN); times.len()];
        let slot = |t: f64| times.iter().position(|&x| (x - t).abs() <= 1e-9 * t_end);
        let sens = std::cell::RefCell::new(&mut at);
        let mut take = |rows: &[SensitivityRow]| -> Result<(), growth::ObserverError> {
            if let Some(first) = rows.first() {
                if let Some(i) = slot(first.t) {
                    let mut at = sens.borrow_mut();
                    at[i].0 = first.axial_length;
                    for (j, r) in rows.iter().enumerate().take(k) {
                        at[i].1[j] = r.d_axial_length;
                    }
                }
            }
            Ok(())
        };
        // The series of every output time gives the refraction, and L to a run without
        // sensitivities (one of finite differences).
        let series = self.refraction || k == 0;
        let mut output = |sys: &mut growth::system::GrowthSystem,
                          t: f64,
                          p: &[f64]|
         -> Result<(), growth::ObserverError> {
            if let Some(i) = slot(t).filter(|_| series) {
                let row = sys.series(t, p)?;
                let mut at = sens.borrow_mut();
                if k == 0 {
                    at[i].0 = row.axial_length;
                }
                at[i].2 = row.refraction_d;
            }
            Ok(())
        };
        let start = std::time::Instant::now();
        // The observation times and the fitted parameters are what is recorded, not the
        // problem: the problem checked stays checked.
        let problem = self.problem.recording(settings);
        growth::run_with(&problem, &mut take, &mut output, step)?;
        let seconds = start.elapsed().as_secs_f64();
        let n = self.times.len();
        let mut axial_length = Vec::with_capacity(n);
        let mut refraction_d = Vec::with_capacity(n);
        let mut jacobian = DMatrix::zeros(n, k);
        for (i, &t) in self.times.iter().enumerate() {
            // The distinct time this observation was merged into (none only for a time the
            // run did not cover, which reads as not recorded).
            let Some(d) = times.iter().position(|&x| (x - t).abs() <= 1e-9 * t_end) else {
                return Err(FitError::NotRecorded { t });
            };
            let (l, dl, refraction) = &at[d];
            if !l.is_finite() || dl.iter().any(|x| !x.is_finite()) {
                return Err(FitError::NotRecorded { t: times[d] });
            }
            axial_length.push(*l);
            refraction_d.push(*refraction);
            for j in 0..k {
                jacobian[(i, j)] = dl[j];
            }
        }
        Ok(ModelValues {
            axial_length,
            refraction_d,
            jacobian,
            seconds,
        })
    }
}

/// The weighted residuals (L − y)/σ and Jacobian (∂L/∂p)/σ of `m` against the observed
/// axial lengths `y` and their σ (1 where None).
pub fn weighted(m: &ModelValues, y: &[f64], sigma: &[Option<f64>]) -> (DVector<f64>, DMatrix<f64>) {
    let n = y.len();
    let mut r = DVector::zeros(n);
    let mut j = m.jacobian.clone();
    for i in 0..n {
        let w = 1.0 / sigma[i].unwrap_or(1.0);
        r[i] = (m.axial_length[i] - y[i]) * w;
        for c in 0..j.ncols() {
            j[(i, c)] *= w;
        }
    }
    (r, j)
}

/// Why the data cannot identify the parameters, as one line naming them, or None.
///
/// Each column of J is scaled by the parameter's magnitude (|p|, or 1 at p = 0): a column
/// below [`IDENTIFIABILITY_THRESHOLD`] of the largest is a parameter the data do not depend
/// on. Otherwise the information matrix JᵀJ is scaled to a unit diagonal (its correlation
/// form, independent of the parameters' units) and its smallest eigenvalue compared with
/// the threshold; the parameters with the largest components of that eigenvector (at least
/// half the largest) are named.
pub fn identifiability(j: &DMatrix<f64>, names: &[&str], values: &[f64]) -> Option<String> {
    let k = names.len();
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
        .map(|c| names[c])
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
        .map(|&c| names[c])
        .collect();
    let direction: Vec<String> = order
        .iter()
        .filter(|&&c| v[c].abs() >= 0.05)
        .map(|&c| format!("{:+.3} {}", v[c], names[c]))
        .collect();
    Some(format!(
        "the data cannot identify {}: the information matrix JᵀWJ is near-singular (smallest eigenvalue of its correlation form {:.2e} ≤ {IDENTIFIABILITY_THRESHOLD:e}, along {}): the data do not determine that combination of them; fix {} in the scene, or add observations that separate them",
        named.join(" from ").replace(" from ", if named.len() > 2 { ", " } else { " from " }),
        lambda.max(0.0),
        direction.join(" "),
        if named.len() == 1 { named[0].to_string() } else { format!("one of {}", named.join(", ")) },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::settings::SolverSettings;
    use crate::growth::{GrowthSettings, Integrator};
    use crate::problem::{ElasticProblem, GrowthProblem};

    /// One growth run gives L and ∂L/∂η0 at each observation, in the data's order (a time
    /// given twice reads the same value), and a time the run does not reach is refused.
    #[test]
    fn the_model_is_read_at_each_observation_time() {
        let solver = SolverSettings {
            nodes: 41,
            ..SolverSettings::default()
        };
        let settings = GrowthSettings {
            integrator: Integrator::Ida,
            ..GrowthSettings::default()
        };
        let elastic = ElasticProblem::builder().solver(solver).build().unwrap();
        let problem = GrowthProblem::builder(elastic)
            .settings(settings)
            .build()
            .unwrap();
        let growth = problem.growth();
        let times = [0.5 * growth.t_end, 0.25 * growth.t_end, 0.5 * growth.t_end];
        let model = GrowthModel {
            problem: &problem,
            fitted: &[SensParam::Eta0],
            times: &times,
            refraction: false,
        };
        let m = model.evaluate(&mut |_| Ok(())).unwrap();
        assert_eq!(m.axial_length.len(), 3);
        assert_eq!(m.jacobian.shape(), (3, 1));
        assert_eq!(m.axial_length[0], m.axial_length[2]);
        // The eye grows: longer at t_end/2 than at t_end/4, and faster with a larger η0.
        assert!(
            m.axial_length[0] > m.axial_length[1],
            "{:?}",
            m.axial_length
        );
        assert!(
            m.jacobian.iter().all(|&d| d.is_finite() && d > 0.0),
            "{}",
            m.jacobian
        );
        let beyond = [2.0 * growth.t_end];
        let err = GrowthModel {
            times: &beyond,
            ..model
        }
        .evaluate(&mut |_| Ok(()))
        .unwrap_err();
        assert!(matches!(err, FitError::NotRecorded { .. }), "{err}");
        assert!(err
            .to_string()
            .starts_with("the growth run recorded no finite axial length"));
        assert_eq!(distinct_times(&[0.5, 0.25, 0.5 + 1e-12], 1.0), [0.25, 0.5]);
    }
}
