//! IDA: failures: recoverable and fatal residuals, panicking callbacks, too much work, a
//! Jacobian outside its band.

use super::calc_ic::NoMaterialLaw;
use super::*;

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
