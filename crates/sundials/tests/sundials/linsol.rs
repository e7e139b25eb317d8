//! The linear solvers used standalone: a 3×3 system with dense, band and KLU; a singular
//! matrix gives a named flag; misuse gives Invalid.

use eyeshell_sundials::{
    klu_available, Context, LinearSolver, LinearSolverSpec, MatrixSink, NVector, SundialsError,
};

/// A = [[4, 1, 0], [1, 4, 1], [0, 1, 4]], b = A (1, 2, 3).
const A: [[f64; 3]; 3] = [[4.0, 1.0, 0.0], [1.0, 4.0, 1.0], [0.0, 1.0, 4.0]];
const X: [f64; 3] = [1.0, 2.0, 3.0];

fn specs() -> Vec<LinearSolverSpec> {
    let mut v = vec![
        LinearSolverSpec::Dense,
        LinearSolverSpec::Band { upper: 1, lower: 1 },
    ];
    if klu_available() {
        v.push(LinearSolverSpec::Klu {
            row_ptr: vec![0, 2, 5, 7],
            col_idx: vec![0, 1, 0, 1, 2, 1, 2],
        });
    }
    v
}

#[test]
fn three_by_three_with_every_solver() {
    let ctx = Context::new().unwrap();
    for spec in specs() {
        let (mut a, mut ls) = LinearSolver::for_spec(&ctx, 3, &spec).unwrap();
        for round in 0..3 {
            {
                a.zero();
                let mut v = a.view_mut();
                for i in 0..3 {
                    for j in 0..3 {
                        if A[i][j] != 0.0 {
                            v.set(i, j, A[i][j] * (round + 1) as f64);
                        }
                    }
                }
            }
            let b: Vec<f64> = (0..3)
                .map(|i| (0..3).map(|j| A[i][j] * X[j]).sum::<f64>() * (round + 1) as f64)
                .collect();
            let b = NVector::from_slice(&ctx, &b).unwrap();
            let mut x = NVector::new(&ctx, 3).unwrap();
            ls.setup(&mut a).unwrap();
            ls.solve(&mut a, &mut x, &b).unwrap();
            for (got, want) in x.as_slice().iter().zip(X) {
                assert!(
                    (got - want).abs() < 1e-14,
                    "{spec:?} round {round}: {:?}",
                    x.as_slice()
                );
            }
        }
    }
}

#[test]
fn singular_matrix_is_a_named_flag() {
    let ctx = Context::new().unwrap();
    for spec in specs() {
        let (mut a, mut ls) = LinearSolver::for_spec(&ctx, 3, &spec).unwrap();
        a.view_mut().set(0, 0, 1.0); // rows 1 and 2 stay zero
        let err = ls.setup(&mut a).unwrap_err();
        let SundialsError::Flag { name, .. } = &err else {
            panic!("{spec:?}: {err:?}")
        };
        assert!(name.starts_with("SUNLS_"), "{spec:?}: {err}");
        eprintln!("{spec:?}: {err}");
    }
}

#[test]
fn misuse_is_invalid() {
    let ctx = Context::new().unwrap();
    let (mut dense, mut ls) = LinearSolver::for_spec(&ctx, 3, &LinearSolverSpec::Dense).unwrap();
    let (mut band, _) =
        LinearSolver::for_spec(&ctx, 3, &LinearSolverSpec::Band { upper: 1, lower: 1 }).unwrap();
    assert!(matches!(
        ls.setup(&mut band),
        Err(SundialsError::Invalid(_))
    ));
    let b = NVector::new(&ctx, 3).unwrap();
    let mut x = NVector::new(&ctx, 3).unwrap();
    assert!(
        matches!(
            ls.solve(&mut dense, &mut x, &b),
            Err(SundialsError::Invalid(_))
        ),
        "solve before setup"
    );
    let mut short = NVector::new(&ctx, 2).unwrap();
    assert!(matches!(
        ls.solve(&mut dense, &mut short, &b),
        Err(SundialsError::Invalid(_))
    ));
}

#[test]
fn objects_outlive_nothing_they_need() {
    // Drop the context handle first: every object keeps it alive through its Rc.
    for _ in 0..1000 {
        let ctx = Context::new().unwrap();
        let (a, ls) =
            LinearSolver::for_spec(&ctx, 4, &LinearSolverSpec::Band { upper: 2, lower: 1 })
                .unwrap();
        let v = NVector::new(&ctx, 4).unwrap();
        drop(ctx);
        drop(a); // the matrix before its solver is also fine outside an integrator
        drop(v);
        drop(ls);
    }
}
