//! The paper's refinement check (docs/MODEL.md §8), reproduced. The const scene at the published
//! settings (N = 501, 200 Euler steps, ε = 1e-3, and our Newton tolerance 1e-10 standing in
//! for bvp4c's 1e-6) is compared at t = 1 with the same run refined — nodes ×2, steps ×2,
//! tolerance ÷100, ε ÷10 — together and one at a time. The paper reports relative changes
//! κ 1.7e-3, α_s 2.1e-5, r 9.4e-4, θ 7.4e-4. The same check is made for CVODE at several
//! tolerances, refined the same way (rtol ÷100 in place of the steps).

use super::{points, run, sample, StudyError};
use eyeshell::bvp::settings::SolverSettings;
use eyeshell::growth::{GrowthParams, GrowthSettings, Integrator};
use eyeshell::model::params::Params;

/// The paper's reported relative changes of κ, α_s, r, θ.
pub const PAPER: [f64; 4] = [1.7e-3, 2.1e-5, 9.4e-4, 7.4e-4];

/// One comparison: a run against its refinement.
#[derive(Clone, Debug)]
pub struct Change {
    pub label: String,
    /// max |refined − base| / max |base| of κ, α_s, r, θ over the base's uniform nodes.
    pub relative: [f64; 4],
    /// Seconds of the base run and of the refined run.
    pub seconds: f64,
    pub refined_seconds: f64,
}

/// The published settings of the const scene (docs/MODEL.md §8).
pub fn published() -> (Params, SolverSettings, GrowthParams, GrowthSettings) {
    let solver = SolverSettings {
        nodes: 501,
        epsilon: 1e-3,
        newton_tol: 1e-10,
        ..SolverSettings::default()
    };
    let settings = GrowthSettings {
        integrator: Integrator::Euler,
        steps: 200,
        output_times: vec![],
        ..GrowthSettings::default()
    };
    (Params::default(), solver, GrowthParams::default(), settings)
}

/// The knobs a refinement turns.
#[derive(Clone, Copy, Debug, Default)]
pub struct Refine {
    pub nodes: bool,
    pub time: bool,
    pub tolerance: bool,
    pub epsilon: bool,
}

impl Refine {
    pub const ALL: Refine = Refine {
        nodes: true,
        time: true,
        tolerance: true,
        epsilon: true,
    };

    fn apply(self, s: &SolverSettings, g: &GrowthSettings) -> (SolverSettings, GrowthSettings) {
        let mut s = *s;
        let mut g = g.clone();
        if self.nodes {
            s.nodes = 2 * s.nodes - 1;
        }
        if self.time {
            match g.integrator {
                Integrator::Euler => g.steps *= 2,
                Integrator::Cvode | Integrator::Ida => {
                    g.rtol /= 100.0;
                    g.atol /= 100.0;
                }
            }
        }
        if self.tolerance {
            s.newton_tol /= 100.0;
        }
        if self.epsilon {
            s.epsilon /= 10.0;
        }
        (s, g)
    }
}

/// Relative change at t_end of κ, α_s, r, θ between `(solver, settings)` and its refinement.
pub fn change(
    label: &str,
    p: &Params,
    solver: &SolverSettings,
    g: &GrowthParams,
    settings: &GrowthSettings,
    refine: Refine,
) -> Result<Change, StudyError> {
    let base = run(p, solver, Some((g, settings)), label)?;
    let (rs, rg) = refine.apply(solver, settings);
    let refined = run(p, &rs, Some((g, &rg)), &format!("{label}, refined"))?;
    let pts = points(solver.epsilon, p.length(), solver.nodes);
    let a = sample(&base.solution, &pts, label)?;
    let b = sample(&refined.solution, &pts, label)?;
    // κ, α_s, r, θ are fields 0..4 of the sample.
    let relative = std::array::from_fn(|c| {
        let scale = a.iter().map(|v| v[c].abs()).fold(0.0, f64::max);
        a.iter()
            .zip(&b)
            .map(|(x, y)| (x[c] - y[c]).abs())
            .fold(0.0, f64::max)
            / scale
    });
    Ok(Change {
        label: label.into(),
        relative,
        seconds: base.seconds,
        refined_seconds: refined.seconds,
    })
}

/// The whole check: Euler at the published settings refined all at once and one knob at a
/// time, then CVODE at each of `rtols` refined all at once.
pub fn check(rtols: &[f64]) -> Result<Vec<Change>, StudyError> {
    let (p, s, g, e) = published();
    let mut out = vec![change(
        "euler 200, all refined",
        &p,
        &s,
        &g,
        &e,
        Refine::ALL,
    )?];
    for (label, r) in [
        (
            "euler 200, nodes x2",
            Refine {
                nodes: true,
                ..Refine::default()
            },
        ),
        (
            "euler 200, steps x2",
            Refine {
                time: true,
                ..Refine::default()
            },
        ),
        (
            "euler 200, newton tol /100",
            Refine {
                tolerance: true,
                ..Refine::default()
            },
        ),
        (
            "euler 200, epsilon /10",
            Refine {
                epsilon: true,
                ..Refine::default()
            },
        ),
    ] {
        out.push(change(label, &p, &s, &g, &e, r)?);
    }
    for &rtol in rtols {
        let c = GrowthSettings {
            integrator: Integrator::Cvode,
            rtol,
            atol: rtol * 1e-2,
            output_times: vec![],
            ..GrowthSettings::default()
        };
        out.push(change(
            &format!("cvode rtol {rtol:e}, all refined"),
            &p,
            &s,
            &g,
            &c,
            Refine::ALL,
        )?);
    }
    Ok(out)
}

/// The check as CSV, with the paper's figures as the first row.
pub fn table(changes: &[Change]) -> (Vec<String>, Vec<Vec<String>>) {
    use super::cell;
    let header = [
        "run",
        "kappa",
        "alpha_s",
        "r",
        "theta",
        "seconds",
        "refined_seconds",
    ]
    .map(String::from)
    .to_vec();
    let mut rows = vec![{
        let mut r = vec!["paper (bvp4c 1e-6, 501 nodes, Euler 200)".to_string()];
        r.extend(PAPER.iter().map(|&x| cell(x)));
        r.extend([String::new(), String::new()]);
        r
    }];
    for c in changes {
        let mut r = vec![c.label.clone()];
        r.extend(c.relative.iter().map(|&x| cell(x)));
        r.extend([cell(c.seconds), cell(c.refined_seconds)]);
        rows.push(r);
    }
    (header, rows)
}
