//! Work-precision diagrams (the trade of speed for accuracy): error against
//! CPU seconds, each error taken against a reference computed at much tighter settings.
//! - Elastic: trapezoid and Hermite–Simpson over a self-similar ladder of meshes (each
//!   rung the last with every interval halved), and Richardson-extrapolated
//!   Hermite–Simpson from consecutive rungs (order 6), errors at common material points;
//!   and Hermite–Simpson with `solver.tol`, its mesh adapted to each tolerance.
//! - Growth: explicit Euler over its step count, CVODE and IDA over rtol, errors in the axial
//!   length (the largest over the scene's output times and t_end: an integrator's error is
//!   not monotone in t, and one instant can flatter it) and the largest field error at t_end
//!   (same mesh as the reference); and IDA under `solver.tol` (mesh and rtol chosen) beside
//!   a fixed (N, rtol) ladder, axial-length errors against a reference on a finer mesh.

use super::{max_diff, run, sample, worst, StudyError};
use eyeshell::bvp::settings::{Scheme, SolverSettings};
use eyeshell::growth::{GrowthSettings, Integrator};
use eyeshell::model::params::Params;
use eyeshell::problem::GrowthProblem;

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
    /// Error of the axial length, the largest over the output times and t_end (growth only;
    /// NaN otherwise).
    pub axial_error: f64,
    pub seconds: f64,
    /// The error the solve estimated for itself (solver.tol; NaN otherwise).
    pub estimate: f64,
    /// Nodes of the mesh reported (elastic; NaN for growth).
    pub nodes: f64,
}

/// Repeat short runs so that timings are not a single noisy sample: the least of up to
/// `repeats` runs, stopping once `budget` seconds are spent.
fn best_of<T>(
    mut f: impl FnMut() -> Result<(T, f64), StudyError>,
    repeats: usize,
    budget: f64,
) -> Result<(T, f64), StudyError> {
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

/// The elastic diagram: both schemes on a ladder of as many rungs as `nodes` starting from
/// `nodes[0]`, and Richardson-extrapolated Hermite–Simpson, against Hermite–Simpson on the
/// last rung halved twice more (Newton tol 1e-12).
/// Every run solves Newton to 1e-12, so that the error measured is the discretisation's (at
/// the default 1e-10 Newton leaves about 1e-9 in Q, which would floor the finest rungs).
pub fn elastic(
    params: &Params,
    solver: &SolverSettings,
    nodes: &[usize],
) -> Result<Vec<Curve>, StudyError> {
    let solver = &SolverSettings {
        newton_tol: solver.newton_tol.min(1e-12),
        ..*solver
    };
    // A self-similar ladder: the first rung's mesh, then every interval halved again and
    // again, so that each error expansion keeps its coefficients from rung to rung (the
    // ladder by solver.nodes re-grades the pole at every N) and orders come out clean.
    let mut meshes = vec![eyeshell::bvp::solve::mesh_of(
        params,
        &SolverSettings {
            nodes: nodes[0],
            ..*solver
        },
    )
    .map_err(|e| StudyError::Invalid(e.to_string()))?];
    for _ in 1..nodes.len() {
        meshes.push(meshes.last().unwrap().halved());
    }
    // Errors at the first rung's nodes, which are nodes of every rung (no interpolation),
    // against Hermite–Simpson two halvings beyond the last rung.
    let pts = meshes[0].nodes.clone();
    let reference_mesh = meshes.last().unwrap().halved().halved();
    let tight = SolverSettings {
        scheme: Scheme::HermiteSimpson,
        ..*solver
    };
    let reference = eyeshell::bvp::solve::solve_on_mesh(params, &tight, reference_mesh, None)
        .map_err(|source| StudyError::Elastic {
            what: "reference".into(),
            source,
        })?;
    let ref_vals = sample(&reference, &pts, "reference")?;
    let mut curves = vec![];
    let mut hs_runs = vec![];
    for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
        let name = match scheme {
            Scheme::Trapezoid => "trapezoid",
            Scheme::HermiteSimpson => "hermite-simpson",
        };
        let mut c = Curve {
            method: name.into(),
            knob: "nodes",
            points: vec![],
        };
        let s = SolverSettings { scheme, ..*solver };
        for mesh in &meshes {
            let what = format!("{scheme:?} on {} nodes", mesh.len());
            let (vals, seconds) = best_of(
                || {
                    let start = std::time::Instant::now();
                    let sol = eyeshell::bvp::solve::solve_on_mesh(params, &s, mesh.clone(), None)
                        .map_err(|source| StudyError::Elastic {
                        what: what.clone(),
                        source,
                    })?;
                    let secs = start.elapsed().as_secs_f64();
                    Ok((sample(&sol, &pts, &what)?, secs))
                },
                5,
                1.0,
            )?;
            c.points.push(WorkPoint {
                value: mesh.len() as f64,
                error: worst(&max_diff(&vals, &ref_vals)),
                axial_error: f64::NAN,
                seconds,
                estimate: f64::NAN,
                nodes: mesh.len() as f64,
            });
            if scheme == Scheme::HermiteSimpson {
                hs_runs.push((mesh.len(), vals, seconds));
            }
        }
        curves.push(c);
    }
    // Richardson: Hermite–Simpson on consecutive rungs, y_f + (y_f − y_c)/15: order 6.
    let mut rich = Curve {
        method: "hermite-simpson + Richardson".into(),
        knob: "nodes",
        points: vec![],
    };
    for w in hs_runs.windows(2) {
        let ((_, coarse, t1), (n, fine, t2)) = (&w[0], &w[1]);
        let extrapolated: Vec<[f64; 5]> = coarse
            .iter()
            .zip(fine)
            .map(|(c, f)| std::array::from_fn(|j| f[j] + (f[j] - c[j]) / 15.0))
            .collect();
        rich.points.push(WorkPoint {
            value: *n as f64,
            error: worst(&max_diff(&extrapolated, &ref_vals)),
            axial_error: f64::NAN,
            seconds: t1 + t2,
            estimate: f64::NAN,
            nodes: *n as f64,
        });
    }
    curves.push(rich);
    curves.push(tolerance_curve(params, solver, &pts, &ref_vals)?);
    Ok(curves)
}

/// The requested tolerances of the tolerance-driven curve.
pub const TOLERANCES: [f64; 4] = [1e-4, 1e-6, 1e-8, 1e-10];

/// Hermite–Simpson with `solver.tol` (the mesh adapted to each of [`TOLERANCES`]): the
/// true error at the same points, the estimate it reported, and the time of the whole
/// adaptive solve.
fn tolerance_curve(
    params: &Params,
    solver: &SolverSettings,
    pts: &[f64],
    ref_vals: &[[f64; 5]],
) -> Result<Curve, StudyError> {
    let mut c = Curve {
        method: "hermite-simpson solver.tol".into(),
        knob: "tol",
        points: vec![],
    };
    for tol in TOLERANCES {
        let s = SolverSettings {
            scheme: Scheme::HermiteSimpson,
            tol: Some(tol),
            ..*solver
        };
        let what = format!("solver.tol = {tol:e}");
        let ((vals, estimate, nodes), seconds) = best_of(
            || {
                let start = std::time::Instant::now();
                let sol = eyeshell::bvp::solve(params, &s, None).map_err(|source| {
                    StudyError::Elastic {
                        what: what.clone(),
                        source,
                    }
                })?;
                let secs = start.elapsed().as_secs_f64();
                let estimate = sol.stats.error_estimate.map_or(f64::NAN, |e| e.overall);
                Ok(((sample(&sol, pts, &what)?, estimate, sol.mesh.len()), secs))
            },
            5,
            1.0,
        )?;
        c.points.push(WorkPoint {
            value: tol,
            error: worst(&max_diff(&vals, ref_vals)),
            axial_error: f64::NAN,
            seconds,
            estimate,
            nodes: nodes as f64,
        });
    }
    Ok(c)
}

/// The largest |axial length − reference| over the times both runs report (the scene's
/// output times and t_end); NaN if they share none.
fn largest_axial_difference(run: &[(f64, f64)], reference: &[(f64, f64)]) -> f64 {
    let mut worst = f64::NAN;
    for &(t, a) in run {
        if let Some(&(_, b)) = reference.iter().find(|(tr, _)| *tr == t) {
            let d = (a - b).abs();
            worst = if worst.is_nan() || d > worst || d.is_nan() {
                d
            } else {
                worst
            };
        }
    }
    worst
}

/// The growth diagram: Euler over `steps`, CVODE and IDA over `rtols`, against CVODE at
/// `reference_rtol`, all on the scene's mesh.
pub fn growth(
    problem: &GrowthProblem,
    steps: &[usize],
    rtols: &[f64],
    reference_rtol: f64,
) -> Result<Vec<Curve>, StudyError> {
    let (params, solver) = (problem.params(), problem.solver());
    let (g, settings) = (problem.growth(), problem.settings());
    let tight = GrowthSettings {
        integrator: Integrator::Cvode,
        rtol: reference_rtol,
        atol: reference_rtol * 1e-2,
        ..settings.clone()
    };
    let reference = run(params, solver, Some((g, &tight)), "reference")?;
    let pts: Vec<f64> = reference.solution.mesh.nodes.clone();
    let ref_vals = sample(&reference.solution, &pts, "reference")?;
    let ref_axial = reference.axial_series.clone();
    // Each point's seconds are the least of up to five runs, as the elastic diagram's: one
    // sample on a shared machine, or the first run of an integrator in the process, once
    // showed IDA dearer at rtol 1e-2 (0.071 s) than at 1e-4 (0.029 s), where runs alone
    // take 35–39 ms at every rtol.
    let measure = |s: &GrowthSettings, value: f64, what: &str| -> Result<WorkPoint, StudyError> {
        let (r, seconds) = best_of(
            || {
                let r = run(params, solver, Some((g, s)), what)?;
                let t = r.seconds;
                Ok((r, t))
            },
            5,
            1.0,
        )?;
        let vals = sample(&r.solution, &pts, what)?;
        Ok(WorkPoint {
            value,
            error: worst(&max_diff(&vals, &ref_vals)),
            axial_error: largest_axial_difference(&r.axial_series, &ref_axial),
            seconds,
            estimate: f64::NAN,
            nodes: f64::NAN,
        })
    };
    let mut euler = Curve {
        method: "euler".into(),
        knob: "steps",
        points: vec![],
    };
    for &n in steps {
        let s = GrowthSettings {
            integrator: Integrator::Euler,
            steps: n,
            ..settings.clone()
        };
        euler
            .points
            .push(measure(&s, n as f64, &format!("Euler {n} steps"))?);
    }
    let mut curves = vec![euler];
    for integrator in [Integrator::Cvode, Integrator::Ida] {
        let mut c = Curve {
            method: integrator.name().into(),
            knob: "rtol",
            points: vec![],
        };
        for &rtol in rtols {
            let s = GrowthSettings {
                integrator,
                rtol,
                atol: rtol * 1e-2,
                ..settings.clone()
            };
            c.points.push(measure(
                &s,
                rtol,
                &format!("{} rtol {rtol:e}", integrator.name()),
            )?);
        }
        curves.push(c);
    }
    Ok(curves)
}

/// The requested tolerances (mm) of the growth diagram's `solver.tol` series.
pub const GROWTH_TOLERANCES: [f64; 3] = [1e-3, 1e-4, 1e-5];
/// The fixed (N, rtol) ladder beside it: on the const scene each rung is the cheapest point
/// of BENCHMARKS.md's hand-picked grid for about a decade of tol (atol = rtol/100).
pub const GROWTH_LADDER: [(usize, f64); 4] = [(51, 1e-5), (101, 1e-6), (201, 1e-7), (401, 1e-8)];
/// The reference of both, space and time together: IDA on this many nodes at this rtol
/// (BENCHMARKS.md, "Growth to a tolerance": CVODE on 1601 nodes at rtol 1e-10 lies within
/// 2.8e-8 mm of it on the const scene).
pub const GROWTH_REFERENCE: (usize, f64) = (3201, 1e-10);

/// The growth diagram's accuracy series: IDA under `solver.tol` for each of `tols` (its mesh
/// and rtol chosen; the point's `estimate` is the axial length's estimated total error
/// from summary.json's `error_estimate`, `nodes` the delivered mesh's, `seconds` the whole
/// choice), and IDA on the fixed (N, rtol) `ladder` (value and nodes N); the axial-length
/// error of each, the largest over the output times and t_end, against IDA on the mesh of
/// `reference.0` nodes at rtol `reference.1`. Field errors are NaN: the meshes differ.
pub fn growth_tolerance(
    problem: &GrowthProblem,
    tols: &[f64],
    ladder: &[(usize, f64)],
    reference: (usize, f64),
) -> Result<Vec<Curve>, StudyError> {
    let (params, solver) = (problem.params(), problem.solver());
    let (g, settings) = (problem.growth(), problem.settings());
    let ida = |rtol: f64| GrowthSettings {
        integrator: Integrator::Ida,
        rtol,
        atol: rtol * 1e-2,
        ..settings.clone()
    };
    let on = |nodes: usize| SolverSettings {
        nodes,
        tol: None,
        ..*solver
    };
    let ref_axial = run(
        params,
        &on(reference.0),
        Some((g, &ida(reference.1))),
        "reference",
    )?
    .axial_series;
    let point = |r: super::Run, value: f64, nodes: f64| {
        let estimate = r
            .growth
            .as_ref()
            .and_then(|s| s.error_estimate.as_ref())
            .map_or(f64::NAN, |e| e.largest.axial_length.total);
        let nodes = r
            .growth
            .as_ref()
            .and_then(|s| s.accuracy.as_ref())
            .map_or(nodes, |a| a.nodes as f64);
        WorkPoint {
            value,
            error: f64::NAN,
            axial_error: largest_axial_difference(&r.axial_series, &ref_axial),
            seconds: r.seconds,
            estimate,
            nodes,
        }
    };
    let mut tol_curve = Curve {
        method: "ida solver.tol".into(),
        knob: "tol",
        points: vec![],
    };
    for &tol in tols {
        let s = SolverSettings {
            tol: Some(tol),
            ..*solver
        };
        let what = format!("IDA solver.tol = {tol:e}");
        tol_curve.points.push(point(
            run(params, &s, Some((g, &ida(settings.rtol))), &what)?,
            tol,
            f64::NAN,
        ));
    }
    let mut fixed = Curve {
        method: "ida fixed (N, rtol)".into(),
        knob: "nodes",
        points: vec![],
    };
    for &(n, rtol) in ladder {
        let what = format!("IDA N = {n}, rtol {rtol:e}");
        fixed.points.push(point(
            run(params, &on(n), Some((g, &ida(rtol))), &what)?,
            n as f64,
            n as f64,
        ));
    }
    Ok(vec![tol_curve, fixed])
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
                    c.points
                        .iter()
                        .filter(|p| err(p) <= target)
                        .map(|p| p.seconds)
                        .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.min(t))))
                        .map(|t| (c.method.clone(), t))
                })
                .min_by(|a, b| a.1.partial_cmp(&b.1).unwrap())
                .map(|(m, t)| (target, m, t))
        })
        .collect()
}

/// All curves as one CSV table: method, knob, value, error, axial_error, seconds, and the
/// estimate and nodes where known.
pub fn table(curves: &[Curve]) -> (Vec<String>, Vec<Vec<String>>) {
    use super::cell;
    let header = [
        "method",
        "knob",
        "value",
        "error",
        "axial_error",
        "seconds",
        "estimate",
        "nodes",
    ]
    .map(String::from)
    .to_vec();
    let rows = curves
        .iter()
        .flat_map(|c| {
            c.points.iter().map(move |p| {
                vec![
                    c.method.clone(),
                    c.knob.to_string(),
                    cell(p.value),
                    cell(p.error),
                    cell(p.axial_error),
                    cell(p.seconds),
                    cell(p.estimate),
                    cell(p.nodes),
                ]
            })
        })
        .collect();
    (header, rows)
}

/// One row of the efficiency table of `solver.tol`: the adapted solve against the
/// uniform-plus-grading mesh (solver.nodes, pole and cornea grading, breakpoints) that
/// reaches the same true error.
#[derive(Clone, Copy, Debug)]
pub struct Efficiency {
    pub tol: f64,
    pub adapted_nodes: usize,
    pub adapted_error: f64,
    pub estimate: f64,
    pub adapted_seconds: f64,
    /// The fewest uniform nodes N whose mesh reaches `adapted_error` (to 2 %), and the
    /// nodes, error and time of that solve.
    pub uniform: usize,
    pub fixed_nodes: usize,
    pub fixed_error: f64,
    pub fixed_seconds: f64,
}

/// For each tolerance: the adapted Hermite–Simpson solve, and the smallest solver.nodes
/// whose (uniform + graded) mesh is as accurate, found by doubling then bisection. True
/// errors are the largest over the five fields at the solution's own nodes (fields.csv,
/// what solver.tol's estimate is of), against Hermite–Simpson on the 1601-node mesh
/// halved twice (interpolated there); times the least of up to 5 runs.
pub fn efficiency(
    params: &Params,
    solver: &SolverSettings,
    tols: &[f64],
) -> Result<Vec<Efficiency>, StudyError> {
    let solver = SolverSettings {
        scheme: Scheme::HermiteSimpson,
        newton_tol: solver.newton_tol.min(1e-12),
        tol: None,
        ..*solver
    };
    let elastic = |what: &str| {
        let what = what.to_string();
        move |source| StudyError::Elastic { what, source }
    };
    let fine = SolverSettings {
        nodes: 1601,
        ..solver
    };
    let mesh = eyeshell::bvp::solve::mesh_of(params, &fine)
        .map_err(|e| StudyError::Invalid(e.to_string()))?
        .halved()
        .halved();
    let reference = eyeshell::bvp::solve::solve_on_mesh(params, &solver, mesh, None)
        .map_err(elastic("reference"))?;
    let nodal_error = |sol: &eyeshell::bvp::Solution| -> Result<f64, StudyError> {
        let vals = sol.rows.iter().map(super::five).collect::<Vec<_>>();
        Ok(worst(&max_diff(
            &vals,
            &sample(&reference, &sol.mesh.nodes, "reference")?,
        )))
    };
    let timed = |s: &SolverSettings, what: &str| {
        best_of(
            || {
                let start = std::time::Instant::now();
                let sol = eyeshell::bvp::solve(params, s, None).map_err(elastic(what))?;
                let secs = start.elapsed().as_secs_f64();
                let err = nodal_error(&sol)?;
                Ok(((sol, err), secs))
            },
            5,
            1.0,
        )
    };
    let error_at = |n: usize| -> Result<f64, StudyError> {
        let s = SolverSettings { nodes: n, ..solver };
        let sol = eyeshell::bvp::solve(params, &s, None).map_err(elastic("uniform"))?;
        nodal_error(&sol)
    };
    let mut rows = vec![];
    for &tol in tols {
        let s = SolverSettings {
            tol: Some(tol),
            ..solver
        };
        let ((sol, adapted_error), adapted_seconds) = timed(&s, &format!("solver.tol = {tol:e}"))?;
        // The fewest uniform nodes reaching the adapted solve's true error.
        let (mut lo, mut hi) = (5usize, 26usize);
        while error_at(hi)? > adapted_error {
            lo = hi;
            hi = 2 * hi - 1;
            if hi > eyeshell::mesh::MAX_NODES / 2 {
                return Err(StudyError::Invalid(format!(
                    "no uniform mesh of up to {hi} nodes reaches {adapted_error:e}"
                )));
            }
        }
        while hi - lo > (hi / 50).max(1) {
            let mid = (lo + hi) / 2;
            if error_at(mid)? > adapted_error {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let fixed = SolverSettings {
            nodes: hi,
            ..solver
        };
        let ((fixed_sol, fixed_error), fixed_seconds) = timed(&fixed, &format!("N = {hi}"))?;
        rows.push(Efficiency {
            tol,
            adapted_nodes: sol.mesh.len(),
            adapted_error,
            estimate: sol.stats.error_estimate.map_or(f64::NAN, |e| e.overall),
            adapted_seconds,
            uniform: hi,
            fixed_nodes: fixed_sol.mesh.len(),
            fixed_error,
            fixed_seconds,
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use eyeshell::model::params::Thickness;

    /// On the exact sphere and the non-uniform shells (with and without fibres), at each tol
    /// of the issue, the adapted mesh reaches a true error with fewer nodes than the
    /// uniform + graded mesh that reaches the same (timings are for BENCHMARKS.md, not here).
    #[test]
    fn adapted_meshes_need_fewer_nodes_than_uniform_ones() {
        let nonuniform = |d| Params {
            thickness: Thickness::NonUniform,
            d,
            ..Params::default()
        };
        let shells = [
            ("exact sphere", Params::default().exact_sphere()),
            ("non-uniform", nonuniform(0.0)),
            ("fibre", nonuniform(200.0)),
        ];
        for (name, p) in shells {
            let rows = efficiency(&p, &SolverSettings::default(), &TOLERANCES).unwrap();
            assert_eq!(rows.len(), 4);
            for r in rows {
                assert!(
                    r.adapted_nodes < r.fixed_nodes && r.fixed_error <= r.adapted_error,
                    "{name}: {r:?}"
                );
                assert!(r.adapted_error <= r.tol, "{name}: {r:?}");
            }
        }
    }

    /// The growth diagram's solver.tol series on the const scene: a point per tol, each
    /// delivered within tol with an estimate within [1/3, 30] of its true error, and the
    /// ladder's rungs beside it (a cheap reference here: IDA on N = 201 at rtol 1e-7, within
    /// 5e-6 mm of N = 3201 at 1e-10 by BENCHMARKS.md; the command uses the latter).
    #[test]
    fn growth_tol_series_delivers_within_tol() {
        let scene = eyeshell::scene::Scene::from_file(
            std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/const.toml")),
            &[],
        )
        .unwrap();
        let problem = scene.growth_problem().unwrap().unwrap();
        let curves = growth_tolerance(&problem, &[1e-3, 1e-4], &[(51, 1e-5)], (201, 1e-7)).unwrap();
        let tol = curves.iter().find(|c| c.knob == "tol").unwrap();
        assert_eq!(
            tol.points.iter().map(|p| p.value).collect::<Vec<_>>(),
            [1e-3, 1e-4]
        );
        for p in &tol.points {
            assert!(p.axial_error > 0.0 && p.axial_error <= p.value, "{p:?}");
            assert!(
                p.estimate >= p.axial_error / 3.0 && p.estimate <= 30.0 * p.axial_error,
                "{p:?}"
            );
            assert!(
                p.nodes > 11.0 && p.nodes < 501.0 && p.seconds > 0.0,
                "{p:?}"
            );
        }
        let fixed = curves.iter().find(|c| c.knob == "nodes").unwrap();
        assert_eq!(fixed.points.len(), 1);
        // N = 51 at rtol 1e-5: 2.3e-4 mm on the const scene (BENCHMARKS.md).
        let e = fixed.points[0].axial_error;
        assert!(e > 5e-5 && e < 1e-3, "{e}");
    }
}
