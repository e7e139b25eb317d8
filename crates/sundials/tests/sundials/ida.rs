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

// ---------------------------------------------------------------------------------------
// Consistent initial conditions, suppressed algebraic error test

#[test]
fn calc_ic_makes_robertson_consistent() {
    for linear in [
        IdaLinearSolver::Custom,
        IdaLinearSolver::Dense {
            user_jacobian: true,
        },
        IdaLinearSolver::Dense {
            user_jacobian: false,
        },
    ] {
        // y3 wrong (the constraint says 0), y' all zero.
        let (mut y, mut yp) = ([1.0, 0.0, 0.3], [0.0; 3]);
        let mut ida = Ida::new(
            RobertsonDae::default(),
            0.0,
            &y,
            &yp,
            linear.clone(),
            &robertson_options(),
        )
        .unwrap();
        ida.calc_ic(0.4, &mut y, &mut yp)
            .unwrap_or_else(|e| panic!("{linear:?}: {e}"));
        assert_eq!(
            (y[0], y[1]),
            (1.0, 0.0),
            "{linear:?}: the differential components of y are kept"
        );
        assert!(y[2].abs() < 1e-10, "{linear:?}: y3 = {:e}", y[2]);
        // IDACalcIC stops its Newton iteration at 0.0033 in the rtol-weighted norm
        // (IDASetNonlinConvCoefIC's default), so y' is right to within rtol = 1e-4 relative,
        // not to round-off: observed 1.5e-9 absolute with an analytic M, 1.2e-6 in y2' with
        // difference quotients, whose increment for y2 = 0 is atol = 1e-6 (see
        // robertson_with_difference_quotients_agrees_with_the_reference).
        let tol = robertson_options().rtol * 0.04;
        assert!(
            (yp[0] + 0.04).abs() < tol && (yp[1] - 0.04).abs() < tol,
            "{linear:?}: y' = {yp:?}"
        );
        assert_eq!(
            yp[2], 0.0,
            "{linear:?}: the algebraic component of y' is left alone"
        );
        let mut r = [0.0; 3];
        RobertsonDae::f(&y, &yp, &mut r);
        assert!(
            r.iter().all(|v| v.abs() < tol) && r[2].abs() < 1e-10,
            "{linear:?}: F(0, y, y') = {r:?}"
        );
        // And the run from there matches the one from the consistent state.
        let mut y04 = [0.0; 3];
        ida.advance_to(0.4, &mut y04, &mut yp).unwrap();
        assert!(
            (y04[0] - 0.98517).abs() < 2e-5,
            "{linear:?}: y(0.4) = {y04:?}"
        );
        if linear == IdaLinearSolver::Custom {
            assert!(ida.system().own.setups >= 1);
        }
    }
}

#[test]
fn calc_ic_on_the_linear_dae_then_suppressed_algebraic_error_test() {
    let options = IdaOptions {
        rtol: 1e-8,
        atol: 1e-10,
        id: Some(vec![1.0, 0.0]),
        suppress_algebraic: true,
        ..Default::default()
    };
    // The algebraic y2 far off, y' zero.
    let (mut y, mut yp) = ([1.0, 42.0], [0.0, 0.0]);
    let mut ida = Ida::new(
        Linear2::default(),
        0.0,
        &y,
        &yp,
        IdaLinearSolver::Custom,
        &options,
    )
    .unwrap();
    ida.calc_ic(1.0, &mut y, &mut yp).unwrap();
    assert_eq!(y[0], 1.0);
    // To a fraction of rtol = 1e-8 (see calc_ic_makes_robertson_consistent; observed 1.6e-11).
    assert!((y[1] + 1.0).abs() < 1e-9, "y2(0) = {}", y[1]);
    assert!((yp[0] + 2.0).abs() < 1e-8, "y1'(0) = {}", yp[0]);
    let mut r = [0.0; 2];
    Linear2::f(0.0, &y, &yp, &mut r);
    assert!(r.iter().all(|v| v.abs() < 1e-8), "F(0, y, y') = {r:?}");
    let s = ida.stats();
    assert!(
        s.residual_evaluations >= 2 && s.jacobian_evaluations >= 1 && s.steps == 0,
        "IDACalcIC did the work: {s:?}"
    );

    // Integrate with the algebraic component out of the error test: still accurate, since
    // y2 is fixed by y1 through the constraint.
    let mut ypo = [0.0; 2];
    ida.advance_to(1.0, &mut y, &mut ypo).unwrap();
    let exact = Linear2::exact(1.0);
    assert!(
        (y[0] - exact[0]).abs() < 1e-7 && (y[1] - exact[1]).abs() < 1e-7,
        "y(1) = {y:?}, exact {exact:?}"
    );
    let suppressed = ida.stats().steps;
    let plain = linear2_error_at_1(
        IdaLinearSolver::Custom,
        &IdaOptions {
            suppress_algebraic: false,
            ..options.clone()
        },
    )
    .1
    .steps;
    assert!(
        suppressed <= plain,
        "suppressing the algebraic error test cannot add steps: {suppressed} vs {plain}"
    );

    // calc_ic only before the first step, and only with id.
    let e = ida.calc_ic(2.0, &mut y, &mut yp).unwrap_err();
    assert!(
        matches!(&e, SundialsError::Invalid(m) if m.contains("before the first step")),
        "{e}"
    );
    let no_id = IdaOptions::default();
    let mut ida = linear2_start(Linear2::default(), IdaLinearSolver::Custom, &no_id);
    let e = ida.calc_ic(1.0, &mut y, &mut yp).unwrap_err();
    assert!(
        matches!(&e, SundialsError::Invalid(m) if m.contains("options.id")),
        "{e}"
    );
}

/// A DAE whose residual always fails (Fatal), of any size.
struct NoMaterialLaw;

impl DaeSystem for NoMaterialLaw {
    fn residual(&mut self, _t: f64, _y: &[f64], _yp: &[f64], _r: &mut [f64]) -> CallbackResult {
        Err(CallbackError::Fatal("no material law".into()))
    }
}

#[test]
fn calc_ic_reports_a_failing_residual() {
    let options = IdaOptions {
        id: Some(vec![1.0]),
        ..Default::default()
    };
    let (mut y, mut yp) = ([1.0], [0.0]);
    let mut ida = Ida::new(
        NoMaterialLaw,
        0.0,
        &y,
        &yp,
        IdaLinearSolver::Dense {
            user_jacobian: false,
        },
        &options,
    )
    .unwrap();
    let e = ida.calc_ic(1.0, &mut y, &mut yp).unwrap_err();
    let SundialsError::Callback(m) = &e else {
        panic!("expected a callback error, got {e}")
    };
    assert!(
        m.starts_with("residual: no material law (IDACalcIC stopped with IDA_RES_FAIL at t = 0e0)"),
        "{m}"
    );
}

// ---------------------------------------------------------------------------------------
// Failures

/// The linear DAE, refusing (Recoverable) the first `refuse` residual calls with t in
/// [0.5, 0.6], like a model whose state leaves its domain there until the step is cut.
struct Refuses {
    inner: Linear2,
    refuse: usize,
    refusals: usize,
}

impl DaeSystem for Refuses {
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        if (0.5..=0.6).contains(&t) && self.refusals < self.refuse {
            self.refusals += 1;
            return Err(CallbackError::Recoverable(format!("t = {t} refused")));
        }
        self.inner.residual(t, y, yp, r)
    }

    fn linear_setup(
        &mut self,
        t: f64,
        cj: f64,
        y: &[f64],
        yp: &[f64],
        r: &[f64],
    ) -> CallbackResult {
        self.inner.linear_setup(t, cj, y, yp, r)
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.inner.linear_solve(b, x)
    }
}

#[test]
fn recoverable_residual_error_is_retried_and_the_run_completes() {
    let options = IdaOptions {
        rtol: 1e-8,
        atol: 1e-10,
        ..Default::default()
    };
    let system = Refuses {
        inner: Linear2::default(),
        refuse: 5,
        refusals: 0,
    };
    let mut ida = linear2_start(system, IdaLinearSolver::Custom, &options);
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    assert_eq!(ida.advance_to(1.0, &mut y, &mut yp).unwrap(), 1.0);
    let exact = Linear2::exact(1.0);
    assert!(
        (y[0] - exact[0]).abs() < 1e-7 && (y[1] - exact[1]).abs() < 1e-7,
        "y(1) = {y:?}, exact {exact:?}"
    );
    let s = ida.stats();
    assert_eq!(ida.system().refusals, 5, "{s:?}");
    assert!(
        s.nonlinear_convergence_failures >= 1,
        "refusals are Newton failures: {s:?}"
    );
}

#[test]
fn always_recoverable_residual_gives_a_named_flag() {
    let options = IdaOptions::default();
    let system = Refuses {
        inner: Linear2::default(),
        refuse: usize::MAX,
        refusals: 0,
    };
    let mut ida = linear2_start(system, IdaLinearSolver::Custom, &options);
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    let e = ida.advance_to(1.0, &mut y, &mut yp).unwrap_err();
    let (function, _, name, _) = flag_parts(&e);
    assert_eq!(function, "IDASolve");
    // IDA cuts the step at each refusal and then creeps towards 0.5 with ever smaller steps,
    // so it may run out of steps before it runs out of convergence failures.
    assert!(
        ["IDA_REP_RES_ERR", "IDA_CONV_FAIL", "IDA_TOO_MUCH_WORK"].contains(&name),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("last recoverable callback error: residual: t = "),
        "{e}"
    );
    assert!(!e.to_string().contains('\n'));
    let t = ida.stats().current_time;
    assert!(t > 0.4 && t < 0.5, "current time {t}");
    eprintln!("always refusing: {e}");
    let exact = Linear2::exact(t);
    assert!(
        (y[0] - exact[0]).abs() < 1e-5,
        "y holds the state at the last step: {y:?} vs {exact:?} at {t}"
    );
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Where {
    Residual,
    LinearSetup,
    LinearSolve,
    Jacobian,
}

/// The linear DAE, failing (Fatal or panic) in one callback once t > 0.5 (linear_solve has
/// no t: it uses that of the residual evaluation before it).
struct Breaks {
    inner: Linear2,
    at: Where,
    panic: bool,
    t: f64,
    failed_at: Option<f64>,
}

impl Breaks {
    fn new(at: Where, panic: bool) -> Self {
        Breaks {
            inner: Linear2::default(),
            at,
            panic,
            t: 0.0,
            failed_at: None,
        }
    }

    fn maybe_fail(&mut self, here: Where) -> CallbackResult {
        if here != self.at || self.t <= 0.5 {
            return Ok(());
        }
        self.failed_at.get_or_insert(self.t);
        if self.panic {
            panic!("{here:?} bug at t = {}", self.t);
        }
        Err(CallbackError::Fatal(format!(
            "{here:?} gave up at t = {}",
            self.t
        )))
    }
}

impl DaeSystem for Breaks {
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        self.t = t;
        self.maybe_fail(Where::Residual)?;
        self.inner.residual(t, y, yp, r)
    }

    fn linear_setup(
        &mut self,
        t: f64,
        cj: f64,
        y: &[f64],
        yp: &[f64],
        r: &[f64],
    ) -> CallbackResult {
        self.t = t;
        self.maybe_fail(Where::LinearSetup)?;
        self.inner.linear_setup(t, cj, y, yp, r)
    }

    fn linear_solve(&mut self, b: &[f64], x: &mut [f64]) -> CallbackResult {
        self.maybe_fail(Where::LinearSolve)?;
        self.inner.linear_solve(b, x)
    }

    fn jacobian(
        &mut self,
        t: f64,
        cj: f64,
        y: &[f64],
        yp: &[f64],
        r: &[f64],
        jac: JacobianMatrix<'_>,
    ) -> CallbackResult {
        self.t = t;
        self.maybe_fail(Where::Jacobian)?;
        self.inner.jacobian(t, cj, y, yp, r, jac)
    }
}

#[test]
fn fatal_and_panicking_callbacks_stop_the_run_with_name_and_time() {
    let options = IdaOptions {
        rtol: 1e-6,
        ..Default::default()
    };
    let cases = [
        (
            Where::Residual,
            IdaLinearSolver::Custom,
            "residual",
            "IDA_RES_FAIL",
        ),
        (
            Where::LinearSetup,
            IdaLinearSolver::Custom,
            "linear_setup",
            "IDA_LSETUP_FAIL",
        ),
        (
            Where::LinearSolve,
            IdaLinearSolver::Custom,
            "linear_solve",
            "IDA_LSOLVE_FAIL",
        ),
        (
            Where::Jacobian,
            IdaLinearSolver::Dense {
                user_jacobian: true,
            },
            "jacobian",
            "IDA_LSETUP_FAIL",
        ),
        (
            Where::Residual,
            IdaLinearSolver::Band {
                upper: 1,
                lower: 1,
                user_jacobian: false,
            },
            "residual",
            "IDA_RES_FAIL",
        ),
    ];
    for (at, linear, callback, flag) in cases {
        for panic in [false, true] {
            let mut ida = linear2_start(Breaks::new(at, panic), linear.clone(), &options);
            let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
            let e = ida.advance_to(2.0, &mut y, &mut yp).unwrap_err();
            let SundialsError::Callback(m) = &e else {
                panic!("{at:?} {linear:?}: expected a callback error, got {e}")
            };
            let failed_at = ida.system().failed_at.expect("the callback failed");
            let what = if panic {
                format!("{callback} panicked: {at:?} bug at t = {failed_at}")
            } else {
                format!("{callback}: {at:?} gave up at t = {failed_at}")
            };
            let t = ida.stats().current_time;
            assert_eq!(
                *m,
                format!("{what} (IDASolve stopped with {flag} at t = {t:e})"),
                "{at:?} panic {panic}"
            );
            // IDA stops at the first failure, in the attempt of the step beyond current_time.
            assert!(
                failed_at > 0.5 && t < failed_at && t > 0.2,
                "{at:?} panic {panic}: failed at {failed_at}, current time {t}"
            );
            let exact = Linear2::exact(t);
            assert!(
                (y[0] - exact[0]).abs() < 1e-5,
                "{at:?}: y holds the state at the last step: {y:?} vs {exact:?}"
            );
        }
    }
}

#[test]
fn failure_in_the_first_step_leaves_the_initial_state() {
    let dense = IdaLinearSolver::Dense {
        user_jacobian: false,
    };
    let mut ida = linear2_start(NoMaterialLaw, dense, &IdaOptions::default());
    let (mut y, mut yp) = ([f64::NAN; 2], [f64::NAN; 2]);
    let e = ida.advance_to(1.0, &mut y, &mut yp).unwrap_err();
    assert_eq!(e.to_string(), "callback failed: residual: no material law (IDASolve stopped with IDA_RES_FAIL at t = 0e0)");
    // IDA writes y0 back, and y0' as (h y0') / h: equal up to an ulp.
    assert_eq!(y, LINEAR2_Y0);
    assert!(
        (0..2).all(|i| (yp[i] - LINEAR2_YP0[i]).abs() <= 4.0 * f64::EPSILON * LINEAR2_YP0[i].abs()),
        "{yp:?}"
    );
    let s = ida.stats();
    assert_eq!(
        (s.steps, s.residual_evaluations, s.current_time),
        (0, 1, 0.0),
        "{s:?}"
    );
}

#[test]
fn failed_run_leaves_a_usable_solver() {
    let system = Breaks::new(Where::LinearSolve, true);
    let mut ida = linear2_start(system, IdaLinearSolver::Custom, &IdaOptions::default());
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    assert!(ida.advance_to(1.0, &mut y, &mut yp).is_err());
    ida.system_mut().at = Where::Jacobian; // never called with Custom
    ida.reinit(0.0, &LINEAR2_Y0, &LINEAR2_YP0).unwrap();
    assert_eq!(ida.advance_to(1.0, &mut y, &mut yp).unwrap(), 1.0);
    let exact = Linear2::exact(1.0);
    assert!((y[0] - exact[0]).abs() < 1e-5, "{y:?} vs {exact:?}");
}

#[test]
fn band_jacobian_outside_the_band_is_an_error() {
    // Linear2's M is full (2×2); a band with upper = lower = 0 cannot hold it.
    let linear = IdaLinearSolver::Band {
        upper: 0,
        lower: 0,
        user_jacobian: true,
    };
    let mut ida = linear2_start(Linear2::default(), linear, &IdaOptions::default());
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    let e = ida.advance_to(1.0, &mut y, &mut yp).unwrap_err();
    let m = e.to_string();
    // Release builds count the writes; debug builds stop at a debug_assert (a panic).
    assert!(
        m.contains("jacobian") && m.contains("outside") && m.contains("IDA_LSETUP_FAIL"),
        "{m}"
    );
    if cfg!(not(debug_assertions)) {
        assert!(m.contains("2 entries were set outside the structure of the band n=2 (upper 0, lower 0) Jacobian"), "{m}");
    }
}

#[test]
fn too_much_work_is_a_typed_flag_and_y_holds_the_last_step() {
    let options = IdaOptions {
        max_steps: 20,
        ..robertson_options()
    };
    let mut ida = robertson(IdaLinearSolver::Custom, &options);
    let (mut y, mut yp) = ([0.0; 3], [0.0; 3]);
    let e = ida.advance_to(4e10, &mut y, &mut yp).unwrap_err();
    let (function, flag, name, message) = flag_parts(&e);
    assert_eq!(
        (function, flag, name),
        ("IDASolve", -1, "IDA_TOO_MUCH_WORK"),
        "{e}"
    );
    assert!(message.contains("mxstep"), "IDA's own message: {message}");
    let s = ida.stats();
    assert_eq!(s.steps, 20);
    assert!(s.current_time > 0.0 && s.current_time < 4e10);
    // IDA leaves its output vectors alone here in IDA_NORMAL mode; the layer fills them from
    // the last step: y is the state at current_time (where the interpolant is exact).
    let mut yi = [0.0; 3];
    ida.interpolate(s.current_time, &mut yi).unwrap();
    assert_eq!(y, yi);
    assert!(
        y[0] < 1.0 && y[2] > 0.0 && (y.iter().sum::<f64>() - 1.0).abs() < 1e-13,
        "{y:?}"
    );
    let mut r = [0.0; 3];
    RobertsonDae::f(&y, &yp, &mut r);
    assert!(
        r[0].abs() < 1e-4 && r[1].abs() < 1e-4,
        "y' belongs to y: F = {r:?}"
    );
    // Asking again continues for another 20 steps.
    assert!(ida.advance_to(4e10, &mut y, &mut yp).is_err());
    assert_eq!(ida.stats().steps, 40);
}

// ---------------------------------------------------------------------------------------
// Dense output, stop time, reinit, options

#[test]
fn one_step_interpolation_stop_time_and_reinit() {
    let options = IdaOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..Default::default()
    };
    let mut ida = linear2_start(Linear2::default(), IdaLinearSolver::Custom, &options);
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    let mut t = 0.0;
    for _ in 0..30 {
        t = ida.step(1.0, &mut y, &mut yp).unwrap();
    }
    assert!(t > 0.0 && t < 1.0, "30 steps reached {t}");
    let close =
        |a: [f64; 2], b: [f64; 2], tol: f64| (a[0] - b[0]).abs() < tol && (a[1] - b[1]).abs() < tol;
    assert!(
        close(y, Linear2::exact(t), 1e-9) && close(yp, Linear2::exact_derivative(t), 1e-6),
        "{y:?} {yp:?} at {t}"
    );
    let s = ida.stats();
    let h = s.last_step;
    assert!(h > 0.0 && s.current_time == t, "{s:?}");
    let (mut yi, mut ypi) = ([0.0; 2], [0.0; 2]);
    for frac in [0.0, 0.25, 0.5, 1.0] {
        let ti = t - frac * h;
        ida.interpolate(ti, &mut yi).unwrap();
        ida.interpolate_derivative(ti, &mut ypi).unwrap();
        assert!(
            close(yi, Linear2::exact(ti), 1e-9),
            "dense output at {ti}: {yi:?} vs {:?}",
            Linear2::exact(ti)
        );
        assert!(
            close(ypi, Linear2::exact_derivative(ti), 1e-6),
            "y' at {ti}: {ypi:?} vs {:?}",
            Linear2::exact_derivative(ti)
        );
    }
    // Before the last step IDA refuses; beyond its end (which IDA 6.4 would extrapolate to)
    // the layer does.
    for bad in [t - 10.0 * h, t + 10.0 * h, f64::NAN] {
        let e = ida.interpolate(bad, &mut yi).unwrap_err();
        let (function, _, name, _) = flag_parts(&e);
        assert_eq!((function, name), ("IDAGetDky", "IDA_BAD_T"), "{e}");
        assert!(e.to_string().contains("is not between tcur - hu = "), "{e}");
    }
    assert!(matches!(
        ida.interpolate(t, &mut [0.0; 3]),
        Err(SundialsError::Invalid(_))
    ));

    // A stop time ends the integration exactly there.
    ida.set_stop_time(1.5).unwrap();
    assert_eq!(ida.advance_to(2.0, &mut y, &mut yp).unwrap(), 1.5);
    assert!(close(y, Linear2::exact(1.5), 1e-9), "{y:?}");
    assert_eq!(ida.stats().current_time, 1.5);
    // IDA 6.4 forgets a stop time once reached; one behind the current time is refused.
    assert_eq!(ida.advance_to(2.0, &mut y, &mut yp).unwrap(), 2.0);
    let e = ida.set_stop_time(1.0).unwrap_err();
    let (function, _, name, _) = flag_parts(&e);
    assert_eq!((function, name), ("IDASetStopTime", "IDA_ILL_INPUT"), "{e}");
    assert!(
        e.to_string().contains("behind current"),
        "IDA's own message: {e}"
    );

    // Stop time in the options, then reinit: counters restart, same answer.
    let with_stop = IdaOptions {
        stop_time: Some(0.75),
        ..options
    };
    let mut ida = linear2_start(Linear2::default(), IdaLinearSolver::Custom, &with_stop);
    assert_eq!(ida.advance_to(1.0, &mut y, &mut yp).unwrap(), 0.75);
    let first = (y, yp, ida.stats());
    ida.reinit(0.0, &LINEAR2_Y0, &LINEAR2_YP0).unwrap();
    assert_eq!(
        (ida.stats().steps, ida.stats().residual_evaluations),
        (0, 0)
    );
    ida.set_stop_time(0.75).unwrap();
    assert_eq!(ida.advance_to(1.0, &mut y, &mut yp).unwrap(), 0.75);
    assert_eq!(
        (y, yp, ida.stats()),
        first,
        "reinit reproduces the first run, counters included"
    );
    assert!(close(y, Linear2::exact(0.75), 1e-9));
}

#[test]
fn options_reach_ida() {
    let options = IdaOptions {
        max_order: 2,
        // Small enough to pass the first error test (y1'' ≈ 4.8, rtol 1e-6).
        initial_step: Some(1e-4),
        max_step: Some(0.01),
        max_error_test_failures: Some(3),
        max_convergence_failures: Some(3),
        max_nonlinear_iterations: Some(2),
        nonlinear_convergence_coefficient: Some(0.1),
        ..Default::default()
    };
    let dense = IdaLinearSolver::Dense {
        user_jacobian: false,
    };
    let mut ida = linear2_start(Linear2::default(), dense, &options);
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    ida.step(1.0, &mut y, &mut yp).unwrap();
    assert_eq!(ida.stats().last_step, 1e-4, "initial step");
    ida.advance_to(1.0, &mut y, &mut yp).unwrap();
    let s = ida.stats();
    assert!(
        s.last_order <= 2 && s.last_step <= 0.01 + 1e-15 && s.steps >= 100,
        "{s:?}"
    );
    assert!(s.current_step <= 0.01 + 1e-15, "{s:?}");
}

#[test]
fn invalid_arguments_are_refused() {
    let new = |y0: &[f64], yp0: &[f64], o: IdaOptions| {
        Ida::new(
            Linear2::default(),
            0.0,
            y0,
            yp0,
            IdaLinearSolver::Custom,
            &o,
        )
        .err()
    };
    let ok = IdaOptions::default();
    let with_options = |o: IdaOptions| new(&LINEAR2_Y0, &LINEAR2_YP0, o);
    let cases: Vec<(&str, Option<SundialsError>)> = vec![
        ("no unknowns", new(&[], &[], ok.clone())),
        ("yp0 length", new(&[1.0, 2.0], &[0.0], ok.clone())),
        (
            "negative rtol",
            with_options(IdaOptions {
                rtol: -1e-6,
                ..ok.clone()
            }),
        ),
        (
            "NaN atol",
            with_options(IdaOptions {
                atol: f64::NAN,
                ..ok.clone()
            }),
        ),
        (
            "atol_vector length",
            with_options(IdaOptions {
                atol_vector: Some(vec![1e-8]),
                ..ok.clone()
            }),
        ),
        (
            "max_order 0",
            with_options(IdaOptions {
                max_order: 0,
                ..ok.clone()
            }),
        ),
        (
            "max_order 6",
            with_options(IdaOptions {
                max_order: 6,
                ..ok.clone()
            }),
        ),
        (
            "max_steps 0",
            with_options(IdaOptions {
                max_steps: 0,
                ..ok.clone()
            }),
        ),
        (
            "id length",
            with_options(IdaOptions {
                id: Some(vec![1.0]),
                ..ok.clone()
            }),
        ),
        (
            "id 0.5",
            with_options(IdaOptions {
                id: Some(vec![1.0, 0.5]),
                ..ok.clone()
            }),
        ),
        (
            "suppress without id",
            with_options(IdaOptions {
                suppress_algebraic: true,
                ..ok.clone()
            }),
        ),
        (
            "max_step 0",
            with_options(IdaOptions {
                max_step: Some(0.0),
                ..ok.clone()
            }),
        ),
        (
            "max_nonlinear_iterations 0",
            with_options(IdaOptions {
                max_nonlinear_iterations: Some(0),
                ..ok.clone()
            }),
        ),
        (
            "coefficient",
            with_options(IdaOptions {
                nonlinear_convergence_coefficient: Some(-0.1),
                ..ok.clone()
            }),
        ),
    ];
    for (what, e) in cases {
        match e {
            Some(SundialsError::Invalid(m)) => {
                assert!(!m.contains('\n'), "{what}: {m}");
                eprintln!("{what}: {m}");
            }
            other => panic!("{what}: expected Invalid, got {other:?}"),
        }
    }
    let e = with_options(IdaOptions {
        id: Some(vec![1.0, 0.5]),
        ..ok.clone()
    })
    .unwrap();
    assert_eq!(
        e.to_string(),
        "invalid argument: id[1] = 0.5 must be 1.0 (differential) or 0.0 (algebraic)"
    );

    let mut ida = linear2_start(Linear2::default(), IdaLinearSolver::Custom, &ok);
    assert!(matches!(
        ida.advance_to(1.0, &mut [0.0; 2], &mut [0.0; 3]),
        Err(SundialsError::Invalid(_))
    ));
    assert!(matches!(
        ida.advance_to(f64::NAN, &mut [0.0; 2], &mut [0.0; 2]),
        Err(SundialsError::Invalid(_))
    ));
    assert!(matches!(
        ida.reinit(0.0, &[1.0], &[0.0]),
        Err(SundialsError::Invalid(_))
    ));
    // tout = t0 is too close for IDA.
    let e = ida
        .advance_to(0.0, &mut [0.0; 2], &mut [0.0; 2])
        .unwrap_err();
    assert_eq!(flag_parts(&e).2, "IDA_ILL_INPUT", "{e}");
    assert!(e.to_string().contains("too close"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Create/drop

#[test]
fn create_and_drop_many_times_with_every_solver() {
    let kinds = [
        IdaLinearSolver::Custom,
        IdaLinearSolver::Dense {
            user_jacobian: true,
        },
        IdaLinearSolver::Dense {
            user_jacobian: false,
        },
        IdaLinearSolver::Band {
            upper: 1,
            lower: 1,
            user_jacobian: true,
        },
        IdaLinearSolver::Band {
            upper: 1,
            lower: 1,
            user_jacobian: false,
        },
    ];
    let options = IdaOptions {
        rtol: 1e-4,
        atol: 1e-8,
        id: Some(vec![1.0, 0.0]),
        ..Default::default()
    };
    let (mut y, mut yp) = ([0.0; 2], [0.0; 2]);
    for linear in kinds {
        for k in 0..300 {
            let mut ida = linear2_start(Linear2::default(), linear.clone(), &options);
            match k % 3 {
                // A third never run: dropping an unused solver must be fine too.
                0 => {}
                1 => {
                    ida.advance_to(0.1, &mut y, &mut yp).unwrap();
                    assert!((y[0] - Linear2::exact(0.1)[0]).abs() < 1e-4);
                }
                _ => {
                    let (mut y0, mut yp0) = ([1.0, 0.0], [0.0; 2]);
                    ida.calc_ic(0.1, &mut y0, &mut yp0).unwrap();
                    assert!((y0[1] + 1.0).abs() < 1e-8);
                }
            }
        }
    }
}

/// The weighted local errors of the last step pass IDA's own error test (their WRMS norm
/// is at most 1) and are not all zero.
#[test]
fn weighted_local_errors_pass_the_error_test() {
    let options = robertson_options();
    let (_, ida) = run_robertson(IdaLinearSolver::Custom, &options, 3);
    let mut e = [0.0; 3];
    ida.weighted_local_errors(&mut e).unwrap();
    let wrms = (e.iter().map(|x| x * x).sum::<f64>() / 3.0).sqrt();
    assert!(
        e.iter().all(|x| x.is_finite()) && wrms > 0.0 && wrms <= 1.0,
        "{e:?}: WRMS {wrms}"
    );
    assert!(ida.weighted_local_errors(&mut [0.0; 2]).is_err());
}
