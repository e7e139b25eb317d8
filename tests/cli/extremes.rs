//! Stability at the extremes: every case of `study::extremes` ends either solved, with its
//! diagnostics within bounds and no NaN anywhere, or with a typed one-line error; and the
//! cases this solver is expected to handle do solve.

use eyeshell_cli::study::extremes::{cases, run, table, Outcome};

#[test]
fn every_extreme_case_ends_cleanly() {
    let results: Vec<_> = cases()
        .into_iter()
        .map(|c| {
            let o = run(&c);
            (c, o)
        })
        .collect();
    println!("{}", table(&results));
    for (c, o) in &results {
        match o {
            Outcome::Solved {
                finite,
                residual_norm,
                first_integral_max,
                exact_error,
                continuation_stages,
                ..
            } => {
                assert!(finite, "{}: a field is not finite", c.name);
                if c.group == "continuation" {
                    assert!(
                        *continuation_stages > 0,
                        "{}: solved without continuation",
                        c.name
                    );
                }
                if c.growth.is_none() {
                    assert!(
                        *residual_norm <= 10.0 * c.solver.newton_tol,
                        "{}: residual {residual_norm:e}",
                        c.name
                    );
                    // The first integral holds to the discretisation error: bounded by 1e-2 of
                    // its natural size r² ΔP even on the coarsest mesh.
                    let scale = (c.params.r0 * c.params.r0 * c.params.dp).max(1e-12);
                    assert!(
                        *first_integral_max <= 1e-2 * scale + 1e-12,
                        "{}: first integral {first_integral_max:e}",
                        c.name
                    );
                }
                if let Some(e) = exact_error {
                    let bound = if c.solver.nodes < 51 { 1e-1 } else { 1e-5 };
                    assert!(
                        *e < bound,
                        "{}: error {e:e} against the exact solution",
                        c.name
                    );
                }
            }
            Outcome::Failed { error, .. } => {
                assert!(
                    !error.is_empty() && !error.contains('\n'),
                    "{}: error not one line: {error}",
                    c.name
                );
                panic!("{} {}: failed: {error}", c.group, c.name);
            }
        }
    }
}
