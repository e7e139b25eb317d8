//! Numerical stability at the extremes (every parameter pushed to its edge). Each case
//! is a scene pushed in one direction; it must either solve, with its diagnostics inside
//! stated bounds, or fail with a typed error that says what failed and where — never NaN,
//! never a panic, never a hang (every iteration in the solvers is bounded).
//!
//! `eyeshell extremes --out TESTING.md` runs them all and writes the table.

use eyeshell::bvp::settings::SolverSettings;
use eyeshell::bvp::{self, FieldRow};
use eyeshell::growth::GROWTH_COLUMNS;
use eyeshell::growth::{self, GrowthParams, GrowthSettings, ThicknessLaw};
use eyeshell::model::cornea;
use eyeshell::model::params::{Params, Thickness};
use std::fmt::Write as _;
use std::time::Instant;

/// One pushed scene.
#[derive(Clone, Debug)]
pub struct Case {
    pub group: &'static str,
    pub name: String,
    pub params: Params,
    pub solver: SolverSettings,
    pub growth: Option<(GrowthParams, GrowthSettings)>,
    /// The parameters are those of docs/MODEL.md §7, so the exact solution is known.
    pub exact: bool,
}

/// How a case ended.
#[derive(Clone, Debug)]
pub enum Outcome {
    Solved {
        seconds: f64,
        newton_iterations: usize,
        continuation_stages: usize,
        residual_norm: f64,
        first_integral_max: f64,
        /// Largest error of κ, α_s, r, θ, Q against the exact solution, when known.
        exact_error: Option<f64>,
        /// Growth: the axial length at t_end.
        axial_length: Option<f64>,
        /// Every field of every node is finite.
        finite: bool,
    },
    Failed {
        seconds: f64,
        error: String,
    },
}

fn fibre_shell() -> Params {
    Params {
        thickness: Thickness::NonUniform,
        d: 200.0,
        ..Params::default()
    }
}

fn exact(p: Params) -> Params {
    p.exact_sphere()
}

/// Half the cornea's largest pressure, so that a pushed material stays admissible.
fn half_limit(p: Params) -> Params {
    Params {
        dp: 0.5 * cornea::max_pressure(&p.cornea),
        ..p
    }
}

/// The head of TESTING.md.
/// The line after which an existing file's text is kept when the table is regenerated
/// (TESTING.md's hand-written sections live below it).
pub const KEEP_BELOW: &str =
    "<!-- eyeshell extremes regenerates the text above this line and keeps the text below -->";

/// The whole file: the preamble, the table, and what `previous` (the file being replaced,
/// if any) held below [`KEEP_BELOW`].
pub fn document(table: &str, previous: Option<&str>) -> String {
    let kept = previous
        .and_then(|p| p.find(KEEP_BELOW).map(|i| &p[i..]))
        .unwrap_or("");
    let sep = if kept.is_empty() { "" } else { "\n" };
    format!("{PREAMBLE}{table}{sep}{kept}")
}

/// Did eyeshell write the file with this text (it starts as [`PREAMBLE`] does)?
pub fn wrote(text: &[u8]) -> bool {
    let first = PREAMBLE.lines().next().unwrap_or_default();
    text.starts_with(first.as_bytes())
}

pub const PREAMBLE: &str = "# Stability at the extremes\n\n\
Every parameter pushed to its edge, one at a time, from the paper's shells (docs/MODEL.md §8).\n\
Regenerate this file with `cargo run --release -- extremes --out TESTING.md`; \
`tests/cli/extremes.rs` runs the same cases and asserts that each one solves with finite \
fields, a Newton residual within 10× its tolerance and a first integral within 1e-2 of \
r²ΔP, and within 1e-5 of docs/MODEL.md §7's exact solution where that applies (1e-1 for N < 51).\n\n\
- Elastic cases: Hermite–Simpson, N = 501, unless the case says otherwise. The sphere \
cases use docs/MODEL.md §7's parameters; a pushed material keeps ΔP at half the cornea's limit.\n\
- Small E_b (the membrane limit): nodes are graded next to the cornea, where the bending \
layer of width √(E_b / t_s) forms (`solver.cornea_grading`, on by default).\n\
- Growth cases: the const scene at N = 101 with IDA (the default integrator) at rtol 1e-5 to t_end; \
their Newton iterations are the coupled system's (with the elastic solves at t = 0 and at the snapshots).\n\
- Seconds are wall time on the machine that wrote the file.\n\n";

/// Every case of the suite: the elastic ones, then growth.
pub fn cases() -> Vec<Case> {
    let mut out = elastic_cases();
    out.extend(growth_cases());
    out
}

/// The elastic cases: the solver's resolution (ε, N), then each parameter of the shell
/// pushed in turn, and continuation forced by a short Newton budget.
fn elastic_cases() -> Vec<Case> {
    let s = SolverSettings::default();
    let mut out = vec![];
    let mut push = |group: &'static str,
                    name: String,
                    params: Params,
                    solver: SolverSettings,
                    is_exact: bool| {
        out.push(Case {
            group,
            name,
            params,
            solver,
            growth: None,
            exact: is_exact,
        });
    };
    let sphere = exact(Params::default());
    for eps in [1e-8, 1e-6, 1e-4, 1e-2, 1e-1] {
        push(
            "pole truncation ε",
            format!("ε = {eps:e}"),
            sphere,
            SolverSettings { epsilon: eps, ..s },
            true,
        );
    }
    for n in [5, 11, 101, 2001, 20001] {
        push(
            "nodes N",
            format!("N = {n}"),
            sphere,
            SolverSettings { nodes: n, ..s },
            true,
        );
    }
    let limit = cornea::max_pressure(&sphere.cornea);
    for dp in [0.0, 1e-6, 2.0, 0.999 * limit] {
        push(
            "pressure ΔP",
            format!("ΔP = {dp:.6e}"),
            Params { dp, ..sphere },
            s,
            true,
        );
    }
    for c in [1.0, 1e5] {
        push(
            "modulus C",
            format!("C = {c:e} (sphere)"),
            half_limit(exact(Params {
                c,
                ..Params::default()
            })),
            s,
            true,
        );
        let p = fibre_shell();
        let p = Params {
            c,
            cornea: eyeshell::model::params::CorneaParams { c, ..p.cornea },
            ..p
        };
        push(
            "modulus C",
            format!("C = {c:e} (fibre shell)"),
            half_limit(p),
            s,
            false,
        );
    }
    for d in [0.0, 1e2, 1e3, 1e4, 1e5] {
        push(
            "fibres D",
            format!("D = {d:e}"),
            Params { d, ..fibre_shell() },
            s,
            false,
        );
    }
    for e_b in [1e-6, 1e-3, 1.0, 1e3, 1e6] {
        push(
            "bending E_b",
            format!("E_b = {e_b:e}"),
            Params {
                e_b,
                ..fibre_shell()
            },
            s,
            false,
        );
    }
    // Newton allowed too few iterations for a cold start: continuation must take over.
    push(
        "continuation",
        "D = 1e5, at most 4 Newton iterations a solve".into(),
        Params {
            d: 1e5,
            ..fibre_shell()
        },
        SolverSettings { max_newton: 4, ..s },
        false,
    );
    push(
        "continuation",
        "E_b = 1e-6, at most 3 Newton iterations a solve".into(),
        Params {
            e_b: 1e-6,
            ..fibre_shell()
        },
        SolverSettings { max_newton: 3, ..s },
        false,
    );
    for h0 in [0.01, 3.0] {
        let p = half_limit(exact(Params {
            h0,
            ..Params::default()
        }));
        push("thickness H0", format!("H0 = {h0}"), p, s, true);
    }
    out
}

/// The growth cases: the const scene at N = 101, IDA (the default) at rtol 1e-5, with
/// one growth parameter pushed in each.
fn growth_cases() -> Vec<Case> {
    let s = SolverSettings::default();
    let mut out = vec![];
    let gs = GrowthSettings {
        rtol: 1e-5,
        atol: 1e-7,
        output_times: vec![],
        ..GrowthSettings::default()
    };
    let g0 = GrowthParams::default();
    let small = SolverSettings { nodes: 101, ..s };
    let mut grow = |name: String, g: GrowthParams| {
        out.push(Case {
            group: "growth",
            name,
            params: Params::default(),
            solver: small,
            growth: Some((g, gs.clone())),
            exact: false,
        });
    };
    for eta0 in [0.0, 1e2, 1e3, 1e4] {
        grow(
            format!("η0 = {eta0:e}"),
            GrowthParams { eta0, ..g0.clone() },
        );
    }
    for delta in [0.05, 50.0] {
        grow(
            format!("δ = {delta}"),
            GrowthParams {
                delta,
                ..g0.clone()
            },
        );
    }
    for gamma in [-10.0, 40.0] {
        grow(
            format!("Γ = {gamma} (outside [0, L])"),
            GrowthParams {
                gamma,
                ..g0.clone()
            },
        );
    }
    grow(
        "t_end = 10".into(),
        GrowthParams {
            t_end: 10.0,
            ..g0.clone()
        },
    );
    grow(
        "mass thickness law".into(),
        GrowthParams {
            thickness_law: ThicknessLaw::Mass,
            ..g0.clone()
        },
    );
    out
}

/// Largest error of κ, α_s, r, θ, Q against docs/MODEL.md §7's exact solution.
fn exact_error(p: &Params, rows: &[FieldRow], alpha: f64) -> f64 {
    rows.iter()
        .map(|r| {
            let x = r.sigma_ref;
            let e = [
                1.0 / (alpha * p.r0),
                alpha,
                alpha * p.r0 * (x / p.r0).sin(),
                x / p.r0,
                0.0,
            ];
            let v = [r.kappa, r.alpha_s, r.r, r.theta, r.q];
            v.iter()
                .zip(e)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

fn finite(rows: &[FieldRow]) -> bool {
    rows.iter()
        .all(|r| r.values().iter().all(|v| v.is_finite()))
}

/// Run one case.
pub fn run(case: &Case) -> Outcome {
    let start = Instant::now();
    let failed = |e: String| Outcome::Failed {
        seconds: start.elapsed().as_secs_f64(),
        error: e,
    };
    match &case.growth {
        None => match bvp::solve(&case.params, &case.solver, None) {
            Ok(sol) => Outcome::Solved {
                seconds: start.elapsed().as_secs_f64(),
                newton_iterations: sol.stats.newton_iterations,
                continuation_stages: sol.stats.continuation_stages,
                residual_norm: sol.stats.residual_norm,
                first_integral_max: sol.stats.first_integral_max,
                exact_error: case
                    .exact
                    .then(|| exact_error(&case.params, &sol.rows, sol.stats.cornea_alpha)),
                axial_length: None,
                finite: finite(&sol.rows),
            },
            Err(e) => failed(e.to_string()),
        },
        Some((g, gs)) => {
            let mut last = None;
            let problem = match super::growth_problem(&case.params, &case.solver, g, gs) {
                Ok(problem) => problem,
                Err(e) => return failed(e.to_string()),
            };
            let r = growth::run(
                &problem,
                &mut |sys, t, p| {
                    let snap = sys.snapshot(t, p)?;
                    last = Some(snap);
                    Ok(())
                },
                &mut |_| Ok(()),
            );
            match (r, last) {
                (Ok(stats), Some(snap)) => Outcome::Solved {
                    seconds: start.elapsed().as_secs_f64(),
                    // The Newton iterations that did the work: of the elastic solves
                    // (CVODE, Euler), or of the coupled system (IDA).
                    newton_iterations: stats.newton_iterations
                        + stats.nonlinear_iterations * usize::from(stats.rhs_evaluations == 0),
                    continuation_stages: 0,
                    residual_norm: f64::NAN,
                    first_integral_max: f64::NAN,
                    exact_error: None,
                    axial_length: Some(snap.series.axial_length),
                    finite: finite(&snap.fields)
                        && snap.growth.iter().all(|g| {
                            // defocus_D is NaN where the rule reads no defocus.
                            g.values().iter().zip(GROWTH_COLUMNS).all(|(x, name)| {
                                x.is_finite() || (name == "defocus_D" && x.is_nan())
                            })
                        }),
                },
                (Ok(_), None) => failed("the run gave no state".into()),
                (Err(e), _) => failed(e.to_string()),
            }
        }
    }
}

fn num(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else {
        format!("{x:.2e}")
    }
}

/// The suite as a Markdown table.
pub fn table(results: &[(Case, Outcome)]) -> String {
    let mut t = String::from("| group | case | outcome | seconds | Newton iterations | continuation stages | residual | first integral | error vs exact | axial length |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (c, o) in results {
        match o {
            Outcome::Solved {
                seconds,
                newton_iterations,
                continuation_stages,
                residual_norm,
                first_integral_max,
                exact_error,
                axial_length,
                finite,
            } => {
                let _ = writeln!(
                    t,
                    "| {} | {} | {} | {:.3} | {} | {} | {} | {} | {} | {} |",
                    c.group,
                    c.name,
                    if *finite {
                        "solved"
                    } else {
                        "solved, NOT FINITE"
                    },
                    seconds,
                    newton_iterations,
                    continuation_stages,
                    num(*residual_norm),
                    num(*first_integral_max),
                    exact_error.map_or("–".into(), num),
                    axial_length.map_or("–".into(), |a| format!("{a:.4}")),
                );
            }
            Outcome::Failed { seconds, error } => {
                let _ = writeln!(
                    t,
                    "| {} | {} | failed: {} | {:.3} | | | | | | |",
                    c.group,
                    c.name,
                    error.replace('|', "/"),
                    seconds
                );
            }
        }
    }
    t
}

#[cfg(test)]
mod keep_tests {
    use super::*;

    /// Regenerating replaces the table and keeps the hand-written text below the marker.
    #[test]
    fn the_tail_below_the_marker_is_kept() {
        let old = format!("{PREAMBLE}| old table |\n\n{KEEP_BELOW}\n## Hostile inputs\nmine\n");
        let new = document("| new table |\n", Some(&old));
        assert!(new.starts_with(PREAMBLE) && wrote(new.as_bytes()));
        assert!(new.contains("| new table |") && !new.contains("old table"));
        assert!(new.ends_with(&format!("{KEEP_BELOW}\n## Hostile inputs\nmine\n")));
        assert_eq!(document("| t |\n", None), format!("{PREAMBLE}| t |\n"));
        assert!(!wrote(b"# my notes"));
    }
}
