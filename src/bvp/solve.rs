//! The KINSOL driver for the elastic BVP (MODEL.md §3): Newton with a line search and the
//! analytic Jacobian, factored by band LU (or KLU); cold starts from the inflated reference
//! sphere, warm starts from a previous solution, and pressure continuation when a cold
//! start does not converge.

use super::discretisation::{Discretisation, EvalFailure, LOWER, NY, UPPER};
use super::equations::{self, Shell, Vec5, KAPPA, QS, R, THETA, TS};
use super::interpolant::{Interpolant, NQ};
use super::material::{reference_data, reference_point};
use super::{FieldRow, SolveStats};
use crate::mesh::Mesh;
use crate::model::constitutive::Law;
use crate::model::cornea;
use crate::model::params::{LinearSolverKind, Params, Scheme, SolverSettings};
use crate::model::profiles::{self, Side};
use crate::sundials::{
    CallbackError, CallbackResult, JacobianMatrix, Kinsol, KinsolOptions, KinsolStats, LinearSolverSpec,
    NonlinearSystem, Strategy, SundialsError,
};
use std::time::Instant;

#[derive(Debug, thiserror::Error)]
pub enum BvpError {
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Sundials(#[from] SundialsError),
    #[error("Σ = {sigma} is outside the shell [{lo}, {hi}]")]
    OutOfRange { sigma: f64, lo: f64, hi: f64 },
    #[error("Newton did not converge at ΔP = {dp} after {iterations} iterations (scaled residual {residual_norm:.3e}); worst equation: {equation} at node {node} (Σ = {sigma_ref:.6}): {reason}")]
    NewtonFailed {
        dp: f64,
        iterations: usize,
        residual_norm: f64,
        node: usize,
        sigma_ref: f64,
        equation: &'static str,
        reason: String,
    },
    #[error("the equations cannot be evaluated at node {} (Σ = {:.6}): {}", .0.node, .0.sigma_ref, .0.why)]
    Evaluation(EvalFailure),
}

/// The elastic system as KINSOL sees it.
struct ElasticSystem {
    disc: Discretisation,
    failure: Option<EvalFailure>,
}

impl ElasticSystem {
    fn record(&mut self, r: Result<(), EvalFailure>) -> CallbackResult {
        r.map_err(|e| {
            self.failure = Some(e);
            CallbackError::Recoverable(format!("cannot evaluate at node {} (Σ = {}): {}", e.node, e.sigma_ref, e.why))
        })
    }
}

impl NonlinearSystem for ElasticSystem {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        let r = self.disc.residual(u, f);
        self.record(r)
    }

    fn jacobian(&mut self, u: &[f64], jac: JacobianMatrix<'_>) -> CallbackResult {
        let r = match jac {
            JacobianMatrix::Band(mut m) => self.disc.jacobian(u, &mut m),
            JacobianMatrix::Sparse(mut m) => self.disc.jacobian(u, &mut m),
            JacobianMatrix::Dense(mut m) => self.disc.jacobian(u, &mut m),
        };
        self.record(r)
    }
}

/// A converged elastic state on the material nodes, with a continuous interpolant.
#[derive(Clone, Debug)]
pub struct Solution {
    pub params: Params,
    pub scheme: Scheme,
    pub mesh: Mesh,
    /// The unknowns, interleaved by node: (κ, r, θ, q_s, t_s) at Σ_0, Σ_1, …
    pub u: Vec<f64>,
    /// Every field at every node.
    pub rows: Vec<FieldRow>,
    pub interpolant: Interpolant,
    pub stats: SolveStats,
}

impl Solution {
    /// y = (κ, r, θ, q_s, t_s) at node i.
    pub fn y(&self, i: usize) -> Vec5 {
        Vec5::from_column_slice(&self.u[NY * i..NY * i + NY])
    }

    /// Every field at the material point Σ = `sigma_ref` (cubic Hermite, like bvp4c's deval).
    pub fn at(&self, sigma_ref: f64) -> Result<FieldRow, BvpError> {
        if let Some(k) = self.mesh.node_at(sigma_ref) {
            return Ok(self.rows[k]);
        }
        let i = self.mesh.locate(sigma_ref).ok_or(BvpError::OutOfRange {
            sigma: sigma_ref,
            lo: self.mesh.nodes[0],
            hi: *self.mesh.nodes.last().unwrap(),
        })?;
        let v = self.interpolant.eval(&self.mesh, i, sigma_ref);
        let mp = reference_point(&self.params, sigma_ref, Side::Above);
        let shell = shell_of(&self.params);
        let (a, _, _, t) = equations::stretch(&shell, &mp, v[R], v[TS], self.rows[i].alpha_s)
            .map_err(|why| BvpError::Evaluation(EvalFailure { node: i, sigma_ref, why }))?;
        Ok(field_row(&mp, &v, a, t.tphi))
    }
}

fn field_row(mp: &equations::MaterialPoint, v: &[f64; NQ], alpha_s: f64, t_phi: f64) -> FieldRow {
    let alpha_phi = v[R] / mp.rho;
    let alpha_n = 1.0 / (alpha_s * alpha_phi);
    FieldRow {
        sigma_ref: mp.sigma_ref,
        sigma: mp.sigma,
        kappa: v[KAPPA],
        alpha_s,
        r: v[R],
        theta: v[THETA],
        q: v[R] * v[QS],
        z: v[6],
        s: v[5],
        alpha_phi,
        alpha_n,
        h: mp.zeta * alpha_n,
        t_s: v[TS],
        t_phi,
    }
}

/// The constants of the equations for a parameter set; fibre terms only when D > 0.
pub fn shell_of(p: &Params) -> Shell {
    Shell { law: Law { c: p.c, d: p.has_fibres().then_some(p.d) }, e_b: p.e_b, dp: p.dp }
}

/// The mesh a scene asks for: uniform nodes, breakpoints and pole grading (MODEL.md §3–4).
pub fn mesh_of(p: &Params, s: &SolverSettings) -> Mesh {
    Mesh::new(s.epsilon, p.length(), s.nodes, &profiles::breakpoints(p), s.pole_grading)
}

/// The discrete problem for a parameter set on its mesh.
pub fn discretise(p: &Params, s: &SolverSettings) -> Result<Discretisation, BvpError> {
    let mesh = mesh_of(p, s);
    let edge = cornea::edge(&p.cornea, p.dp, p.length())?;
    let data = reference_data(p, &mesh);
    Ok(Discretisation::new(shell_of(p), s.scheme, mesh, data, edge))
}

/// The default initial guess: the reference sphere inflated by the cornea's stretch α,
/// carrying the Laplace tension t_s = ΔP α R0 / 2.
pub fn sphere_guess(disc: &Discretisation, r0: f64) -> Vec<f64> {
    let alpha = disc.edge.alpha;
    let ts = 0.5 * disc.shell.dp * alpha * r0;
    let mut u = Vec::with_capacity(disc.len());
    for mp in &disc.data.above {
        u.extend_from_slice(&[1.0 / (alpha * r0), alpha * mp.rho, mp.sigma / r0, 0.0, ts]);
    }
    u
}

fn kinsol_options(s: &SolverSettings) -> KinsolOptions {
    KinsolOptions {
        strategy: Strategy::LineSearch,
        fnorm_tol: s.newton_tol,
        scaled_step_tol: 1e-15,
        max_iterations: s.max_newton,
        max_setup_calls: 1,
        max_newton_step: None,
    }
}

fn linear_spec(disc: &Discretisation, kind: LinearSolverKind) -> LinearSolverSpec {
    match kind {
        LinearSolverKind::Band => LinearSolverSpec::Band { upper: UPPER, lower: LOWER },
        LinearSolverKind::Klu => {
            let (row_ptr, col_idx) = disc.pattern();
            LinearSolverSpec::Klu { row_ptr, col_idx }
        }
    }
}

/// Totals of the Newton work over all continuation stages.
#[derive(Default)]
struct Work {
    iterations: usize,
    residuals: usize,
    jacobians: usize,
    fnorm: f64,
}

impl Work {
    fn add(&mut self, k: &KinsolStats) {
        self.iterations += k.iterations;
        self.residuals += k.residual_evaluations;
        self.jacobians += k.jacobian_evaluations;
        self.fnorm = k.fnorm;
    }
}

/// Run Newton on `kin` from `u`; on failure, say where the residual is worst.
fn newton(kin: &mut Kinsol<ElasticSystem>, u: &mut [f64], r0: f64, work: &mut Work) -> Result<(), BvpError> {
    let (u_scale, f_scale) = kin.system().disc.scales(r0);
    kin.system_mut().failure = None;
    match kin.solve(u, &u_scale, &f_scale) {
        Ok(k) => {
            work.add(&k);
            Ok(())
        }
        Err(e) => {
            let k = kin.last_stats();
            work.add(&k);
            let sys = kin.system_mut();
            if let Some(f) = sys.failure {
                return Err(BvpError::Evaluation(f));
            }
            let mut f = vec![0.0; u.len()];
            let (mut worst, mut node, mut equation) = (f64::NAN, 0, "?");
            if sys.disc.residual(u, &mut f).is_ok() {
                let (row, val) = f
                    .iter()
                    .zip(&f_scale)
                    .map(|(a, b)| (a * b).abs())
                    .enumerate()
                    .fold((0, -1.0), |acc, (i, v)| if v > acc.1 { (i, v) } else { acc });
                worst = val;
                (node, equation) = sys.disc.locate_row(row);
            }
            Err(BvpError::NewtonFailed {
                dp: sys.disc.shell.dp,
                iterations: work.iterations,
                residual_norm: if worst.is_nan() { k.fnorm } else { worst },
                node,
                sigma_ref: sys.disc.mesh.nodes[node],
                equation,
                reason: e.to_string(),
            })
        }
    }
}

/// Solve the elastic BVP, warm-started from `warm` when given.
pub fn solve(params: &Params, settings: &SolverSettings, warm: Option<&Solution>) -> Result<Solution, BvpError> {
    let start = Instant::now();
    let disc = discretise(params, settings)?;
    let spec = linear_spec(&disc, settings.linear);
    let n = disc.len();
    let mut u = match warm {
        Some(w) => resample(w, &disc.mesh)?,
        None => sphere_guess(&disc, params.r0),
    };
    let mut kin = Kinsol::new(ElasticSystem { disc, failure: None }, n, spec, &kinsol_options(settings))?;
    let mut work = Work::default();
    let mut stages = 0;
    let first = newton(&mut kin, &mut u, params.r0, &mut work);
    if let Err(err) = first {
        // Pressure continuation from the unloaded sphere: each stage starts from the last.
        if warm.is_some() || params.dp == 0.0 {
            return Err(err);
        }
        let mut last_err = err;
        let mut ok = false;
        for count in [4usize, 16] {
            let mut failed = false;
            for k in 1..=count {
                let dp = params.dp * k as f64 / count as f64;
                let p = Params { dp, ..*params };
                let edge = cornea::edge(&p.cornea, dp, p.length())?;
                {
                    let d = &mut kin.system_mut().disc;
                    d.shell.dp = dp;
                    d.edge = edge;
                    if k == 1 {
                        u = sphere_guess(d, p.r0);
                    }
                }
                stages += 1;
                if let Err(e) = newton(&mut kin, &mut u, p.r0, &mut work) {
                    last_err = e;
                    failed = true;
                    break;
                }
            }
            if !failed {
                ok = true;
                break;
            }
        }
        if !ok {
            return Err(last_err);
        }
    }
    let disc = &mut kin.system_mut().disc;
    let mut sol = assemble_solution(params, settings, disc, &u)?;
    sol.stats.newton_iterations = work.iterations;
    sol.stats.residual_evaluations = work.residuals;
    sol.stats.jacobian_evaluations = work.jacobians;
    sol.stats.residual_norm = work.fnorm;
    sol.stats.continuation_stages = stages;
    sol.stats.wall_seconds = start.elapsed().as_secs_f64();
    Ok(sol)
}

/// A previous solution's unknowns at the nodes of `mesh`.
fn resample(w: &Solution, mesh: &Mesh) -> Result<Vec<f64>, BvpError> {
    if w.mesh.nodes == mesh.nodes {
        return Ok(w.u.clone());
    }
    let mut u = Vec::with_capacity(NY * mesh.len());
    let (lo, hi) = (w.mesh.nodes[0], *w.mesh.nodes.last().unwrap());
    for &x in &mesh.nodes {
        let row = w.at(x.clamp(lo, hi))?;
        u.extend_from_slice(&[row.kappa, row.r, row.theta, row.q / row.r, row.t_s]);
    }
    Ok(u)
}

/// Fields, quadratures (s, z) and the interpolant from the converged unknowns.
fn assemble_solution(params: &Params, settings: &SolverSettings, disc: &mut Discretisation, u: &[f64]) -> Result<Solution, BvpError> {
    let m = disc.mesh.len();
    let hs = disc.scheme == Scheme::HermiteSimpson;
    let edge = disc.edge;
    let dp = disc.shell.dp;
    let data = disc.data.clone();
    let mesh = disc.mesh.clone();
    let ev = disc.point_evaluations(u).map_err(BvpError::Evaluation)?;
    let y = |i: usize| Vec5::from_column_slice(&u[NY * i..NY * i + NY]);
    // ds/dΣ = γ α_s, dz/dΣ = −γ α_s sin θ.
    let ds = |g: f64, a: f64| g * a;
    let dz = |g: f64, a: f64, th: f64| -g * a * th.sin();
    let mut s = vec![0.0; m];
    let mut z = vec![0.0; m];
    s[0] = data.above[0].sigma * ev.left(0).alpha_s;
    let mut dzi = vec![0.0; m - 1];
    let mut slope_left = Vec::with_capacity(m - 1);
    let mut slope_right = Vec::with_capacity(m - 1);
    for i in 0..m - 1 {
        let h = mesh.step(i);
        let (ga, gb) = (data.above[i].gamma, data.below[i + 1].gamma);
        let (aa, ab) = (ev.left(i).alpha_s, ev.right(i).alpha_s);
        let (ta, tb) = (y(i)[THETA], y(i + 1)[THETA]);
        let (s_a, s_b, z_a, z_b) = (ds(ga, aa), ds(gb, ab), dz(ga, aa, ta), dz(gb, ab, tb));
        let (ds_i, dz_i) = if hs {
            let gm = data.mid[i].gamma;
            let am = ev.mid(i).alpha_s;
            let thm = ev.y_mid(i)[THETA];
            (
                h / 6.0 * (s_a + 4.0 * ds(gm, am) + s_b),
                h / 6.0 * (z_a + 4.0 * dz(gm, am, thm) + z_b),
            )
        } else {
            (0.5 * h * (s_a + s_b), 0.5 * h * (z_a + z_b))
        };
        s[i + 1] = s[i] + ds_i;
        dzi[i] = dz_i;
        let fl = ev.left(i).f;
        let fr = ev.right(i).f;
        slope_left.push([fl[0], fl[1], fl[2], fl[3], fl[4], s_a, z_a]);
        slope_right.push([fr[0], fr[1], fr[2], fr[3], fr[4], s_b, z_b]);
    }
    z[m - 1] = edge.z;
    for i in (0..m - 1).rev() {
        z[i] = z[i + 1] - dzi[i];
    }
    let values: Vec<[f64; NQ]> = (0..m)
        .map(|i| {
            let v = y(i);
            [v[0], v[1], v[2], v[3], v[4], s[i], z[i]]
        })
        .collect();
    // Node rows use the profile's own value at a breakpoint: the limit from below.
    let rows: Vec<FieldRow> = (0..m)
        .map(|i| {
            let (mp, e) = if i == 0 { (&data.above[0], ev.left(0)) } else { (&data.below[i], ev.right(i - 1)) };
            field_row(mp, &values[i], e.alpha_s, e.tensions.tphi)
        })
        .collect();
    let first_integral_max = (0..m).map(|i| equations::first_integral(dp, &y(i)).abs()).fold(0.0, f64::max);
    let stats = SolveStats {
        first_integral_max,
        nodes: m,
        uniform_nodes: mesh.uniform,
        breakpoint_nodes: mesh.inserted_breakpoints,
        pole_nodes: mesh.pole_nodes,
        cornea_alpha: edge.alpha,
        ..SolveStats::default()
    };
    Ok(Solution {
        params: *params,
        scheme: settings.scheme,
        mesh,
        u: u.to_vec(),
        rows,
        interpolant: Interpolant { values, slope_left, slope_right },
        stats,
    })
}
