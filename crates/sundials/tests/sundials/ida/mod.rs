//! IDA through the safe layer: Robertson's kinetics as a DAE (idaRoberts_dns) with the
//! system's own linear solver, dense (user and difference-quotient Jacobians) and band,
//! against a tight CVODE run of the ODE form; a linear index-1 DAE against its closed form
//! at three tolerances; consistent initial conditions (IDACalcIC) and suppressed algebraic
//! error test; recoverable, fatal and panicking callbacks; counters, dense output, stop time,
//! reinit, invalid options; many create/drop cycles.

use eyeshell_sundials::{
    CallbackError, CallbackResult, Cvode, CvodeLinearSolver, CvodeOptions, DaeSystem, Ida,
    IdaLinearSolver, IdaOptions, IdaStats, JacobianMatrix, MatrixSink, OdeSystem, SundialsError,
};
use nalgebra::{DMatrix, DVector, LU};

use crate::sundials_support::flag_parts;

mod calc_ic;
mod failures;
mod options;

type Lu = LU<f64, nalgebra::Dyn, nalgebra::Dyn>;

/// A dense LU of M for the Custom solver, as a caller's own solver would keep one.
#[derive(Default)]
struct OwnSolver {
    lu: Option<Lu>,
    setups: usize,
    solves: usize,
}

impl OwnSolver {
    fn setup(&mut self, m: DMatrix<f64>) -> CallbackResult {
        self.setups += 1;
        let lu = m.lu();
        if !lu.is_invertible() {
            return Err(CallbackError::Recoverable("singular Newton matrix".into()));
        }
        self.lu = Some(lu);
        Ok(())
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.solves += 1;
        let lu = self
            .lu
            .as_ref()
            .ok_or_else(|| CallbackError::Fatal("solve before setup".into()))?;
        let sol = lu
            .solve(&DVector::from_column_slice(b))
            .ok_or_else(|| CallbackError::Recoverable("LU solve failed".into()))?;
        x.copy_from_slice(sol.as_slice());
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Robertson as a DAE

/// y1' = −0.04 y1 + 1e4 y2 y3, y2' = 0.04 y1 − 1e4 y2 y3 − 3e7 y2², 0 = y1 + y2 + y3 − 1.
#[derive(Default)]
struct RobertsonDae {
    residual_calls: usize,
    jac_calls: usize,
    own: OwnSolver,
}

impl RobertsonDae {
    /// M = ∂F/∂y + cj ∂F/∂y'.
    fn newton_matrix(cj: f64, y: &[f64]) -> [[f64; 3]; 3] {
        [
            [-0.04 - cj, 1e4 * y[2], 1e4 * y[1]],
            [0.04, -1e4 * y[2] - 6e7 * y[1] - cj, -1e4 * y[1]],
            [1.0, 1.0, 1.0],
        ]
    }

    fn f(y: &[f64], yp: &[f64], r: &mut [f64]) {
        let (a, b) = (0.04 * y[0] - 1e4 * y[1] * y[2], 3e7 * y[1] * y[1]);
        r[0] = -a - yp[0];
        r[1] = a - b - yp[1];
        r[2] = y[0] + y[1] + y[2] - 1.0;
    }
}

impl DaeSystem for RobertsonDae {
    fn residual(&mut self, _t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        self.residual_calls += 1;
        Self::f(y, yp, r);
        Ok(())
    }

    fn linear_setup(
        &mut self,
        _t: f64,
        cj: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
    ) -> CallbackResult {
        let m = Self::newton_matrix(cj, y);
        self.own.setup(DMatrix::from_fn(3, 3, |i, j| m[i][j]))
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.own.solve(b, x)
    }

    fn jacobian(
        &mut self,
        _t: f64,
        cj: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        mut jac: JacobianMatrix<'_>,
    ) -> CallbackResult {
        self.jac_calls += 1;
        let m = Self::newton_matrix(cj, y);
        for i in 0..3 {
            for j in 0..3 {
                jac.set(i, j, m[i][j]);
            }
        }
        Ok(())
    }
}

/// idaRoberts_dns's settings.
fn robertson_options() -> IdaOptions {
    IdaOptions {
        rtol: 1e-4,
        atol_vector: Some(vec![1e-8, 1e-6, 1e-6]),
        id: Some(vec![1.0, 1.0, 0.0]),
        ..Default::default()
    }
}

const ROBERTSON_Y0: [f64; 3] = [1.0, 0.0, 0.0];
const ROBERTSON_YP0: [f64; 3] = [-0.04, 0.04, 0.0];

/// IDA on Robertson from its consistent start (ROBERTSON_Y0, ROBERTSON_YP0) at t = 0.
fn robertson(linear: IdaLinearSolver, options: &IdaOptions) -> Ida<RobertsonDae> {
    Ida::new(
        RobertsonDae::default(),
        0.0,
        &ROBERTSON_Y0,
        &ROBERTSON_YP0,
        linear,
        options,
    )
    .unwrap()
}

/// The ODE form (y3' = 3e7 y2²) for CVODE: an independent reference.
struct RobertsonOde;

impl OdeSystem for RobertsonOde {
    fn rhs(&mut self, _t: f64, y: &[f64], ydot: &mut [f64]) -> CallbackResult {
        let (a, b) = (0.04 * y[0] - 1e4 * y[1] * y[2], 3e7 * y[1] * y[1]);
        ydot[0] = -a;
        ydot[1] = a - b;
        ydot[2] = b;
        Ok(())
    }
}

const ROBERTSON_TOUTS: [f64; 12] = [0.4, 4.0, 40.0, 4e2, 4e3, 4e4, 4e5, 4e6, 4e7, 4e8, 4e9, 4e10];

/// y at the outputs from CVODE (BDF on the ODE form, difference-quotient Jacobian) at
/// rtol 1e-11: a reference independent of IDA and of the DAE form.
fn cvode_reference() -> Vec<[f64; 3]> {
    let options = CvodeOptions {
        rtol: 1e-11,
        atol_vector: Some(vec![1e-16, 1e-22, 1e-16]),
        max_steps: 1_000_000,
        ..Default::default()
    };
    let mut cv = Cvode::new(
        RobertsonOde,
        0.0,
        &ROBERTSON_Y0,
        CvodeLinearSolver::Dense {
            user_jacobian: false,
        },
        &options,
    )
    .unwrap();
    ROBERTSON_TOUTS
        .iter()
        .map(|&tout| {
            let mut y = [0.0; 3];
            cv.advance_to(tout, &mut y).unwrap();
            y
        })
        .collect()
}

/// The error in IDA's own weights: max_i |y_i − ref_i| / (rtol |ref_i| + atol_i).
fn weighted_error(y: &[f64; 3], reference: &[f64; 3], options: &IdaOptions) -> f64 {
    let atol = options.atol_vector.as_ref().unwrap();
    (0..3)
        .map(|i| (y[i] - reference[i]).abs() / (options.rtol * reference[i].abs() + atol[i]))
        .fold(0.0, f64::max)
}

/// A BDF code's global error is a few times its local error tolerance: observed ≤ 2.9 in
/// IDA's weights for every solver here, at every output.
const ROBERTSON_WEIGHTED_ERROR: f64 = 5.0;

/// Integrate to the first `outputs` of 0.4, 4, ..., 4e10 (idaRoberts_dns's outputs); check
/// y1 + y2 + y3 = 1 at every output; return every output and the solver.
fn run_robertson(
    linear: IdaLinearSolver,
    options: &IdaOptions,
    outputs: usize,
) -> (Vec<[f64; 3]>, Ida<RobertsonDae>) {
    let mut ida = robertson(linear.clone(), options);
    let (mut y, mut yp) = ([0.0; 3], [0.0; 3]);
    let mut results = Vec::new();
    let mut worst_sum: f64 = 0.0;
    for &tout in &ROBERTSON_TOUTS[..outputs] {
        let t = ida
            .advance_to(tout, &mut y, &mut yp)
            .unwrap_or_else(|e| panic!("{linear:?} at tout {tout}: {e}"));
        assert_eq!(t, tout);
        // The constraint row of M is exactly (1, 1, 1) (or 1 + O(1e-8) by difference
        // quotients), so each Newton correction keeps the sum, and so does interpolation (a
        // linear combination of states and differences whose sums are 1 and 0): what is left
        // is round-off, accumulated over some 300 steps (observed ≤ 1.2e-13).
        let sum = y[0] + y[1] + y[2];
        worst_sum = worst_sum.max((sum - 1.0).abs());
        assert!(
            (sum - 1.0).abs() < 1e-12,
            "{linear:?}: y1 + y2 + y3 − 1 = {:e} at t = {t}",
            sum - 1.0
        );
        results.push(y);
    }
    eprintln!("{linear:?}: max |y1 + y2 + y3 − 1| = {worst_sum:.1e}");
    if outputs == ROBERTSON_TOUTS.len() {
        // At t = 4e10 nearly everything is y3 (y1 = 5.2e-8, y2 = 2.1e-13).
        let last = results[outputs - 1];
        assert!(
            last[0].abs() < 1e-6 && last[1].abs() < 1e-11 && last[2] > 0.999_99,
            "{linear:?}: y(4e10) = {last:?}"
        );
    }
    (results, ida)
}

#[test]
fn robertson_reference_is_the_published_one() {
    // The tight references: CVODE on the ODE form and IDA (dense) on the DAE form agree to
    // ~1e-9 relative, and both round to the published y(0.4) (cvRoberts_dns, idaRoberts_dns).
    let cv = cvode_reference()[0];
    let tight = IdaOptions {
        rtol: 1e-10,
        atol_vector: Some(vec![1e-14, 1e-18, 1e-14]),
        max_steps: 100_000,
        ..robertson_options()
    };
    let dense = IdaLinearSolver::Dense {
        user_jacobian: true,
    };
    let mut ida = robertson(dense, &tight);
    let (mut y, mut yp) = ([0.0; 3], [0.0; 3]);
    ida.advance_to(0.4, &mut y, &mut yp).unwrap();
    for i in 0..3 {
        assert!(
            (y[i] - cv[i]).abs() < 1e-8 * cv[i].abs(),
            "component {i}: IDA {:e}, CVODE {:e}",
            y[i],
            cv[i]
        );
    }
    assert!((cv[0] - 9.8517e-01).abs() < 5e-6, "{cv:?}");
    assert!((cv[1] - 3.3864e-05).abs() < 5e-10, "{cv:?}");
    // idaRoberts_dns prints y3 = 1.4796e-02: its own result at rtol = 1e-4, 2e-6 (1.4e-4
    // relative) off the converged 0.0147940, which 1 − y1 − y2 confirms.
    assert!((cv[2] - 1.47940e-02).abs() < 5e-8, "{cv:?}");
    // y' at 0.4 satisfies the differential equations: F(t, y, y') = 0 to the tolerance.
    let mut r = [0.0; 3];
    RobertsonDae::f(&y, &yp, &mut r);
    assert!(r.iter().all(|v| v.abs() < 1e-8), "F(0.4) = {r:?}");
}

#[test]
fn robertson_with_analytic_matrices_agrees_with_the_reference() {
    let reference = cvode_reference();
    let options = robertson_options();
    let mut runs = Vec::new();
    for linear in [
        IdaLinearSolver::Custom,
        IdaLinearSolver::Dense {
            user_jacobian: true,
        },
        IdaLinearSolver::Band {
            upper: 2,
            lower: 2,
            user_jacobian: true,
        },
    ] {
        let (outputs, ida) = run_robertson(linear.clone(), &options, ROBERTSON_TOUTS.len());
        for (k, y) in outputs.iter().enumerate() {
            let e = weighted_error(y, &reference[k], &options);
            let (t, r) = (ROBERTSON_TOUTS[k], reference[k]);
            assert!(
                e < ROBERTSON_WEIGHTED_ERROR,
                "{linear:?} at t = {t}: y = {y:?}, reference {r:?}, weighted error {e:.2}"
            );
        }
        let y = outputs[0];
        let published = (y[0] - 0.98517).abs() < 5e-6
            && (y[1] - 3.3864e-5).abs() < 5e-10
            && (y[2] - 0.014794).abs() < 5e-6;
        assert!(published, "{linear:?}: y(0.4) = {y:?}");
        eprintln!("{linear:?}: y(0.4) = {y:?}, {:?}", ida.stats());
        runs.push((linear, outputs, ida.stats()));
    }
    // The three see the same M up to round-off (the caller's LU, SUNDIALS's dense LU, its band
    // LU with full bandwidth), so they take the same steps and agree far inside the tolerance.
    let (_, custom, custom_stats) = &runs[0];
    for (linear, outputs, stats) in &runs[1..] {
        assert_eq!(
            (stats.steps, stats.jacobian_evaluations),
            (custom_stats.steps, custom_stats.jacobian_evaluations),
            "{linear:?}"
        );
        for (k, y) in outputs.iter().enumerate() {
            let e = weighted_error(y, &custom[k], &options);
            assert!(
                e < 1e-6,
                "{linear:?} vs Custom at t = {}: {y:?} vs {:?}",
                ROBERTSON_TOUTS[k],
                custom[k]
            );
        }
    }
}

#[test]
fn robertson_with_difference_quotients_agrees_with_the_reference() {
    let reference = cvode_reference();
    // With idaRoberts_dns's atol = 1e-6 for y2 (1e3 × y2 once t ≳ 1e5), IDA's DQ increment
    // for y2 is 1/ewt = atol: ∂F2/∂y2 picks up 3e7 · 1e-6 = 30, which swamps the 6e7 y2 ≲ 0.1
    // that sets the slow dynamics, so Newton stalls once h ≳ 1e4 (the step size sticks at
    // ~7e3, the run needs 19000 steps to 9e7). It is accurate up to 4e4; an atol of 1e-14
    // for y2 takes it to 4e10 in ~500 steps.
    let loose = robertson_options();
    let tight_y2 = IdaOptions {
        atol_vector: Some(vec![1e-8, 1e-14, 1e-6]),
        ..robertson_options()
    };
    for linear in [
        IdaLinearSolver::Dense {
            user_jacobian: false,
        },
        IdaLinearSolver::Band {
            upper: 2,
            lower: 2,
            user_jacobian: false,
        },
    ] {
        for (options, outputs) in [(&loose, 6), (&tight_y2, ROBERTSON_TOUTS.len())] {
            let (results, ida) = run_robertson(linear.clone(), options, outputs);
            for (k, y) in results.iter().enumerate() {
                let e = weighted_error(y, &reference[k], options);
                let (t, r) = (ROBERTSON_TOUTS[k], reference[k]);
                assert!(
                    e < ROBERTSON_WEIGHTED_ERROR,
                    "{linear:?} at t = {t}: y = {y:?}, reference {r:?}, weighted error {e:.2}"
                );
            }
            let s = ida.stats();
            assert!(s.steps < 600, "{linear:?}: {s:?}");
        }
        // The stall: to 4e6 with the loose atol, several times the steps of the analytic M.
        let (_, dq) = run_robertson(linear.clone(), &loose, 8);
        let (_, analytic) = run_robertson(IdaLinearSolver::Custom, &loose, 8);
        let (dq, analytic) = (dq.stats(), analytic.stats());
        assert!(
            dq.steps > 3 * analytic.steps && dq.nonlinear_convergence_failures > 100,
            "{linear:?}: DQ {dq:?}, analytic {analytic:?}"
        );
    }
}

#[test]
fn custom_solver_reuses_its_matrix_and_counts_match_the_system() {
    let (_, ida) = run_robertson(
        IdaLinearSolver::Custom,
        &robertson_options(),
        ROBERTSON_TOUTS.len(),
    );
    let s = ida.stats();
    let sys = ida.system();
    assert!(s.steps > 100, "{s:?}");
    assert!(
        s.jacobian_evaluations >= 1 && 5 * s.jacobian_evaluations < s.nonlinear_iterations,
        "IDA reuses M across steps: {s:?}"
    );
    assert_eq!(
        s.jacobian_evaluations, sys.own.setups,
        "IDAGetNumJacEvals counts linear_setup calls"
    );
    assert_eq!(s.linear_setups, s.jacobian_evaluations, "{s:?}");
    assert_eq!(
        sys.own.solves, s.nonlinear_iterations,
        "one linear_solve per Newton iteration"
    );
    assert_eq!(s.residual_evaluations, sys.residual_calls);
    assert_eq!(
        s.linear_solver_residual_evaluations, 0,
        "no difference quotients"
    );
    assert_eq!(
        sys.jac_calls, 0,
        "the dense Jacobian callback is not registered"
    );
    assert!(
        s.last_order >= 1 && s.last_step > 0.0 && s.current_time >= 4e10,
        "{s:?}"
    );
    eprintln!("Custom: {s:?}");
}

#[test]
fn dense_and_band_counters() {
    let options = robertson_options();
    let (_, ida) = run_robertson(
        IdaLinearSolver::Dense {
            user_jacobian: true,
        },
        &options,
        ROBERTSON_TOUTS.len(),
    );
    let s = ida.stats();
    assert_eq!(s.jacobian_evaluations, ida.system().jac_calls);
    assert_eq!(
        (
            s.linear_solver_residual_evaluations,
            ida.system().own.setups
        ),
        (0, 0)
    );
    assert_eq!(s.residual_evaluations, ida.system().residual_calls);
    for (linear, per_jacobian) in [
        (
            IdaLinearSolver::Dense {
                user_jacobian: false,
            },
            3,
        ),
        // Band difference quotients take min(upper + lower + 1, n) = 3 evaluations.
        (
            IdaLinearSolver::Band {
                upper: 2,
                lower: 2,
                user_jacobian: false,
            },
            3,
        ),
    ] {
        let (_, ida) = run_robertson(linear.clone(), &options, 6);
        let s = ida.stats();
        assert_eq!(
            ida.system().jac_calls,
            0,
            "{linear:?}: the user's Jacobian must not be called"
        );
        assert!(s.jacobian_evaluations > 0, "{linear:?}: {s:?}");
        assert_eq!(
            s.linear_solver_residual_evaluations,
            per_jacobian * s.jacobian_evaluations,
            "{linear:?}: {s:?}"
        );
        assert_eq!(
            s.residual_evaluations,
            ida.system().residual_calls,
            "{linear:?}: includes the difference quotients"
        );
    }
}

// ---------------------------------------------------------------------------------------
// A linear index-1 DAE with a closed form

/// y1' = −y1 + y2, 0 = y1 + y2 − sin t, y1(0) = 1: y1' = −2 y1 + sin t, so
/// y1 = 1.2 e^{−2t} + (2 sin t − cos t)/5 and y2 = sin t − y1.
#[derive(Default)]
struct Linear2 {
    own: OwnSolver,
    residual_calls: usize,
}

impl Linear2 {
    fn exact(t: f64) -> [f64; 2] {
        let y1 = 1.2 * (-2.0 * t).exp() + (2.0 * t.sin() - t.cos()) / 5.0;
        [y1, t.sin() - y1]
    }

    fn exact_derivative(t: f64) -> [f64; 2] {
        let y1p = -2.4 * (-2.0 * t).exp() + (2.0 * t.cos() + t.sin()) / 5.0;
        [y1p, t.cos() - y1p]
    }

    fn f(t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        r[0] = -y[0] + y[1] - yp[0];
        r[1] = y[0] + y[1] - t.sin();
    }
}

impl DaeSystem for Linear2 {
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        self.residual_calls += 1;
        Self::f(t, y, yp, r);
        Ok(())
    }

    fn linear_setup(
        &mut self,
        _t: f64,
        cj: f64,
        _y: &[f64],
        _yp: &[f64],
        _r: &[f64],
    ) -> CallbackResult {
        self.own
            .setup(DMatrix::from_row_slice(2, 2, &[-1.0 - cj, 1.0, 1.0, 1.0]))
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.own.solve(b, x)
    }

    fn jacobian(
        &mut self,
        _t: f64,
        cj: f64,
        _y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        mut jac: JacobianMatrix<'_>,
    ) -> CallbackResult {
        jac.set(0, 0, -1.0 - cj);
        jac.set(0, 1, 1.0);
        jac.set(1, 0, 1.0);
        jac.set(1, 1, 1.0);
        Ok(())
    }
}

const LINEAR2_Y0: [f64; 2] = [1.0, -1.0];
const LINEAR2_YP0: [f64; 2] = [-2.0, 3.0];

/// IDA on `system` (two unknowns: the linear DAE, a wrapper of it, or a broken one) from
/// the linear DAE's consistent start (LINEAR2_Y0, LINEAR2_YP0) at t = 0.
fn linear2_start<S: DaeSystem>(system: S, linear: IdaLinearSolver, options: &IdaOptions) -> Ida<S> {
    Ida::new(system, 0.0, &LINEAR2_Y0, &LINEAR2_YP0, linear, options).unwrap()
}

/// Max error over both components at t = 1, scaled by max |y(1)|.
fn linear2_error_at_1(linear: IdaLinearSolver, options: &IdaOptions) -> (f64, IdaStats) {
    let mut ida = linear2_start(Linear2::default(), linear, options);
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    assert_eq!(ida.advance_to(1.0, &mut y, &mut yp).unwrap(), 1.0);
    assert_eq!(
        ida.stats().residual_evaluations,
        ida.system().residual_calls
    );
    let exact = Linear2::exact(1.0);
    let scale = exact[0].abs().max(exact[1].abs());
    let err = (y[0] - exact[0]).abs().max((y[1] - exact[1]).abs()) / scale;
    (err, ida.stats())
}

#[test]
fn linear_dae_error_falls_with_the_tolerance() {
    for linear in [
        IdaLinearSolver::Custom,
        IdaLinearSolver::Dense {
            user_jacobian: true,
        },
    ] {
        let mut errors = Vec::new();
        for rtol in [1e-4, 1e-6, 1e-8] {
            let options = IdaOptions {
                rtol,
                atol: rtol * 1e-2,
                ..Default::default()
            };
            let (err, s) = linear2_error_at_1(linear.clone(), &options);
            eprintln!(
                "{linear:?} rtol {rtol:e}: error {err:.2e}, {} steps",
                s.steps
            );
            // Global error of a few rtol.
            assert!(
                err < 10.0 * rtol,
                "{linear:?} rtol {rtol:e}: relative error {err:e}"
            );
            errors.push(err);
        }
        // 100× tighter tolerances cut the error at least 10× each time.
        assert!(
            errors[1] < errors[0] / 10.0 && errors[2] < errors[1] / 10.0,
            "{linear:?}: errors {errors:?}"
        );
    }
}
