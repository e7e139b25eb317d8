//! IDA: consistent initial conditions (IDACalcIC) and the suppressed algebraic error test.

use super::*;

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
pub(super) struct NoMaterialLaw;

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
