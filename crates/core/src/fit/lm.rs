//! Levenberg–Marquardt with bounds, on our residuals and our Jacobian.
//!
//! Hand-written on nalgebra: the `levenberg-marquardt` crate (a MINPACK port on nalgebra)
//! has no bounds, and a fit must keep every trial inside each key's validity range (a
//! growth run at δ ≤ 0 has no meaning). A dozen lines of linear algebra are the whole of it.
//!
//! Each iteration takes the δ that minimises ‖Jδ + r‖² + λ δᵀDδ, D = diag(JᵀJ) (Marquardt's
//! scaling, its largest value so far, as MINPACK keeps it: the step is invariant to the
//! parameters' units): the solution of (JᵀJ + λ D) δ = −Jᵀr, found by a QR factorisation of
//! the stacked matrix [J; √(λD)] ([`damped_step`]), never by forming JᵀJ, whose condition
//! number is that of J squared (η0 and Γ correlate at −0.99 on the const scene). The
//! Gauss–Newton quantities (the full step, the χ² it would gain, the covariance) come from
//! the QR factors of J the same way ([`GaussNewton`]). The trial p + δ is **projected** onto the range: onto a closed bound exactly
//! (≥ 0), and towards an open bound (> 0) at most 90 % of the remaining distance, so that
//! it is never reached. A trial the problem cannot evaluate (a fit's scene refuses it at a
//! cross-key limit, or its growth run fails) counts as a rejected step. A step is accepted when it lowers the cost; λ follows
//! Nielsen's rule: × max(1/3, 1 − (2ρ − 1)³) after an accepted step (ρ the actual over the
//! predicted reduction of the projected step), × ν (ν doubling) after a rejected one.
//! (Nielsen's smallest factor is 1/3; here 1/9, and λ starts at 1e-5: see [`LAMBDA0`].)
//!
//! The iteration stops ([`Convergence`]) when, after an accepted step,
//! - every parameter moved less than `xtol` relative to its magnitude (`step`), or
//! - the cost fell by less than `ftol` relative (`cost`), or
//! - the largest scaled gradient |Jⱼᵀr| / (‖Jⱼ‖ ‖r‖) (the cosine between the residuals and a
//!   column, MINPACK's gtol) is below `gtol`, free parameters only (`gradient`);
//! - the full Gauss–Newton step would lower χ² by less than `setol`² s² (0.01 s²:
//!   `standard-error`): the estimate is within 0.1 standard errors of the optimum along every
//!   direction (the Mahalanobis norm of the step, not the marginal standard errors, which
//!   would stop a step across a narrow valley of correlated parameters far too early).
//!   This is the test that ends a fit in practice: the cost is a growth run's, exact only to
//!   the run's tolerance (solver.rtol), and on the const scene at rtol 1e-6 χ² varies by
//!   ~1e-3 between neighbouring runs (0.03 standard errors in the Mahalanobis norm), so the
//!   tests on the step and the cost alone chase that noise for tens of iterations;
//!
//! or when no step lowers the cost any more (λ beyond 1e16: `stalled`, the cost is at the
//! accuracy of the growth run), or after `max_iterations` (`iterations`, reported, not an
//! error: the report says so). When the steps that drove λ there include one the scene
//! refused or whose growth run failed (`refused`), the cost was not found lower nowhere
//! near the estimate: it could not be evaluated there, and the fit has not converged.

use nalgebra::{DMatrix, DVector};

use super::Bounds;

/// The first damping λ, relative to Marquardt's diagonal: small, because the growth
/// parameters are strongly correlated (η0 and Γ near −0.99 on the const scene), and a
/// damping near the smallest eigenvalue of the correlation form makes the steps crawl along
/// the valley.
const LAMBDA0: f64 = 1e-5;

/// The stopping tolerances of [`minimise`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    pub max_iterations: usize,
    /// Relative step of every parameter.
    pub xtol: f64,
    /// Relative reduction of the cost.
    pub ftol: f64,
    /// Scaled gradient (cosine between the residuals and each column of J).
    pub gtol: f64,
    /// The Gauss–Newton step in standard errors (its Mahalanobis norm): below it, the
    /// estimate is that close to the optimum along every direction.
    pub setol: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_iterations: 50,
            xtol: 1e-6,
            ftol: 1e-10,
            gtol: 1e-8,
            setol: 0.1,
        }
    }
}

/// Why the iteration stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Convergence {
    Step,
    Cost,
    Gradient,
    StandardError,
    Stalled,
    /// λ beyond 1e16 after rejected steps of which at least one could not be evaluated.
    Refused,
    Iterations,
}

impl Convergence {
    /// Did the fit converge (every reason but the iteration limit and refused steps)?
    pub fn converged(self) -> bool {
        !matches!(self, Convergence::Iterations | Convergence::Refused)
    }

    /// The reason in words.
    pub fn describe(self, o: &FitOptions) -> String {
        match self {
            Convergence::Step => format!("converged: every parameter moved less than {:e} of its value", o.xtol),
            Convergence::Cost => format!("converged: the cost fell by less than {:e} relative", o.ftol),
            Convergence::Gradient => format!("converged: the scaled gradient is below {:e}", o.gtol),
            Convergence::StandardError => format!(
                "converged: the Gauss–Newton step is below {} standard errors (it would gain less than {:e} in χ²/s²)",
                o.setol,
                (o.setol * o.setol * 1e12).round() / 1e12
            ),
            Convergence::Stalled => "converged: no step lowers the cost further (it is at the accuracy of the growth runs)".into(),
            Convergence::Refused => "not converged: the last steps were rejected, some because the scene refused them or their growth run failed, until the damping passed 1e16 (the estimates are the last accepted)".into(),
            Convergence::Iterations => format!("not converged: stopped after {} iterations (the estimates are the last accepted)", o.max_iterations),
        }
    }
}

/// One iteration: the step tried and what came of it.
#[derive(Clone, Debug, PartialEq)]
pub struct IterationRecord {
    pub iteration: usize,
    /// The parameters after it (the accepted trial, or unchanged).
    pub values: Vec<f64>,
    /// Σ r² after it.
    pub chi2: f64,
    /// λ used for the step.
    pub lambda: f64,
    pub accepted: bool,
    /// Why a trial was rejected: a higher cost, or the scene's or the run's refusal.
    pub rejected: Option<String>,
}

/// What [`minimise`] found.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub values: Vec<f64>,
    pub residuals: DVector<f64>,
    pub jacobian: DMatrix<f64>,
    /// The model's axial lengths at the estimate.
    pub model: Vec<f64>,
    pub initial_chi2: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub convergence: Convergence,
    /// Why the last step that could not be evaluated was refused, since the last accepted.
    pub last_refusal: Option<String>,
    pub history: Vec<IterationRecord>,
}

/// (weighted residuals, weighted Jacobian, model values) at a parameter vector.
pub type Evaluation = (DVector<f64>, DMatrix<f64>, Vec<f64>);

/// `key = value, ...` for messages.
pub fn show(names: &[&str], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} = {}", crate::text::decimals6(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Is `x` on a closed bound of `b`?
pub fn at_closed_bound(b: &Bounds, x: f64) -> bool {
    (!b.lower_open && b.lower == Some(x)) || (!b.upper_open && b.upper == Some(x))
}

/// Which parameters their range holds at `p`: on a closed bound, or with the full
/// Gauss–Newton step from `p` (residuals `r`, Jacobian `j`) leaving the range: the data
/// pull them beyond it (towards an open bound the steps only approach it), so the estimate
/// is the bound's, not the data's optimum, and its standard error means little.
pub fn held_by_bounds(
    bounds: &[Bounds],
    p: &[f64],
    r: &DVector<f64>,
    j: &DMatrix<f64>,
) -> Vec<bool> {
    let step = GaussNewton::of(j).map(|gn| gn.step(r));
    (0..bounds.len())
        .map(|c| {
            let b = &bounds[c];
            at_closed_bound(b, p[c])
                || step
                    .as_ref()
                    .is_some_and(|s| s[c].is_finite() && b.excludes(p[c] + s[c]))
        })
        .collect()
}

/// The QR factors J = QR of a Jacobian of full column rank: the Gauss–Newton step, the χ²
/// it gains and the covariance (JᵀJ)⁻¹ = R⁻¹R⁻ᵀ, each to the accuracy of J's own condition
/// number, where the normal equations would square it.
pub struct GaussNewton {
    q: DMatrix<f64>,
    r: DMatrix<f64>,
}

impl GaussNewton {
    /// The factors of `j` (n × k, n ≥ k), or None when a diagonal entry of R is zero or not
    /// finite relative to the largest (J's columns dependent to round-off).
    pub fn of(j: &DMatrix<f64>) -> Option<GaussNewton> {
        let (n, k) = j.shape();
        if n < k || k == 0 || j.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let qr = j.clone().qr();
        let (q, r) = (qr.q(), qr.r());
        let top = (0..k).map(|c| r[(c, c)].abs()).fold(0.0_f64, f64::max);
        let full_rank = (0..k).all(|c| r[(c, c)].abs() > f64::EPSILON * top);
        (top > 0.0 && full_rank).then_some(GaussNewton { q, r })
    }

    /// The full Gauss–Newton step −(JᵀJ)⁻¹Jᵀr = −R⁻¹Qᵀr.
    pub fn step(&self, residuals: &DVector<f64>) -> DVector<f64> {
        let qtr = self.q.transpose() * residuals;
        self.r
            .solve_upper_triangular(&(-qtr))
            .unwrap_or_else(|| DVector::from_element(self.r.ncols(), f64::NAN))
    }

    /// The χ² the full step would gain, gᵀ(JᵀJ)⁻¹g with g = Jᵀr: ‖Qᵀr‖².
    pub fn gain(&self, residuals: &DVector<f64>) -> f64 {
        (self.q.transpose() * residuals).norm_squared()
    }

    /// (JᵀJ)⁻¹ = R⁻¹R⁻ᵀ.
    pub fn inverse_information(&self) -> Option<DMatrix<f64>> {
        let k = self.r.ncols();
        let r_inv = self.r.solve_upper_triangular(&DMatrix::identity(k, k))?;
        Some(&r_inv * r_inv.transpose())
    }
}

/// The Levenberg–Marquardt step: argmin ‖Jδ + r‖² + λ δᵀ diag(d) δ, the least-squares
/// solution of [J; √(λd)] δ = [−r; 0] by QR (None if that matrix is rank-deficient).
pub fn damped_step(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    lambda: f64,
    d: &DVector<f64>,
) -> Option<DVector<f64>> {
    let (n, k) = j.shape();
    let stacked = DMatrix::from_fn(n + k, k, |row, c| {
        if row < n {
            j[(row, c)]
        } else if row - n == c {
            (lambda * d[c]).sqrt()
        } else {
            0.0
        }
    });
    let rhs = DVector::from_fn(n + k, |row, _| if row < n { r[row] } else { 0.0 });
    let gn = GaussNewton::of(&stacked)?;
    let step = gn.step(&rhs);
    step.iter().all(|x| x.is_finite()).then_some(step)
}

/// `from + step` kept in `b`: onto a closed bound, 90 % of the way towards an open one.
fn project(b: &Bounds, from: f64, step: f64) -> f64 {
    let mut x = from + step;
    if let Some(lo) = b.lower {
        if x < lo || (b.lower_open && x <= lo) {
            x = if b.lower_open {
                from - 0.9 * (from - lo)
            } else {
                lo
            };
        }
    }
    if let Some(hi) = b.upper {
        if x > hi || (b.upper_open && x >= hi) {
            x = if b.upper_open {
                from + 0.9 * (hi - from)
            } else {
                hi
            };
        }
    }
    x
}

/// A least-squares problem for [`minimise`]: its parameters (names for messages, ranges
/// the steps are kept in), the weighted residuals and Jacobian at a parameter vector, and
/// the s² that scales its covariance.
pub trait Problem {
    /// Why an evaluation failed (in words: a rejected step records it).
    type Error: std::fmt::Display;
    /// The parameters' names, in order (in messages).
    fn names(&self) -> Vec<&str>;
    /// The parameters' ranges, in order.
    fn bounds(&self) -> Vec<Bounds>;
    /// r, J and the model's values at `p`.
    fn evaluate(&mut self, p: &[f64]) -> Result<Evaluation, Self::Error>;
    /// s² at χ² (the unit of the standard-error test).
    fn variance(&self, chi2: f64) -> f64;
    /// Whether the evaluation that failed with `e` ends the fit instead of rejecting its
    /// step: a caller's interruption (Ctrl-C in a growth run's step), which every further
    /// trial would meet again, or not at all once it was heard. None by default.
    fn stops(&self, _e: &Self::Error) -> bool {
        false
    }
}

/// Why [`minimise`] gave no outcome.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LmError<E: std::fmt::Display> {
    /// The first evaluation failed.
    #[error("{0}")]
    Evaluation(E),
    /// The data cannot identify the parameters at the start (the user's to change).
    #[error("{0}")]
    Unidentifiable(String),
    /// The damped least-squares problem has no unique solution (a failure).
    #[error("{0}")]
    RankDeficient(String),
}

/// The test that ends the fit before a step: the scaled gradient is below `gtol`, or the
/// Gauss–Newton step would gain less than `setol` standard errors.
/// `s2` is the problem's s² at the current χ².
fn converged_before_step(
    bounds: &[Bounds],
    p: &[f64],
    r: &DVector<f64>,
    j: &DMatrix<f64>,
    g: &DVector<f64>,
    s2: f64,
    o: &FitOptions,
) -> Option<Convergence> {
    let k = bounds.len();
    // Scaled gradient on the free parameters (a parameter held at a closed bound with
    // the gradient pushing it out of the range does not count).
    let rnorm = r.norm();
    let held = |c: usize, p: &[f64], g: &DVector<f64>| {
        let b = &bounds[c];
        let held_low = !b.lower_open && b.lower == Some(p[c]) && g[c] > 0.0;
        let held_high = !b.upper_open && b.upper == Some(p[c]) && g[c] < 0.0;
        held_low || held_high
    };
    let gradient = (0..k)
        .filter(|&c| !held(c, p, g))
        .map(|c| {
            let cn = j.column(c).norm();
            if cn > 0.0 && rnorm > 0.0 {
                g[c].abs() / (cn * rnorm)
            } else {
                0.0
            }
        })
        .fold(0.0_f64, f64::max);
    if gradient <= o.gtol {
        return Some(Convergence::Gradient);
    }
    // The χ² the full Gauss–Newton step would gain, gᵀ(JᵀJ)⁻¹g over the free parameters,
    // in units of s²: the squared distance to the optimum in standard errors along the
    // worst direction (the Mahalanobis norm; the marginal standard errors would miss a
    // step across a narrow valley of correlated parameters).
    let free: Vec<usize> = (0..k).filter(|&c| !held(c, p, g)).collect();
    if !free.is_empty() {
        let j_free = DMatrix::from_fn(j.nrows(), free.len(), |row, c| j[(row, free[c])]);
        if let Some(gn) = GaussNewton::of(&j_free) {
            if gn.gain(r) <= o.setol * o.setol * s2 {
                return Some(Convergence::StandardError);
            }
        }
    }
    None
}

/// Minimise ½‖r(p)‖² from `p0` within the parameters' ranges, calling `each` after every
/// iteration. An evaluation that fails at the start is the error; later ones reject the
/// step. The identifiability at the start is checked before the first step.
pub fn minimise<P: Problem>(
    problem: &mut P,
    p0: &[f64],
    o: &FitOptions,
    each: &mut dyn FnMut(&IterationRecord),
) -> Result<Outcome, LmError<P::Error>> {
    let bounds = problem.bounds();
    let k = bounds.len();
    let (mut r, mut j, mut model) = problem.evaluate(p0).map_err(LmError::Evaluation)?;
    let mut evaluations = 1;
    {
        let names = problem.names();
        if let Some(why) = super::identifiability(&j, &names, p0) {
            return Err(LmError::Unidentifiable(format!(
                "at the start ({}): {why}",
                show(&names, p0)
            )));
        }
    }
    let initial_chi2 = r.norm_squared();
    let mut p = p0.to_vec();
    let mut chi2 = initial_chi2;
    let mut d = DVector::<f64>::zeros(k);
    let mut lambda = LAMBDA0;
    let mut nu = 2.0;
    let mut history = Vec::new();
    let mut convergence = Convergence::Iterations;
    let mut last_refusal: Option<String> = None;
    for iteration in 1..=o.max_iterations {
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        for c in 0..k {
            d[c] = d[c].max(jtj[(c, c)]).max(f64::MIN_POSITIVE);
        }
        if let Some(c) = converged_before_step(&bounds, &p, &r, &j, &g, problem.variance(chi2), o) {
            convergence = c;
            break;
        }
        let Some(step) = damped_step(&j, &r, lambda, &d) else {
            return Err(LmError::RankDeficient(format!(
                "Levenberg–Marquardt: the damped least-squares problem is rank-deficient at {}",
                show(&problem.names(), &p)
            )));
        };
        let trial: Vec<f64> = (0..k).map(|c| project(&bounds[c], p[c], step[c])).collect();
        let delta = DVector::from_iterator(k, (0..k).map(|c| trial[c] - p[c]));
        // The reduction of ½‖r‖² the linear model predicts for the projected step.
        let predicted = -(g.dot(&delta) + 0.5 * delta.dot(&(&jtj * &delta)));
        let tried = problem.evaluate(&trial);
        evaluations += 1;
        let (accepted, rejected) = match tried {
            Ok((r2, j2, m2)) => {
                let chi2_new = r2.norm_squared();
                if chi2_new < chi2 {
                    let rho = if predicted > 0.0 {
                        0.5 * (chi2 - chi2_new) / predicted
                    } else {
                        0.0
                    };
                    let small_cost = (chi2 - chi2_new) <= o.ftol * chi2;
                    let small_step =
                        (0..k).all(|c| delta[c].abs() <= o.xtol * (p[c].abs() + o.xtol));
                    p = trial;
                    (r, j, model) = (r2, j2, m2);
                    last_refusal = None;
                    chi2 = chi2_new;
                    lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 9.0);
                    nu = 2.0;
                    if small_step {
                        convergence = Convergence::Step;
                    } else if small_cost {
                        convergence = Convergence::Cost;
                    }
                    (true, None)
                } else {
                    (false, Some(format!("χ² {chi2_new:.6e} ≥ {chi2:.6e}")))
                }
            }
            Err(e) if problem.stops(&e) => return Err(LmError::Evaluation(e)),
            Err(e) => {
                last_refusal = Some(e.to_string());
                (false, last_refusal.clone())
            }
        };
        if !accepted {
            lambda *= nu;
            nu *= 2.0;
        }
        let record = IterationRecord {
            iteration,
            values: p.clone(),
            chi2,
            lambda,
            accepted,
            rejected,
        };
        each(&record);
        history.push(record);
        if accepted && convergence != Convergence::Iterations {
            break;
        }
        if lambda > 1e16 {
            convergence = if last_refusal.is_some() {
                Convergence::Refused
            } else {
                Convergence::Stalled
            };
            break;
        }
    }
    let iterations = history.len();
    Ok(Outcome {
        values: p,
        residuals: r,
        jacobian: j,
        model,
        initial_chi2,
        iterations,
        evaluations,
        convergence,
        last_refusal,
        history,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A problem given by a closure, its parameters named p0, p1, ...
    struct Closure<F> {
        bounds: Vec<Bounds>,
        names: Vec<String>,
        f: F,
    }

    fn problem<F>(bounds: Vec<Bounds>, f: F) -> Closure<F>
    where
        F: FnMut(&[f64]) -> Result<Evaluation, String>,
    {
        let names = (0..bounds.len()).map(|c| format!("p{c}")).collect();
        Closure { bounds, names, f }
    }

    impl<F: FnMut(&[f64]) -> Result<Evaluation, String>> Problem for Closure<F> {
        type Error = String;
        fn names(&self) -> Vec<&str> {
            self.names.iter().map(String::as_str).collect()
        }
        fn bounds(&self) -> Vec<Bounds> {
            self.bounds.clone()
        }
        fn evaluate(&mut self, p: &[f64]) -> Result<Evaluation, String> {
            (self.f)(p)
        }
        fn variance(&self, _chi2: f64) -> f64 {
            1.0
        }
    }

    #[test]
    fn projection_stops_short_of_an_open_bound_and_on_a_closed_one() {
        let open = Bounds {
            lower: Some(0.0),
            lower_open: true,
            ..Bounds::NONE
        };
        let closed = Bounds {
            lower: Some(0.0),
            ..Bounds::NONE
        };
        assert!((project(&open, 1.0, -5.0) - 0.1).abs() < 1e-15);
        assert_eq!(project(&closed, 1.0, -5.0), 0.0);
        assert_eq!(project(&open, 1.0, 0.5), 1.5);
        assert_eq!(project(&Bounds::NONE, 1.0, -5.0), -4.0);
    }

    /// An evaluation the problem says stops the fit (a caller's interruption) ends it at
    /// once, at any iteration: taken as a rejected step, the fit would go on damping, trial
    /// after trial, for as long as the damping took to pass its limit.
    #[test]
    fn an_evaluation_that_stops_ends_the_fit_at_once() {
        struct Interrupted {
            evaluations: usize,
        }
        impl Problem for Interrupted {
            type Error = String;
            fn names(&self) -> Vec<&str> {
                vec!["p0"]
            }
            fn bounds(&self) -> Vec<Bounds> {
                vec![Bounds::NONE]
            }
            fn evaluate(&mut self, p: &[f64]) -> Result<Evaluation, String> {
                self.evaluations += 1;
                if self.evaluations == 3 {
                    return Err("interrupted".into());
                }
                let r = DVector::from_vec(vec![(p[0] - 3.0).powi(3), p[0] - 3.5]);
                let j = DMatrix::from_vec(2, 1, vec![3.0 * (p[0] - 3.0).powi(2), 1.0]);
                Ok((r, j, vec![p[0]; 2]))
            }
            fn variance(&self, _chi2: f64) -> f64 {
                1.0
            }
            fn stops(&self, e: &String) -> bool {
                e == "interrupted"
            }
        }
        let mut problem = Interrupted { evaluations: 0 };
        let out = minimise(&mut problem, &[0.0], &FitOptions::default(), &mut |_| {});
        assert!(matches!(out, Err(LmError::Evaluation(ref e)) if e == "interrupted"));
        assert_eq!(problem.evaluations, 3);
    }

    /// Steps that cannot be evaluated (the scene refuses them, their run fails) are
    /// rejected; when they drive the damping to its limit the fit has not converged, and
    /// the last refusal is kept to say why.
    #[test]
    fn a_fit_stopped_by_refused_steps_has_not_converged() {
        let p0 = [1.0];
        let mut refusing = problem(vec![Bounds::NONE], |p: &[f64]| {
            if p != p0 {
                return Err("the scene refuses it".to_string());
            }
            let r = DVector::from_vec(vec![p[0] - 3.0, p[0] - 3.5]);
            Ok((r, DMatrix::from_element(2, 1, 1.0), vec![p[0]; 2]))
        });
        let out = minimise(&mut refusing, &p0, &FitOptions::default(), &mut |_| {}).unwrap();
        assert_eq!(out.convergence, Convergence::Refused);
        assert!(!out.convergence.converged());
        assert!(out
            .convergence
            .describe(&FitOptions::default())
            .starts_with("not converged"));
        assert_eq!(out.last_refusal.as_deref(), Some("the scene refuses it"));
        assert_eq!(out.values, p0);
    }

    /// The range holds a parameter on a closed bound, or one the Gauss–Newton step would
    /// take beyond an open bound; not one at an interior optimum.
    #[test]
    fn held_by_bounds_tells_the_range_from_the_data() {
        let open_above = Bounds {
            upper: Some(2.0),
            upper_open: true,
            ..Bounds::NONE
        };
        let j = DMatrix::from_element(2, 1, 1.0);
        // The data want p = 3.25, beyond the open bound 2: held at p = 1.99.
        let r = DVector::from_vec(vec![1.99 - 3.0, 1.99 - 3.5]);
        assert_eq!(held_by_bounds(&[open_above], &[1.99], &r, &j), [true]);
        // The data want p = 1.5, inside: not held.
        let r = DVector::from_vec(vec![1.5 - 1.25, 1.5 - 1.75]);
        assert_eq!(held_by_bounds(&[open_above], &[1.5], &r, &j), [false]);
        let closed = Bounds {
            lower: Some(0.0),
            ..Bounds::NONE
        };
        assert_eq!(held_by_bounds(&[closed], &[0.0], &r, &j), [true]);
    }

    /// y = a·exp(b·x) on exact data: LM finds (a, b) from far away.
    #[test]
    fn an_exponential_is_fitted_to_round_off() {
        let xs: Vec<f64> = (0..8).map(|i| i as f64 / 4.0).collect();
        let (a0, b0) = (2.0, -1.3);
        let eval = |p: &[f64]| -> Result<Evaluation, String> {
            let model: Vec<f64> = xs.iter().map(|x| p[0] * (p[1] * x).exp()).collect();
            let r = DVector::from_iterator(
                xs.len(),
                xs.iter().zip(&model).map(|(x, m)| m - a0 * (b0 * x).exp()),
            );
            let j = DMatrix::from_fn(xs.len(), 2, |i, c| {
                let e = (p[1] * xs[i]).exp();
                if c == 0 {
                    e
                } else {
                    p[0] * xs[i] * e
                }
            });
            Ok((r, j, model))
        };
        let bounds = vec![
            Bounds {
                lower: Some(0.0),
                lower_open: true,
                ..Bounds::NONE
            },
            Bounds::NONE,
        ];
        let out = minimise(
            &mut problem(bounds, eval),
            &[0.5, 0.5],
            &FitOptions {
                setol: 0.0,
                ..FitOptions::default()
            },
            &mut |_| {},
        )
        .unwrap();
        assert!(
            (out.values[0] - a0).abs() < 1e-8 && (out.values[1] - b0).abs() < 1e-8,
            "{:?}",
            out.values
        );
        assert!(
            out.convergence.converged() && out.iterations < 30,
            "{:?} {}",
            out.convergence,
            out.iterations
        );
    }
}
