//! KINSOL through the safe layer: the same roots with every linear solver, typed errors for
//! failing and panicking callbacks, non-convergence, and many create/drop cycles.

use crate::sundials_support::*;

use eyeshell_sundials::{
    klu_available, CallbackError, CallbackResult, JacobianMatrix, Kinsol, KinsolOptions,
    LinearSolverSpec, MatrixSink, NonlinearSystem, Strategy, SundialsError,
};

/// F = (10 (u1 - u0²), 1 - u0): Rosenbrock's valley as a root problem, root (1, 1).
struct Rosenbrock;

impl NonlinearSystem for Rosenbrock {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        f[0] = 10.0 * (u[1] - u[0] * u[0]);
        f[1] = 1.0 - u[0];
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        jac.set(0, 0, -20.0 * u[0]);
        jac.set(0, 1, 10.0);
        jac.set(1, 0, -1.0);
        Ok(())
    }
}

/// Bratu's problem on n interior nodes: (u[i-1] - 2u[i] + u[i+1]) / h² + λ exp(u[i]) = 0.
struct Bratu {
    n: usize,
    lambda: f64,
}

impl Bratu {
    fn h2(&self) -> f64 {
        (1.0 / (self.n as f64 + 1.0)).powi(2)
    }
}

impl NonlinearSystem for Bratu {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        let h2 = self.h2();
        for i in 0..self.n {
            let left = if i > 0 { u[i - 1] } else { 0.0 };
            let right = if i + 1 < self.n { u[i + 1] } else { 0.0 };
            f[i] = (left - 2.0 * u[i] + right) / h2 + self.lambda * u[i].exp();
        }
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        let h2 = self.h2();
        for i in 0..self.n {
            if i > 0 {
                jac.set(i, i - 1, 1.0 / h2);
            }
            jac.set(i, i, -2.0 / h2 + self.lambda * u[i].exp());
            if i + 1 < self.n {
                jac.set(i, i + 1, 1.0 / h2);
            }
        }
        Ok(())
    }
}

#[test]
fn rosenbrock_same_root_with_every_solver() {
    for (name, spec) in specs(2, 1, 1) {
        let mut kin = Kinsol::new(Rosenbrock, 2, spec, &tight()).unwrap();
        let mut u = [-1.2, 1.0];
        let stats = kin
            .solve(&mut u, &[1.0; 2], &[1.0; 2])
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(max_diff(&u, &[1.0, 1.0]) < 1e-12, "{name}: {u:?}");
        assert!(
            stats.iterations > 0 && stats.jacobian_evaluations > 0,
            "{name}: {stats:?}"
        );
        assert!(stats.fnorm <= 1e-11, "{name}: {stats:?}");
    }
}

#[test]
fn bratu_200_same_root_with_every_solver() {
    let n = 200;
    let mut roots: Vec<(&str, Vec<f64>)> = Vec::new();
    for (name, spec) in specs(n, 1, 1) {
        let mut kin = Kinsol::new(Bratu { n, lambda: 1.0 }, n, spec, &tight()).unwrap();
        let mut u = vec![0.0; n];
        let stats = kin
            .solve(&mut u, &vec![1.0; n], &vec![1.0; n])
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(stats.iterations >= 2, "{name}: {stats:?}");
        // The lower branch of Bratu (λ = 1) peaks at about 0.1405 in the middle.
        let peak = u.iter().cloned().fold(f64::MIN, f64::max);
        assert!((peak - 0.1405).abs() < 1e-3, "{name}: peak {peak}");
        roots.push((name, u));
    }
    for (name, u) in &roots[1..] {
        let d = max_diff(u, &roots[0].1);
        assert!(d < 1e-12, "{name} differs from {} by {d:e}", roots[0].0);
    }
    assert_eq!(roots.len(), if klu_available() { 3 } else { 2 });
}

#[test]
fn stats_are_per_solve_and_options_can_change() {
    let mut kin = Kinsol::new(Rosenbrock, 2, LinearSolverSpec::Dense, &tight()).unwrap();
    let mut u = [-1.2, 1.0];
    let first = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap();
    let mut u = [-1.2, 1.0];
    let second = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap();
    assert_eq!(first, second);
    assert_eq!(kin.last_stats(), second);
    // A full Newton step with a Jacobian kept for up to 10 iterations still gets there.
    kin.set_options(&KinsolOptions {
        strategy: Strategy::Newton,
        max_setup_calls: 10,
        ..tight()
    })
    .unwrap();
    let mut u = [-1.2, 1.0];
    let stats = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap();
    assert!(max_diff(&u, &[1.0, 1.0]) < 1e-10, "{u:?} {stats:?}");
    assert!(kin
        .set_options(&KinsolOptions {
            fnorm_tol: -1.0,
            ..tight()
        })
        .is_err());
}

/// F(u) = u² + 1 has no real root.
struct NoRoot {
    seen: Vec<f64>,
}

impl NonlinearSystem for NoRoot {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        self.seen.push(u[0]);
        f[0] = u[0] * u[0] + 1.0;
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        jac.set(0, 0, 2.0 * u[0]);
        Ok(())
    }
}

#[test]
fn no_root_gives_a_named_flag_and_the_last_iterate() {
    let mut kin = Kinsol::new(
        NoRoot { seen: vec![] },
        1,
        LinearSolverSpec::Dense,
        &tight(),
    )
    .unwrap();
    let mut u = [0.7];
    let err = kin.solve(&mut u, &[1.0], &[1.0]).unwrap_err();
    let SundialsError::Flag {
        function,
        flag,
        name,
        ..
    } = &err
    else {
        panic!("expected a Flag error, got {err:?}");
    };
    assert_eq!(*function, "KINSol");
    assert!(*flag < 0);
    assert!(name.starts_with("KIN_"), "{name}");
    let text = err.to_string();
    assert!(text.contains(name) && !text.contains('\n'), "{text}");
    // u holds KINSOL's last iterate: a point the residual was evaluated at, not the guess.
    assert!(u[0].is_finite() && u[0] != 0.7);
    assert!(
        kin.system().seen.contains(&u[0]),
        "{} not among evaluated points",
        u[0]
    );
    assert!(kin.last_stats().iterations > 0, "{:?}", kin.last_stats());
    eprintln!("no-root error: {text}");
}

#[test]
fn max_iterations_is_reported_by_name() {
    let opts = KinsolOptions {
        max_iterations: 3,
        strategy: Strategy::Newton,
        ..tight()
    };
    let mut kin = Kinsol::new(NoRoot { seen: vec![] }, 1, LinearSolverSpec::Dense, &opts).unwrap();
    let mut u = [0.7];
    let err = kin.solve(&mut u, &[1.0], &[1.0]).unwrap_err();
    assert!(
        matches!(
            err,
            SundialsError::Flag {
                name: "KIN_MAXITER_REACHED" | "KIN_MXNEWT_5X_EXCEEDED",
                ..
            }
        ),
        "{err}"
    );
    assert_eq!(kin.last_stats().iterations, 3);
}

/// Rosenbrock whose residual or Jacobian misbehaves on the k-th call.
struct Faulty {
    calls: usize,
    fail_at: usize,
    mode: Mode,
}

#[derive(Clone, Copy)]
enum Mode {
    ResidualPanics,
    JacobianPanics,
    ResidualFatal,
}

impl NonlinearSystem for Faulty {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        self.calls += 1;
        if self.calls == self.fail_at {
            match self.mode {
                Mode::ResidualPanics => panic!("boom in residual at call {}", self.calls),
                Mode::ResidualFatal => {
                    return Err(CallbackError::Fatal("thickness went negative".into()))
                }
                Mode::JacobianPanics => {}
            }
        }
        Rosenbrock.residual(u, f)
    }

    fn jacobian(&mut self, u: &[f64], jac: JacobianMatrix<'_>) -> CallbackResult {
        if let Mode::JacobianPanics = self.mode {
            let v: Vec<f64> = Vec::new();
            let _ = v[u.len()]; // index out of bounds
        }
        Rosenbrock.jacobian(u, jac)
    }
}

#[test]
fn panicking_residual_is_a_callback_error_not_an_abort() {
    for (name, spec) in specs(2, 1, 1) {
        let sys = Faulty {
            calls: 0,
            fail_at: 3,
            mode: Mode::ResidualPanics,
        };
        let mut kin = Kinsol::new(sys, 2, spec, &tight()).unwrap();
        let mut u = [-1.2, 1.0];
        let err = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap_err();
        match &err {
            SundialsError::Callback(m) => {
                assert!(
                    m.contains("residual panicked: boom in residual at call 3"),
                    "{name}: {m}"
                );
                assert!(m.contains("KIN_"), "{name}: {m}");
            }
            other => panic!("{name}: expected Callback, got {other:?}"),
        }
        // The solver is still usable after a caught panic.
        kin.system_mut().fail_at = usize::MAX;
        let mut u = [-1.2, 1.0];
        kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap();
        assert!(max_diff(&u, &[1.0, 1.0]) < 1e-12);
    }
}

#[test]
fn panicking_jacobian_is_a_callback_error() {
    let sys = Faulty {
        calls: 0,
        fail_at: 0,
        mode: Mode::JacobianPanics,
    };
    let mut kin = Kinsol::new(
        sys,
        2,
        LinearSolverSpec::Band { upper: 1, lower: 1 },
        &tight(),
    )
    .unwrap();
    let mut u = [-1.2, 1.0];
    let err = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap_err();
    let SundialsError::Callback(m) = &err else {
        panic!("expected Callback, got {err:?}")
    };
    assert!(
        m.contains("jacobian panicked") && m.contains("index out of bounds"),
        "{m}"
    );
}

#[test]
fn fatal_residual_is_a_callback_error() {
    let sys = Faulty {
        calls: 0,
        fail_at: 2,
        mode: Mode::ResidualFatal,
    };
    let mut kin = Kinsol::new(sys, 2, LinearSolverSpec::Dense, &tight()).unwrap();
    let mut u = [-1.2, 1.0];
    let err = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap_err();
    let SundialsError::Callback(m) = &err else {
        panic!("expected Callback, got {err:?}")
    };
    assert!(m.contains("residual: thickness went negative"), "{m}");
    assert!(!err.to_string().contains('\n'));
}

/// F(u) = ln u - 1 (root e); ln is undefined for u ≤ 0, reported as recoverable.
struct Log {
    failures: usize,
}

impl NonlinearSystem for Log {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        if u[0] <= 0.0 {
            self.failures += 1;
            return Err(CallbackError::Recoverable(format!(
                "ln({}) undefined",
                u[0]
            )));
        }
        f[0] = u[0].ln() - 1.0;
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        jac.set(0, 0, 1.0 / u[0]);
        Ok(())
    }
}

#[test]
fn recoverable_residual_error_lets_kinsol_shorten_the_step() {
    // From u = 20 the first Newton step lands at about -19.9, where ln fails recoverably.
    for strategy in [Strategy::Newton, Strategy::LineSearch] {
        let mut kin = Kinsol::new(
            Log { failures: 0 },
            1,
            LinearSolverSpec::Dense,
            &KinsolOptions {
                strategy,
                ..tight()
            },
        )
        .unwrap();
        let mut u = [20.0];
        let stats = kin.solve(&mut u, &[1.0], &[1.0]).unwrap();
        assert!(
            (u[0] - std::f64::consts::E).abs() < 1e-10,
            "{strategy:?}: {u:?} {stats:?}"
        );
        assert!(
            kin.system().failures >= 1,
            "{strategy:?}: the bad step was never tried"
        );
    }
}

/// Writes one Jacobian entry outside the band.
struct OutsideBand;

impl NonlinearSystem for OutsideBand {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        f.iter_mut().zip(u).for_each(|(f, u)| *f = u - 1.0);
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        for i in 0..u.len() {
            jac.set(i, i, 1.0);
        }
        jac.set(0, u.len() - 1, 0.0); // not in a tridiagonal band
        Ok(())
    }
}

#[test]
fn jacobian_entry_outside_the_structure_is_an_error() {
    let n = 5;
    let (row_ptr, col_idx) = band_pattern(n, 1, 1);
    let mut cases = vec![LinearSolverSpec::Band { upper: 1, lower: 1 }];
    if klu_available() {
        cases.push(LinearSolverSpec::Klu { row_ptr, col_idx });
    }
    for spec in cases {
        let mut kin = Kinsol::new(OutsideBand, n, spec, &tight()).unwrap();
        let mut u = vec![0.0; n];
        let err = kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n]).unwrap_err();
        // Release builds count the stray write; debug builds panic in a debug_assert.
        let SundialsError::Callback(m) = &err else {
            panic!("expected Callback, got {err:?}")
        };
        assert!(m.contains("outside"), "{m}");
    }
}

#[test]
fn bad_arguments_are_invalid_errors() {
    let mut kin = Kinsol::new(Rosenbrock, 2, LinearSolverSpec::Dense, &tight()).unwrap();
    let mut u = [0.0; 3];
    assert!(matches!(
        kin.solve(&mut u, &[1.0; 3], &[1.0; 3]),
        Err(SundialsError::Invalid(_))
    ));
    let mut u = [0.0; 2];
    assert!(matches!(
        kin.solve(&mut u, &[1.0, 0.0], &[1.0; 2]),
        Err(SundialsError::Invalid(_))
    ));
    let bad = LinearSolverSpec::Klu {
        row_ptr: vec![0, 2, 1],
        col_idx: vec![0, 1],
    };
    assert!(Kinsol::new(Rosenbrock, 2, bad, &tight()).is_err());
    assert!(Kinsol::new(Rosenbrock, 0, LinearSolverSpec::Dense, &tight()).is_err());
}

#[test]
fn klu_unavailable_is_reported_when_not_built() {
    let spec = LinearSolverSpec::Klu {
        row_ptr: vec![0, 1, 2],
        col_idx: vec![0, 1],
    };
    let result = Kinsol::new(Rosenbrock, 2, spec, &tight());
    if klu_available() {
        assert!(result.is_ok());
    } else {
        assert!(matches!(result, Err(SundialsError::KluUnavailable)));
    }
}

#[test]
fn many_solvers_created_and_dropped() {
    let n = 50;
    for round in 0..300 {
        for (name, spec) in specs(n, 1, 1) {
            let mut kin = Kinsol::new(Bratu { n, lambda: 1.0 }, n, spec, &tight()).unwrap();
            if round % 3 == 0 {
                let mut u = vec![0.0; n];
                kin.solve(&mut u, &vec![1.0; n], &vec![1.0; n])
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
            }
            // Dropping here frees KINSOL, then the linear solver, matrix, vectors, context.
        }
        // And one that fails, so that drop follows an error path.
        let mut kin = Kinsol::new(
            NoRoot { seen: vec![] },
            1,
            LinearSolverSpec::Dense,
            &tight(),
        )
        .unwrap();
        assert!(kin.solve(&mut [0.5], &[1.0], &[1.0]).is_err());
    }
}
