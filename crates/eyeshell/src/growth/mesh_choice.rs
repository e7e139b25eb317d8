//! The material mesh of a growth run under `solver.tol` (docs/MODEL.md §3–5). Material
//! points cannot move while the shell grows, so the mesh is chosen once, before the run:
//!
//! 1. the elastic solve at t = 0 is adapted to tol ([`adapt::solve_to_tolerance`]); its
//!    report lies on M/2, the halving of its last mesh M;
//! 2. a test run on M/2 (the run itself: the same integrator and tolerances) records the
//!    growth state at t = 0 and at every snapshot time (`output.times` and t_end);
//! 3. at each of those states the grown shell is solved on M/2 and on M, with M's data
//!    read from M/2's points (M's nodes and midpoints are nodes of M/2, so both meshes see
//!    the same unloaded shell, with no interpolation) and the error of M/2's solution is
//!    estimated as in [`adapt::estimate`];
//! 4. if every estimate is at most tol, M/2 is the run's mesh; otherwise the next M
//!    equidistributes the largest of the local error indicators over those times (aiming at
//!    [`adapt::AIM`] · tol), and 2–4 repeat, at most [`MAX_TEST_RUNS`] times.
//!
//! The test run is not made at a looser time tolerance: the integrator's error differs
//! from point to point of the shell (each point stops growing at its own time), and that
//! jitter in the unloaded shell's data is part of what M/2 sees and M does not. On the const
//! scene at tol 1e-6, a test run at rtol 1e-4 left the estimate stalled at 4e-6 however
//! fine the mesh; at the scene's rtol 1e-6 it took 1039 nodes, at rtol 1e-9 only 525.
//!
//! What it promises: the estimated elastic error of every field (in summary.json's units,
//! [`crate::bvp::adapt`]), at t = 0 and at the snapshot times of the last test run (the run
//! on the chosen mesh with the run's own settings), is at most tol. What it does not: the
//! error of the time integration (solver.rtol's), the elastic error between snapshot
//! times, and anything about the growth fields beyond the elastic ones. `solver.max_seconds`
//! bounds the whole: the adaptation at t = 0, the test runs, their estimates and the final
//! run share one clock (started by [`super::run_with`]).

use crate::bvp::adapt::{self, PassEstimate};
use crate::bvp::discretisation::{MaterialData, NY};
use crate::bvp::settings::SolverSettings;
use crate::bvp::solve::{ElasticSolver, Solution};
use crate::bvp::BvpError;
use crate::bvp::ErrorEstimate;
use crate::mesh::Mesh;
use crate::model::params::Params;

use super::{GrowthParams, GrowthSettings};

/// The most test runs before giving up.
pub const MAX_TEST_RUNS: usize = 8;

/// The estimated elastic error at one time of the last test run (summary.json).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct TimedEstimate {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub t: f64,
    pub error_estimate: ErrorEstimate,
}

/// How `solver.tol` chose a growth run's mesh (summary.json's `stats.mesh_choice`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct MeshChoice {
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub tol: f64,
    /// Nodes of the chosen mesh.
    pub nodes: usize,
    /// Nodes of each pass of the adaptation at t = 0.
    pub elastic_pass_nodes: Vec<usize>,
    /// Nodes of the mesh of each test run (the last is the chosen one).
    pub test_run_nodes: Vec<usize>,
    /// The elastic error estimated on the chosen mesh at t = 0 and at each snapshot time
    /// of the last test run.
    pub estimates: Vec<TimedEstimate>,
    #[serde(deserialize_with = "crate::json::f64_or_nan")]
    pub wall_seconds: f64,
}

/// M, of which `fine` is the halving (its even nodes).
fn parent(fine: &Mesh) -> Mesh {
    let nodes = fine.nodes.iter().step_by(2).copied().collect();
    let breakpoints = fine.breakpoint_nodes.iter().map(|&i| i / 2).collect();
    Mesh::adapted(nodes, breakpoints)
}

/// M's data read from those of M/2: M's node i is M/2's node 2i, M's midpoint i its
/// node 2i + 1 (never a breakpoint: one-sided limits agree there).
fn restrict(fine: &MaterialData) -> MaterialData {
    let m = fine.above.len().div_ceil(2);
    MaterialData {
        above: (0..m).map(|i| fine.above[2 * i]).collect(),
        below: (0..m).map(|i| fine.below[2 * i]).collect(),
        mid: (0..m - 1).map(|i| fine.above[2 * i + 1]).collect(),
    }
}

/// The elastic solution of the shell with `data` on `mesh`, Newton from `u`.
fn solve_with_data(
    params: &Params,
    s: &SolverSettings,
    mesh: Mesh,
    data: MaterialData,
    u: Vec<f64>,
) -> Result<Solution, BvpError> {
    let mut elastic = ElasticSolver::on_mesh(params, s, mesh)?;
    elastic.discretisation_mut().set_data(data);
    elastic.u = u;
    elastic.newton()?;
    elastic.solution()
}

/// One recorded state of a test run: t, the growth state and the elastic unknowns on M/2.
struct State {
    t: f64,
    p: Vec<f64>,
    u: Vec<f64>,
}

/// The test run on `fine` (the run's own integrator and tolerances), recording
/// the state at t = 0 and at every snapshot time.
fn test_run(
    params: &Params,
    s: &SolverSettings,
    growth: &GrowthParams,
    settings: &GrowthSettings,
    fine: &Mesh,
) -> Result<(Vec<State>, super::points::GrowthPoints), String> {
    let recorded = GrowthSettings {
        history_points: 0,
        // The test runs check the mesh only: no sensitivities.
        sensitivities: Vec::new(),
        ..settings.clone()
    };
    let mut states = vec![];
    let mut points = None;
    let mut record = |sys: &mut super::system::GrowthSystem, t: f64, p: &[f64]| {
        sys.solve_elastic(p).map_err(|e| e.to_string())?;
        points.get_or_insert_with(|| sys.points.clone());
        states.push(State {
            t,
            p: p.to_vec(),
            u: sys.elastic.u.clone(),
        });
        Ok(())
    };
    let snapshots = super::snapshot_times(&recorded, growth.t_end);
    let mut output = |sys: &mut super::system::GrowthSystem, t: f64, p: &[f64]| {
        if t == 0.0 || snapshots.contains(&t) {
            record(sys, t, p)
        } else {
            Ok(())
        }
    };
    super::run_on(
        params,
        s,
        growth,
        &recorded,
        Some(fine.clone()),
        &mut |_| Ok(()),
        &mut output,
        &mut |_| Ok(()),
    )
    .map_err(|e| {
        format!(
            "the test run of solver.tol's mesh choice on {} nodes: {e}",
            fine.len()
        )
    })?;
    Ok((states, points.expect("t = 0 is always recorded")))
}

/// The error of the grown shell's elastic solution on M/2 at `state`, estimated against M.
fn estimate_at(
    params: &Params,
    s: &SolverSettings,
    points: &super::points::GrowthPoints,
    coarse: &Mesh,
    fine: &Mesh,
    state: &State,
) -> Result<PassEstimate, BvpError> {
    let data = points.material_data(&state.p);
    let coarse_data = restrict(&data);
    let fine_sol = solve_with_data(params, s, fine.clone(), data, state.u.clone())?;
    let u: Vec<f64> = (0..coarse.len())
        .flat_map(|i| fine_sol.u[2 * NY * i..2 * NY * i + NY].iter().copied())
        .collect();
    let coarse_sol = solve_with_data(params, s, coarse.clone(), coarse_data, u)?;
    Ok(adapt::estimate(&coarse_sol, &fine_sol))
}

/// Choose the growth run's mesh for `solver.tol` (module docs). Err: why not, in a sentence.
pub fn choose(
    params: &Params,
    solver: &SolverSettings,
    growth: &GrowthParams,
    settings: &GrowthSettings,
) -> Result<(Mesh, MeshChoice), String> {
    let start = std::time::Instant::now();
    let tol = solver.tol.expect("mesh choice is for solver.tol");
    let first = adapt::solve_to_tolerance(params, solver).map_err(|e| e.to_string())?;
    // The solves of the test runs and the estimates: on given meshes, Newton tightened.
    let s = SolverSettings {
        tol: None,
        richardson: false,
        newton_tol: adapt::newton_tol_for(solver),
        ..*solver
    };
    let floors = adapt::Floors::of(params, solver);
    let order = solver.scheme.order();
    let mut fine = first.mesh.clone();
    let mut choice = MeshChoice {
        tol,
        elastic_pass_nodes: first.stats.pass_nodes.clone().unwrap_or_default(),
        ..MeshChoice::default()
    };
    loop {
        let coarse = parent(&fine);
        choice.test_run_nodes.push(fine.len());
        let (states, points) = test_run(params, &s, growth, settings, &fine)?;
        let mut worst: Option<PassEstimate> = None;
        choice.estimates.clear();
        for state in &states {
            let est = estimate_at(params, &s, &points, &coarse, &fine, state).map_err(|e| {
                format!(
                    "solver.tol's error estimate at t = {} on {} nodes: {e}",
                    crate::text::decimals6(state.t),
                    fine.len()
                )
            })?;
            choice.estimates.push(TimedEstimate {
                t: state.t,
                error_estimate: est.error_estimate(),
            });
            worst = Some(match worst {
                None => est,
                Some(w) => PassEstimate {
                    global: std::array::from_fn(|k| w.global[k].max(est.global[k])),
                    local: w
                        .local
                        .iter()
                        .zip(&est.local)
                        .map(|(a, b)| a.max(*b))
                        .collect(),
                },
            });
        }
        let worst = worst.expect("t = 0 is always recorded");
        let error = worst.overall();
        if error <= tol {
            choice.nodes = fine.len();
            choice.wall_seconds = start.elapsed().as_secs_f64();
            return Ok((fine, choice));
        }
        let unreached = |why: String| {
            format!(
                "solver.tol = {} cannot be reached in growth: the estimated elastic error was \
                 {error:.2e} with {} nodes (the largest over t = 0 and the snapshot times); {why}",
                crate::text::number(tol),
                fine.len()
            )
        };
        if choice.test_run_nodes.len() >= MAX_TEST_RUNS {
            return Err(unreached(format!(
                "{MAX_TEST_RUNS} test runs did not reach it"
            )));
        }
        let target = adapt::next_target(&worst, order, adapt::AIM * tol);
        let cap = solver.max_nodes.div_ceil(2);
        let next = adapt::equidistribute(&coarse, &worst.local, order, target, &floors, cap)
            .map_err(|_| {
                unreached(format!(
                    "the next mesh would need more than solver.max_nodes = {} nodes",
                    solver.max_nodes
                ))
            })?;
        fine = next.halved();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// M/2 read back as M gives M again, node for node, breakpoints included.
    #[test]
    fn the_parent_of_a_halved_mesh_is_the_mesh() {
        let p = Params::default();
        let s = SolverSettings {
            nodes: 31,
            ..SolverSettings::default()
        };
        let m = crate::bvp::solve::mesh_of(&p, &s).unwrap();
        let back = parent(&m.halved());
        assert_eq!(back.nodes, m.nodes);
        assert_eq!(back.breakpoint_nodes, m.breakpoint_nodes);
        assert_eq!(back.halved().nodes, m.halved().nodes);
    }
}
