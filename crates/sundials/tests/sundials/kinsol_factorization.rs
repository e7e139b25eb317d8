//! `Kinsol::solve_with_last_factorization`: after a solve, J x = b with the factorisation of
//! KINSOL's last Jacobian setup, for dense, band and KLU; Invalid before any setup and after
//! a failed one.

use crate::sundials_support::*;

use eyeshell_sundials::{
    CallbackError, CallbackResult, JacobianMatrix, Kinsol, KinsolOptions, MatrixSink,
    NonlinearSystem, Strategy, SundialsError,
};
use nalgebra::{DMatrix, DVector};

/// Exact Newton: a fresh Jacobian (and factorisation) at every iteration.
fn exact_newton() -> KinsolOptions {
    KinsolOptions {
        strategy: Strategy::Newton,
        fnorm_tol: 1e-12,
        max_iterations: 50,
        ..tight()
    }
}

/// A deterministic pseudo-random vector in [-1, 1].
fn pseudo_random(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

// ---------------------------------------------------------------------------------------

const N: usize = 30;

/// F(u) = A u − c with a nonsymmetric tridiagonal A (bandwidths 1, 2 to exercise the band
/// layout): J = A everywhere.
struct Linear {
    c: Vec<f64>,
}

fn linear_a(i: usize, j: usize) -> f64 {
    match j as isize - i as isize {
        0 => 4.0 + 0.1 * i as f64,
        1 => -1.0 - 0.01 * i as f64,
        -1 => -1.5,
        -2 => 0.25,
        _ => 0.0,
    }
}

fn linear_times(v: &[f64]) -> Vec<f64> {
    (0..N)
        .map(|i| {
            (i.saturating_sub(2)..(i + 2).min(N))
                .map(|j| linear_a(i, j) * v[j])
                .sum()
        })
        .collect()
}

impl NonlinearSystem for Linear {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        let au = linear_times(u);
        for i in 0..N {
            f[i] = au[i] - self.c[i];
        }
        Ok(())
    }

    fn jacobian(&mut self, _u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        for i in 0..N {
            for j in i.saturating_sub(2)..(i + 2).min(N) {
                jac.set(i, j, linear_a(i, j));
            }
        }
        Ok(())
    }
}

#[test]
fn linear_system_inverse_jacobian_gives_unit_vectors() {
    for (name, spec) in specs(N, 1, 2) {
        let c = pseudo_random(N, 1);
        let mut kin = Kinsol::new(Linear { c }, N, spec, &exact_newton()).unwrap();
        let mut u = vec![0.0; N];
        let ones = vec![1.0; N];
        kin.solve(&mut u, &ones, &ones)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut x = vec![0.0; N];
        for k in 0..N {
            let mut e = vec![0.0; N];
            e[k] = 1.0;
            let b = linear_times(&e);
            kin.solve_with_last_factorization(&mut x, &b).unwrap();
            let err = x
                .iter()
                .zip(&e)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                err < 1e-12,
                "{name}: J⁻¹ J e_{k} differs from e_{k} by {err:e}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------

/// Bratu-like: (u[i−1] − 2u[i] + u[i+1]) / h² + λ exp(u[i]) + 0.3 u[i+1]² = 0, with the
/// Jacobian's evaluation points recorded (the last one is where KINSOL last factorised).
struct Nonlinear {
    lambda: f64,
    setups_at: Vec<Vec<f64>>,
    fail_jacobian: bool,
}

impl Nonlinear {
    fn new() -> Self {
        Nonlinear {
            lambda: 1.5,
            setups_at: Vec::new(),
            fail_jacobian: false,
        }
    }

    fn h2() -> f64 {
        (1.0 / (N as f64 + 1.0)).powi(2)
    }

    /// The Jacobian at u as a dense nalgebra matrix.
    fn dense_jacobian(&self, u: &[f64]) -> DMatrix<f64> {
        let h2 = Self::h2();
        DMatrix::from_fn(N, N, |i, j| {
            if i == j {
                -2.0 / h2 + self.lambda * u[i].exp()
            } else if j + 1 == i {
                1.0 / h2
            } else if i + 1 == j {
                1.0 / h2 + 0.6 * u[j]
            } else {
                0.0
            }
        })
    }
}

impl NonlinearSystem for Nonlinear {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        let h2 = Self::h2();
        for i in 0..N {
            let left = if i > 0 { u[i - 1] } else { 0.0 };
            let right = if i + 1 < N { u[i + 1] } else { 0.0 };
            f[i] =
                (left - 2.0 * u[i] + right) / h2 + self.lambda * u[i].exp() + 0.3 * right * right;
        }
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        if self.fail_jacobian {
            return Err(CallbackError::Fatal("Jacobian assembly failed".into()));
        }
        self.setups_at.push(u.to_vec());
        let j = self.dense_jacobian(u);
        for r in 0..N {
            for c in r.saturating_sub(1)..(r + 2).min(N) {
                jac.set(r, c, j[(r, c)]);
            }
        }
        Ok(())
    }
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

#[test]
fn nonlinear_system_matches_dense_lu_at_the_last_setup() {
    for (name, spec) in specs(N, 1, 1) {
        let mut kin = Kinsol::new(Nonlinear::new(), N, spec, &exact_newton()).unwrap();
        let mut u = vec![0.0; N];
        let ones = vec![1.0; N];
        let stats = kin
            .solve(&mut u, &ones, &ones)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            stats.iterations >= 3,
            "{name}: a nonlinear problem should take several Newton steps: {stats:?}"
        );
        let setups = &kin.system().setups_at;
        assert_eq!(setups.len(), stats.linear_setups, "{name}");
        let last = setups.last().unwrap().clone();
        assert!(
            rel_diff(&last, &u) > 0.0,
            "{name}: KINSOL never factorises at the root itself"
        );
        let lu = kin.system().dense_jacobian(&last).lu();
        for seed in 0..5 {
            let b = pseudo_random(N, 100 + seed);
            let mut x = vec![0.0; N];
            kin.solve_with_last_factorization(&mut x, &b).unwrap();
            let reference = lu.solve(&DVector::from_column_slice(&b)).unwrap();
            let d = rel_diff(&x, reference.as_slice());
            assert!(
                d < 1e-10,
                "{name}: differs from nalgebra's LU by {d:e} (relative)"
            );
            // The factorisation is reused, not consumed.
            let mut again = vec![0.0; N];
            kin.solve_with_last_factorization(&mut again, &b).unwrap();
            assert_eq!(x, again, "{name}");
        }
        // A solve that starts at the root makes no setup and keeps the factorisation
        // (KINSOL accepts an initial guess with ‖F‖ ≤ 0.01 · fnorm_tol, hence the looser tol).
        let before = kin.system().setups_at.len();
        kin.set_options(&KinsolOptions {
            fnorm_tol: 1e-6,
            ..exact_newton()
        })
        .unwrap();
        let stats = kin.solve(&mut u, &ones, &ones).unwrap();
        assert_eq!(stats.iterations, 0, "{name}");
        // (stats.linear_setups is KINGetNumJacEvals, which KINSOL 6.4 does not reset when the
        // initial guess is already a root: it still says the previous solve's count.)
        assert_eq!(kin.system().setups_at.len(), before, "{name}");
        let b = pseudo_random(N, 7);
        let mut x = vec![0.0; N];
        kin.solve_with_last_factorization(&mut x, &b).unwrap();
        assert!(
            rel_diff(
                &x,
                lu.solve(&DVector::from_column_slice(&b))
                    .unwrap()
                    .as_slice()
            ) < 1e-10,
            "{name}"
        );
    }
}

#[test]
fn no_factorisation_before_a_setup_or_after_a_failed_one() {
    for (name, spec) in specs(N, 1, 1) {
        let mut kin = Kinsol::new(Nonlinear::new(), N, spec, &exact_newton()).unwrap();
        let mut x = vec![0.0; N];
        let b = vec![1.0; N];
        let e = kin.solve_with_last_factorization(&mut x, &b).unwrap_err();
        assert!(matches!(e, SundialsError::Invalid(_)), "{name}: {e}");
        assert!(
            e.to_string().contains("no successful Jacobian setup"),
            "{name}: {e}"
        );

        let ones = vec![1.0; N];
        let mut root = vec![0.0; N];
        kin.solve(&mut root, &ones, &ones).unwrap();
        kin.solve_with_last_factorization(&mut x, &b).unwrap();
        assert!(matches!(
            kin.solve_with_last_factorization(&mut x[..3], &b),
            Err(SundialsError::Invalid(_))
        ));

        // A failed setup (the Jacobian callback fails) leaves no usable factorisation.
        kin.system_mut().fail_jacobian = true;
        let mut u = vec![0.5; N];
        let e = kin.solve(&mut u, &ones, &ones).unwrap_err();
        assert!(
            e.to_string().contains("Jacobian assembly failed"),
            "{name}: {e}"
        );
        let e = kin.solve_with_last_factorization(&mut x, &b).unwrap_err();
        assert!(matches!(e, SundialsError::Invalid(_)), "{name}: {e}");
        // A solve that makes no setup (the guess is already a root) does not bring it back.
        kin.set_options(&KinsolOptions {
            fnorm_tol: 1e-6,
            ..exact_newton()
        })
        .unwrap();
        let mut u = root.clone();
        assert_eq!(
            kin.solve(&mut u, &ones, &ones).unwrap().iterations,
            0,
            "{name}"
        );
        let e = kin.solve_with_last_factorization(&mut x, &b).unwrap_err();
        assert!(matches!(e, SundialsError::Invalid(_)), "{name}: {e}");
        kin.set_options(&exact_newton()).unwrap();

        // A later successful solve restores it.
        kin.system_mut().fail_jacobian = false;
        let mut u = vec![0.0; N];
        kin.solve(&mut u, &ones, &ones).unwrap();
        kin.solve_with_last_factorization(&mut x, &b).unwrap();
    }
}

/// A singular Jacobian: SUNLinSolSetup fails (LU or KLU), KINSOL stops with
/// KIN_LSETUP_FAIL and there is no factorisation to solve with.
#[test]
fn singular_jacobian_leaves_no_factorisation() {
    struct Singular;
    impl NonlinearSystem for Singular {
        fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
            f[0] = u[0] + u[1] - 1.0;
            f[1] = 2.0 * u[0] + 2.0 * u[1] - 3.0;
            Ok(())
        }
        fn jacobian(&mut self, _u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
            jac.set(0, 0, 1.0);
            jac.set(0, 1, 1.0);
            jac.set(1, 0, 2.0);
            jac.set(1, 1, 2.0);
            Ok(())
        }
    }
    for (name, spec) in specs(2, 1, 1) {
        let mut kin = Kinsol::new(Singular, 2, spec, &exact_newton()).unwrap();
        let mut u = vec![0.0; 2];
        let e = kin.solve(&mut u, &[1.0; 2], &[1.0; 2]).unwrap_err();
        assert!(
            matches!(
                &e,
                SundialsError::Flag {
                    name: "KIN_LSETUP_FAIL",
                    ..
                }
            ),
            "{name}: {e}"
        );
        let e = kin
            .solve_with_last_factorization(&mut [0.0; 2], &[1.0, 2.0])
            .unwrap_err();
        assert!(matches!(e, SundialsError::Invalid(_)), "{name}: {e}");
    }
}
