//! IDA: dense output, stop time, reinit, options, arguments refused, create/drop.

use super::*;

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
