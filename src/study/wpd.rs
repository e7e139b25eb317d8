//! Work-precision diagrams (issue: measure the trade of speed for accuracy): error against
//! CPU seconds, each error taken against a reference computed at much tighter settings.
//! - Elastic: trapezoid and Hermite–Simpson over N, and Richardson-extrapolated
//!   Hermite–Simpson (N and 2N − 1 combined: order 6), errors at common material points.
//! - Growth: explicit Euler over its step count and CVODE over rtol, errors in the axial
//!   length and the largest field error at t_end (same mesh as the reference).

use super::{max_diff, points, run, sample, worst, StudyError};
use crate::growth::{GrowthParams, GrowthSettings, Integrator};
use crate::model::params::{Params, Scheme, SolverSettings};

/// One method's points: (knob value, error, seconds), coarse to fine.
#[derive(Clone, Debug)]
pub struct Curve {
    pub method: String,
    pub knob: &'static str,
    pub points: Vec<WorkPoint>,
}

#[derive(Clone, Copy, Debug)]
pub struct WorkPoint {
    pub value: f64,
    /// Largest error over the five fields (and material points).
    pub error: f64,
    /// Error of the axial length at t_end (growth only; NaN otherwise).
    pub axial_error: f64,
    pub seconds: f64,
}

/// Repeat short runs so that timings are not a single noisy sample: the least of up to
/// `repeats` runs, stopping once `budget` seconds are spent.
fn best_of<T>(mut f: impl FnMut() -> Result<(T, f64), StudyError>, repeats: usize, budget: f64) -> Result<(T, f64), StudyError> {
    let (mut best_val, mut best) = f()?;
    let mut spent = best;
    for _ in 1..repeats {
        if spent > budget {
            break;
        }
        let (v, t) = f()?;
        spent += t;
        if t < best {
            best = t;
            best_val = v;
        }
    }
    Ok((best_val, best))
}

/// The elastic diagram: both schemes over `nodes`, and Richardson-extrapolated
/// Hermite–Simpson, against Hermite–Simpson at `reference_nodes` (Newton tol 1e-12).
pub fn elastic(params: &Params, solver: &SolverSettings, nodes: &[usize], reference_nodes: usize) -> Result<Vec<Curve>, StudyError> {
    let tight = SolverSettings { nodes: reference_nodes, scheme: Scheme::HermiteSimpson, newton_tol: 1e-12, ..*solver };
    let reference = run(params, &tight, None, "reference")?;
    let pts = points(solver.epsilon, params.length(), 201);
    let ref_vals = sample(&reference.solution, &pts, "reference")?;
    let mut curves = vec![];
    let mut hs_runs = vec![];
    for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
        let mut c = Curve { method: format!("{scheme:?}").to_lowercase(), knob: "nodes", points: vec![] };
        for &n in nodes {
            let s = SolverSettings { nodes: n, scheme, ..*solver };
            let what = format!("{scheme:?} N = {n}");
            let (vals, seconds) = best_of(
                || {
                    let r = run(params, &s, None, &what)?;
                    Ok((sample(&r.solution, &pts, &what)?, r.seconds))
                },
                5,
                1.0,
            )?;
            c.points.push(WorkPoint { value: n as f64, error: worst(&max_diff(&vals, &ref_vals)), axial_error: f64::NAN, seconds });
            if scheme == Scheme::HermiteSimpson {
                hs_runs.push((n, vals, seconds));
            }
        }
        curves.push(c);
    }
    // Richardson: Hermite–Simpson at N and at 2N − 1 (the next rung when the ladder doubles).
    let mut rich = Curve { method: "hermite-simpson + Richardson".into(), knob: "nodes", points: vec![] };
    for w in hs_runs.windows(2) {
        let ((n1, c, t1), (n2, f, t2)) = (&w[0], &w[1]);
        if *n2 != 2 * n1 - 1 {
            continue;
        }
        let extrapolated: Vec<[f64; 5]> = c.iter().zip(f).map(|(c, f)| std::array::from_fn(|j| f[j] + (f[j] - c[j]) / 15.0)).collect();
        rich.points.push(WorkPoint { value: *n2 as f64, error: worst(&max_diff(&extrapolated, &ref_vals)), axial_error: f64::NAN, seconds: t1 + t2 });
    }
    curves.push(rich);
    Ok(curves)
}

/// The growth diagram: Euler over `steps` and CVODE over `rtols`, against CVODE at
/// `reference_rtol`, all on the scene's mesh.
pub fn growth(
    params: &Params,
    solver: &SolverSettings,
    g: &GrowthParams,
    settings: &GrowthSettings,
    steps: &[usize],
    rtols: &[f64],
    reference_rtol: f64,
) -> Result<Vec<Curve>, StudyError> {
    let tight = GrowthSettings { integrator: Integrator::Cvode, rtol: reference_rtol, atol: reference_rtol * 1e-2, ..settings.clone() };
    let reference = run(params, solver, Some((g, &tight)), "reference")?;
    let pts: Vec<f64> = reference.solution.mesh.nodes.clone();
    let ref_vals = sample(&reference.solution, &pts, "reference")?;
    let ref_axial = reference.axial_length.unwrap_or(f64::NAN);
    let measure = |s: &GrowthSettings, value: f64, what: &str| -> Result<WorkPoint, StudyError> {
        let r = run(params, solver, Some((g, s)), what)?;
        let vals = sample(&r.solution, &pts, what)?;
        Ok(WorkPoint {
            value,
            error: worst(&max_diff(&vals, &ref_vals)),
            axial_error: (r.axial_length.unwrap_or(f64::NAN) - ref_axial).abs(),
            seconds: r.seconds,
        })
    };
    let mut euler = Curve { method: "euler".into(), knob: "steps", points: vec![] };
    for &n in steps {
        let s = GrowthSettings { integrator: Integrator::Euler, steps: n, ..settings.clone() };
        euler.points.push(measure(&s, n as f64, &format!("Euler {n} steps"))?);
    }
    let mut cvode = Curve { method: "cvode".into(), knob: "rtol", points: vec![] };
    for &rtol in rtols {
        let s = GrowthSettings { integrator: Integrator::Cvode, rtol, atol: rtol * 1e-2, ..settings.clone() };
        cvode.points.push(measure(&s, rtol, &format!("CVODE rtol {rtol:e}"))?);
    }
    Ok(vec![euler, cvode])
}

/// For each target accuracy, the cheapest method that reaches it (by interpolating each
/// curve's cost in log-log between its points): (target, method, seconds).
pub fn winners(curves: &[Curve], targets: &[f64], axial: bool) -> Vec<(f64, String, f64)> {
    let err = |p: &WorkPoint| if axial { p.axial_error } else { p.error };
    targets
        .iter()
        .filter_map(|&target| {
            curves
                .iter()
                .filter_map(|c| {
                    // The cheapest point at or below the target.
                    c.points.iter().filter(|p| err(p) <= target).map(|p| p.seconds).fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.min(t)))).map(|t| (c.method.clone(), t))
                })
                .min_by(|a, b| a.1.partial_cmp(&b.1).unwrap())
                .map(|(m, t)| (target, m, t))
        })
        .collect()
}

/// All curves as one CSV table: method, knob, value, error, axial_error, seconds.
pub fn table(curves: &[Curve]) -> (Vec<String>, Vec<Vec<String>>) {
    use super::cell;
    let header = ["method", "knob", "value", "error", "axial_error", "seconds"].map(String::from).to_vec();
    let rows = curves
        .iter()
        .flat_map(|c| {
            c.points.iter().map(move |p| vec![c.method.clone(), c.knob.to_string(), cell(p.value), cell(p.error), cell(p.axial_error), cell(p.seconds)])
        })
        .collect();
    (header, rows)
}
