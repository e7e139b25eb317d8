//! The KINSOL driver for the elastic BVP (docs/MODEL.md §3): Newton with a line search and the
//! analytic Jacobian, factored by band LU (or KLU); cold starts from the inflated reference
//! sphere, warm starts from a previous solution, and pressure continuation when a cold
//! start does not converge. The solve on one mesh ([`solve_on_mesh`]) and its pieces: a
//! leaf below the adaptive solve (`super::adapt`) and `super::solve`, which dispatches.

use super::discretisation::{
    Discretisation, EvalFailure, MaterialData, LOWER, NY, POLE_ROWS, UPPER,
};
use super::equations::{self, Shell, Vec5, KAPPA, QS, R, THETA, TS};
use super::interpolant::{Interpolant, NQ};
use super::material::{reference_data, reference_point};
use super::{BvpError, FieldRow, SolveStats};
use crate::bvp::settings::{LinearSolverKind, Scheme, SolverSettings};
use crate::deadline::Deadline;
use crate::mesh::{self, Mesh, MeshError};
use crate::model::cornea;
use crate::model::params::Params;
use crate::model::profiles::{self, Side};
use crate::text::number;
use eyeshell_sundials::{
    CallbackError, CallbackResult, JacobianMatrix, Kinsol, KinsolOptions, KinsolStats,
    LinearSolverSpec, NonlinearSystem, Strategy,
};
use std::time::Instant;

/// The elastic system as KINSOL sees it.
struct ElasticSystem {
    disc: Discretisation,
    failure: Option<EvalFailure>,
    /// Residual evaluations of the current Newton solve, and the most it may make.
    evaluations: usize,
    max_evaluations: usize,
    /// solver.max_seconds, and whether it stopped the current Newton solve.
    deadline: Deadline,
    out_of_time: bool,
    /// Whether an iterate whose residual stalls at round-off counts as converged
    /// ([`Convergence::ToPrecision`]), or is reported as a precision limit.
    convergence: Convergence,
}

/// What a Newton solve that stops short of solver.newton_tol may still deliver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Convergence {
    /// The scaled residual must reach newton_tol; a solve whose residual stalls above it
    /// with its Newton correction within newton_tol (round-off: u is the root as far as
    /// double precision finds it) is a [`BvpError::PrecisionLimit`], as the user asked for
    /// that residual.
    ToTolerance,
    /// Such a solve has converged: the adaptive solve's Newton tolerance is its own
    /// choice, and what bounds the error it leaves in u is the correction's size. So has
    /// one whose correction, as it stands, is within `budget` (a share of solver.tol): on
    /// a soft shell's fine mesh the residual's round-off (1e-11 scaled, at E_b = 1e-6 and
    /// C = 1 on 8,770 nodes) lies above the newton_tol of 1e-2·tol while the correction
    /// there is 1e-12, a hundredth of tol.
    ToPrecision { budget: f64 },
}

/// Residual evaluations one Newton solve may make per allowed iteration (solver.max_newton).
/// KINSOL bounds the iterations but not its line search inside one: on a hopeless problem
/// (E_b = 1e-200, a coefficient 1/E_b of 1e200) the search shrinks the step by tiny factors
/// down to a minimum near 1e-300 and evaluates the residual hundreds of times per
/// iteration, for minutes. A converging solve makes one or two per iteration.
const EVALUATIONS_PER_ITERATION: usize = 20;

impl ElasticSystem {
    /// Start the count of a new Newton solve of at most `max_iterations` iterations.
    fn start(&mut self, max_iterations: usize) {
        self.failure = None;
        self.out_of_time = false;
        self.evaluations = 0;
        self.max_evaluations = EVALUATIONS_PER_ITERATION.saturating_mul(max_iterations.max(1));
    }

    fn record(&mut self, r: Result<(), EvalFailure>) -> CallbackResult {
        r.map_err(|e| {
            self.failure = Some(e);
            CallbackError::Recoverable(format!(
                "cannot evaluate at node {} (Σ = {}): {}",
                e.node, e.sigma_ref, e.why
            ))
        })
    }
}

impl NonlinearSystem for ElasticSystem {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        if self.deadline.passed() {
            // Fatal: KINSOL stops at once (a recoverable error would only shorten the step).
            self.out_of_time = true;
            return Err(CallbackError::Fatal(format!(
                "{} reached",
                crate::names::Quantity::MaxSeconds
            )));
        }
        self.evaluations += 1;
        if self.evaluations > self.max_evaluations {
            return Err(CallbackError::Fatal(format!(
                "stopped after {} residual evaluations, the most one solve may make \
                 ({EVALUATIONS_PER_ITERATION} per iteration of solver.max_newton): the line \
                 search finds no step that lowers the residual",
                self.max_evaluations
            )));
        }
        let r = self.disc.residual(u, f);
        self.record(r)
    }

    fn jacobian(&mut self, u: &[f64], jac: JacobianMatrix<'_>) -> CallbackResult {
        let r = match jac {
            JacobianMatrix::Band(mut m) => self.disc.jacobian(u, &mut m),
            JacobianMatrix::Sparse(mut m) => self.disc.jacobian(u, &mut m),
            JacobianMatrix::Dense(mut m) => self.disc.jacobian(u, &mut m),
            JacobianMatrix::Block(m) => self.disc.jacobian(u, m),
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
    /// The unloaded shell's data when it has grown (None: the reference shell, whose data
    /// are known at every Σ). Between nodes `at` interpolates them from the node and
    /// midpoint values (quadratic with Hermite–Simpson's midpoints, else linear).
    pub grown: Option<MaterialData>,
}

impl Solution {
    /// The values of the field `name` (a column of fields.csv: `Sigma`, `kappa`, `r`, `z`,
    /// `theta`, `Q`, …; see [`super::COLUMNS`]) at every node, or None for an unknown name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let j = super::COLUMNS.iter().position(|&c| c == name)?;
        Some(self.rows.iter().map(|r| r.values()[j]).collect())
    }
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
        let mp = match &self.grown {
            None => reference_point(&self.params, sigma_ref, Side::Above),
            Some(data) => self.grown_point(data, i, sigma_ref),
        };
        let shell = shell_of(&self.params);
        let (a, _, _, t) = equations::stretch(&shell, &mp, v[R], v[TS], self.rows[i].alpha_s)
            .map_err(|why| {
                BvpError::Evaluation(EvalFailure {
                    node: i,
                    sigma_ref,
                    why,
                })
            })?;
        Ok(field_row(&mp, &v, a, t.tphi))
    }
}

impl Solution {
    /// A grown shell's data at Σ inside interval i, interpolated from its ends (and midpoint).
    fn grown_point(
        &self,
        data: &MaterialData,
        i: usize,
        sigma_ref: f64,
    ) -> equations::MaterialPoint {
        let (a, b) = (&data.above[i], &data.below[i + 1]);
        let t = (sigma_ref - self.mesh.nodes[i]) / self.mesh.step(i);
        let blend = |f: &dyn Fn(&equations::MaterialPoint) -> f64| match self.scheme {
            // Lagrange through t = 0, 1/2, 1.
            Scheme::HermiteSimpson => {
                let m = &data.mid[i];
                f(a) * (2.0 * t - 1.0) * (t - 1.0)
                    + f(m) * 4.0 * t * (1.0 - t)
                    + f(b) * t * (2.0 * t - 1.0)
            }
            Scheme::Trapezoid => f(a) * (1.0 - t) + f(b) * t,
        };
        equations::MaterialPoint {
            sigma_ref,
            sigma: blend(&|p| p.sigma),
            rho: blend(&|p| p.rho),
            zeta: blend(&|p| p.zeta),
            gamma: blend(&|p| p.gamma),
            fibre: reference_point(&self.params, sigma_ref, Side::Above).fibre,
        }
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
    Shell {
        law: crate::model::components::Membrane::of(p).law(),
        e_b: p.e_b,
        dp: p.dp,
    }
}

/// The width of the bending boundary layer at the cornea, √(E_b / t_s) with t_s ≈ ΔP R0 / 2
/// (bounded below by 10⁻³ C H0 so that it stays finite without pressure), when the mesh
/// grades nodes into it: with `solver.cornea_grading` and a layer thinner than the spacing.
pub(crate) fn cornea_layer(p: &Params, s: &SolverSettings) -> Option<f64> {
    let layer = (p.e_b / (0.5 * p.dp * p.r0).max(1e-3 * p.c * p.h0)).sqrt();
    let h = (p.length() - s.epsilon) / (s.nodes.max(2) - 1) as f64;
    (s.cornea_grading && !(layer >= h)).then_some(layer)
}

/// The node counts of the mesh a scene asks for, checked before anything is allocated
/// (scene validation calls this, so a mesh that cannot be laid is the user's error).
pub fn mesh_plan(p: &Params, s: &SolverSettings) -> Result<mesh::Plan, MeshError> {
    mesh::plan(
        s.epsilon,
        p.length(),
        s.nodes,
        s.pole_grading,
        cornea_layer(p, s),
    )
}

/// The mesh a scene asks for: uniform nodes, breakpoints and pole grading (docs/MODEL.md §3–4),
/// and the cornea's grading into its bending layer.
pub fn mesh_of(p: &Params, s: &SolverSettings) -> Result<Mesh, MeshError> {
    mesh_plan(p, s)?;
    let mesh = Mesh::new(
        s.epsilon,
        p.length(),
        s.nodes,
        &profiles::breakpoints(p),
        s.pole_grading,
    )?;
    match cornea_layer(p, s) {
        Some(layer) => mesh.grade_cornea(layer),
        None => Ok(mesh),
    }
}

/// The discrete problem for a parameter set on its mesh.
pub fn discretise(p: &Params, s: &SolverSettings) -> Result<Discretisation, BvpError> {
    discretise_on(p, s, mesh_of(p, s)?)
}

/// The discrete problem on a given mesh (which must hold the scene's breakpoints).
pub fn discretise_on(
    p: &Params,
    s: &SolverSettings,
    mesh: Mesh,
) -> Result<Discretisation, BvpError> {
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
        reuse_factorization: false,
    }
}

/// The linear solver for a discretisation: band (its bandwidths), KLU (its pattern) or the
/// almost-block-diagonal LU (its nodes and pole rows).
pub fn linear_spec(disc: &Discretisation, kind: LinearSolverKind) -> LinearSolverSpec {
    match kind {
        LinearSolverKind::Band => LinearSolverSpec::Band {
            upper: UPPER,
            lower: LOWER,
        },
        LinearSolverKind::Klu => {
            let (row_ptr, col_idx) = disc.pattern();
            LinearSolverSpec::Klu { row_ptr, col_idx }
        }
        LinearSolverKind::Block => LinearSolverSpec::Block {
            nodes: disc.mesh.len(),
            top: POLE_ROWS,
        },
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
///
/// KINSOL stops once the scaled residual of every row is below the tolerance; the rows of
/// the intervals are increments, so the error left in u can be that tolerance times the
/// number of intervals (measured: 8e-10 in Q at 8705 nodes and 1e-12). One more Newton
/// correction with the factorisation KINSOL already holds removes it (a residual and a
/// back-substitution, no new LU).
fn newton(
    kin: &mut Kinsol<ElasticSystem>,
    u: &mut [f64],
    r0: f64,
    work: &mut Work,
    polished: bool,
    stage: Stage,
) -> Result<(), BvpError> {
    let (u_scale, f_scale) = kin.system().disc.scales(r0);
    let max_iterations = kin.options().max_iterations;
    kin.system_mut().start(max_iterations);
    match kin.solve(u, &u_scale, &f_scale) {
        Ok(k) => {
            work.add(&k);
            // Only after a solve that factored at its own iterates (see `polish`).
            if polished && k.iterations > 0 {
                polish(kin, u, &f_scale);
            }
            Ok(())
        }
        Err(e) => {
            let k = kin.last_stats();
            work.add(&k);
            let newton_tol = kin.options().fnorm_tol;
            let sys = kin.system_mut();
            if sys.out_of_time {
                let n = k.iterations;
                let place = format!("in {stage}, after {n} Newton iteration{}", plural(n));
                return Err(sys.deadline.reached(place).into());
            }
            // Where KINSOL stopped. Its line search fails when no step lowers ‖F‖ any more,
            // which near a root is round-off, not divergence: so the iterate is judged by
            // its own residual and Newton correction before the failure is believed (and an
            // evaluation that failed at a trial point of the search is the cause only when
            // the iterate is no root).
            let mut f = vec![0.0; u.len()];
            let (mut worst, mut node, mut equation) = (f64::NAN, 0, "?");
            let evaluated = sys.disc.residual(u, &mut f).is_ok();
            if evaluated {
                let (row, val) = f
                    .iter()
                    .zip(&f_scale)
                    .map(|(a, b)| (a * b).abs())
                    .enumerate()
                    .fold(
                        (0, -1.0),
                        |acc, (i, v)| if v > acc.1 { (i, v) } else { acc },
                    );
                worst = val;
                (node, equation) = sys.disc.locate_row(row);
                // KINSOL's own test (the max norm of the scaled residual), which its line
                // search can fail before making.
                if worst <= newton_tol {
                    return Ok(());
                }
                // The residual stalled above newton_tol. If the Newton correction there is
                // within newton_tol (or round-off) of the unknowns' scale, u is the root as
                // far as the residual's round-off lets it be found: a precision limit, not
                // divergence. To precision, a correction within the error budget is enough.
                if let Some(step) = newton_correction(kin, u, &f, &u_scale) {
                    let sys = kin.system();
                    let budget = match sys.convergence {
                        Convergence::ToPrecision { budget } => budget,
                        Convergence::ToTolerance => 0.0,
                    };
                    let within_budget =
                        step.absolute <= budget && worst <= BUDGET_RESIDUAL_SPAN * newton_tol;
                    if step.scaled <= newton_tol.max(ROUND_OFF_STEP) || within_budget {
                        return match sys.convergence {
                            Convergence::ToPrecision { .. } => Ok(()),
                            Convergence::ToTolerance => Err(BvpError::PrecisionLimit {
                                newton_tol,
                                residual: worst,
                                step: step.scaled,
                                nodes: sys.disc.mesh.len(),
                            }),
                        };
                    }
                }
            }
            let sys = kin.system_mut();
            if let Some(f) = sys.failure {
                return Err(BvpError::Evaluation(f));
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

/// A Newton correction this small (scaled: a thousand ulps of the unknowns' typical size)
/// is round-off, whatever newton_tol asked for.
const ROUND_OFF_STEP: f64 = 1e3 * f64::EPSILON;

/// The size of a Newton correction δ = J⁻¹F: scaled as KINSOL scales the unknowns (max norm
/// of |δ_j| · u_scale_j), and as it stands (max |δ_j|, in the fields' own units, which
/// solver.tol bounds).
struct Correction {
    scaled: f64,
    absolute: f64,
}

/// The Newton correction J⁻¹F at u, with the factorisation of KINSOL's last setup: after a
/// failed line search, the Jacobian at u itself (KINSOL sets up at every iteration's
/// start). None when that solve fails.
fn newton_correction(
    kin: &mut Kinsol<ElasticSystem>,
    u: &[f64],
    f: &[f64],
    u_scale: &[f64],
) -> Option<Correction> {
    let mut dx = vec![0.0; u.len()];
    kin.solve_with_last_factorization(&mut dx, f).ok()?;
    let scaled = dx
        .iter()
        .zip(u_scale)
        .fold(0.0f64, |a, (d, s)| a.max((d * s).abs()));
    let absolute = dx.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    (scaled.is_finite() && absolute.is_finite()).then_some(Correction { scaled, absolute })
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// The paper's bending stiffness E_b, the easy end of a bending continuation.
const DEFAULT_BENDING: f64 = 18.0;

/// Which Newton solve of [`ElasticSolver`] is running: what a message of
/// `solver.max_seconds` says.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    /// From the inflated sphere, a warm start, or growth's re-solves.
    Direct,
    /// Stage `k` of `n` of the pressure continuation, at ΔP = `dp`.
    Pressure { k: usize, n: usize, dp: f64 },
    /// Stage `k` of `n` of the continuation in D and E_b at full pressure.
    Material { k: usize, n: usize },
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Stage::Direct => f.write_str("the elastic solve"),
            Stage::Pressure { k, n, dp } => write!(
                f,
                "the elastic solve, stage {k} of {n} of the pressure continuation (ΔP = {})",
                number(dp)
            ),
            Stage::Material { k, n } => write!(
                f,
                "the elastic solve, stage {k} of {n} of the continuation in D and E_b"
            ),
        }
    }
}

/// An elastic solver that lives across solves: KINSOL, its matrix and factorisation, the
/// discretisation and the last converged unknowns. Growth re-solves it at every change of
/// the unloaded shell, warm-started from the last solution.
pub struct ElasticSolver {
    kin: Kinsol<ElasticSystem>,
    params: Params,
    settings: SolverSettings,
    /// The current unknowns (the last converged state after a successful solve).
    pub u: Vec<f64>,
    work: Work,
    stage: Stage,
}

impl ElasticSolver {
    /// The solver for the reference (ungrown) shell, starting from the inflated sphere.
    pub fn new(params: &Params, settings: &SolverSettings) -> Result<Self, BvpError> {
        Self::on_mesh(params, settings, mesh_of(params, settings)?)
    }

    /// The same on a given mesh, e.g. a [`Mesh::halved`] one for Richardson extrapolation.
    pub fn on_mesh(
        params: &Params,
        settings: &SolverSettings,
        mesh: Mesh,
    ) -> Result<Self, BvpError> {
        let convergence = match settings.newton_budget {
            Some(budget) => Convergence::ToPrecision { budget },
            None => Convergence::ToTolerance,
        };
        Self::on_mesh_to(params, settings, mesh, convergence)
    }

    /// [`Self::on_mesh`], its Newton solves converging as `convergence` says.
    pub(crate) fn on_mesh_to(
        params: &Params,
        settings: &SolverSettings,
        mesh: Mesh,
        convergence: Convergence,
    ) -> Result<Self, BvpError> {
        let disc = discretise_on(params, settings, mesh)?;
        let spec = linear_spec(&disc, settings.linear);
        let n = disc.len();
        let u = sphere_guess(&disc, params.r0);
        let kin = Kinsol::new(
            ElasticSystem {
                disc,
                failure: None,
                evaluations: 0,
                max_evaluations: usize::MAX,
                deadline: Deadline::since(settings.clock_start, settings.max_seconds),
                out_of_time: false,
                convergence,
            },
            n,
            spec,
            &kinsol_options(settings),
        )?;
        Ok(ElasticSolver {
            kin,
            params: *params,
            settings: *settings,
            u,
            work: Work::default(),
            stage: Stage::Direct,
        })
    }

    /// `solver.max_seconds` of this solver, set when it was made: every Newton solve it makes
    /// (a growth run's, all of them) stops once it has passed.
    pub fn deadline(&self) -> Deadline {
        self.kin.system().deadline
    }

    /// The shell's parameters.
    pub fn params(&self) -> Params {
        self.params
    }

    pub fn discretisation(&self) -> &Discretisation {
        &self.kin.system().disc
    }

    pub fn discretisation_mut(&mut self) -> &mut Discretisation {
        &mut self.kin.system_mut().disc
    }

    /// Newton from the current unknowns; on success they hold the root. A one-shot solve
    /// ends with a polishing correction; growth's re-solves (`set_jacobian_reuse`) do not,
    /// as their accuracy is far below CVODE's tolerances and their factorisations are reused.
    /// If modified Newton fails, the solve is retried once from the same start by exact
    /// Newton with the line search.
    pub fn newton(&mut self) -> Result<(), BvpError> {
        let reusing = self.kin.options().reuse_factorization;
        let start = reusing.then(|| self.u.clone());
        let ElasticSolver {
            kin,
            u,
            work,
            params,
            stage,
            ..
        } = self;
        let first = newton(kin, u, params.r0, work, !reusing, *stage);
        let (Err(e), Some(start)) = (&first, start) else {
            return first;
        };
        if e.is_out_of_time() {
            return first;
        }
        let reuse = self.kin.options().clone();
        self.kin.set_options(&kinsol_options(&self.settings))?;
        self.u = start;
        let ElasticSolver {
            kin,
            u,
            work,
            params,
            stage,
            ..
        } = self;
        let retry = newton(kin, u, params.r0, work, false, *stage);
        self.kin.set_options(&reuse)?;
        retry
    }

    /// For a sequence of nearby problems (growth): start each Newton solve from the previous
    /// factorisation and refactor only every `refactor_every` iterations (modified Newton),
    /// or go back to exact Newton with `None`.
    ///
    /// Modified Newton runs without KINSOL's line search: with a factorisation carried over
    /// (KINSetNoInitSetup) a failed line search made KINSOL 6.4 spin inside KINSol for ever
    /// (seen with η0 = 1e4: it never called back again). Plain steps from a warm start
    /// converge as fast (const scene: the same 597 iterations), and a failure falls back to
    /// exact Newton with the line search (see [`Self::newton`]).
    pub fn set_jacobian_reuse(&mut self, refactor_every: Option<usize>) -> Result<(), BvpError> {
        let mut options = kinsol_options(&self.settings);
        if let Some(k) = refactor_every {
            options.reuse_factorization = true;
            options.max_setup_calls = k.max(1);
            options.strategy = Strategy::Newton;
        }
        self.kin.set_options(&options)?;
        Ok(())
    }

    /// Newton iterations (and residual, Jacobian evaluations) since the solver was made.
    pub fn newton_iterations(&self) -> usize {
        self.work.iterations
    }

    /// A cold start: from the inflated sphere, with pressure continuation if Newton fails.
    /// Returns the number of continuation stages used.
    pub fn solve_cold(&mut self) -> Result<usize, BvpError> {
        let solved = self.continue_from_sphere();
        // Later solves (growth's) are direct, whatever stage this one ended in.
        self.stage = Stage::Direct;
        solved
    }

    fn continue_from_sphere(&mut self) -> Result<usize, BvpError> {
        self.u = sphere_guess(self.discretisation(), self.params.r0);
        let err = match self.newton() {
            Ok(()) => return Ok(0),
            Err(e) if self.params.dp == 0.0 || e.ends_continuation() => return Err(e),
            Err(e) => e,
        };
        // Pressure continuation from the unloaded sphere: each stage starts from the last.
        let mut last_err = err;
        let mut stages = 0;
        for count in [4usize, 16] {
            match self.ramp_pressure(count, &mut stages) {
                Ok(()) => return Ok(stages),
                Err(e) if e.ends_continuation() => return Err(e),
                Err(e) => last_err = e,
            }
        }
        self.set_pressure(self.params.dp)?;
        // Then continuation in the hard material parameters at full pressure: the fibres
        // stiffened from D = 0, the bending stiffness brought down from the paper's E_b.
        if self.params.d > 0.0 || self.params.e_b < DEFAULT_BENDING {
            for count in [8usize, 32] {
                match self.ramp_material(count, &mut stages) {
                    Ok(()) => return Ok(stages),
                    Err(e) if e.ends_continuation() => return Err(e),
                    Err(e) => last_err = e,
                }
            }
            self.set_material(1.0);
        }
        Err(last_err)
    }

    /// The shell's D and E_b at fraction s of the way from the easy shell (D = 0,
    /// E_b = max(E_b, 18)) to the scene's; s = 1 is the scene.
    fn set_material(&mut self, s: f64) {
        let (d, e_b) = (self.params.d, self.params.e_b);
        let easy = e_b.max(DEFAULT_BENDING);
        let shell = &mut self.discretisation_mut().shell;
        shell.law.d = (d > 0.0).then_some(d * s);
        shell.e_b = easy.powf(1.0 - s) * e_b.powf(s);
        let data = self.discretisation().data.clone();
        self.discretisation_mut().set_data(data); // drop evaluations of the old shell
    }

    fn ramp_material(&mut self, count: usize, stages: &mut usize) -> Result<(), BvpError> {
        self.u = sphere_guess(self.discretisation(), self.params.r0);
        for k in 0..=count {
            self.set_material(k as f64 / count as f64);
            *stages += 1;
            self.stage = Stage::Material {
                k: k + 1,
                n: count + 1,
            };
            self.newton()?;
        }
        Ok(())
    }

    fn set_pressure(&mut self, dp: f64) -> Result<(), BvpError> {
        let edge = cornea::edge(&self.params.cornea, dp, self.params.length())?;
        let d = self.discretisation_mut();
        d.shell.dp = dp;
        d.edge = edge;
        d.set_data(d.data.clone()); // drop evaluations taken at the old pressure
        Ok(())
    }

    fn ramp_pressure(&mut self, count: usize, stages: &mut usize) -> Result<(), BvpError> {
        for k in 1..=count {
            let dp = self.params.dp * k as f64 / count as f64;
            self.set_pressure(dp)?;
            if k == 1 {
                self.u = sphere_guess(self.discretisation(), self.params.r0);
            }
            *stages += 1;
            self.stage = Stage::Pressure { k, n: count, dp };
            self.newton()?;
        }
        Ok(())
    }

    /// The converged state with every field, its interpolant and the work so far.
    pub fn solution(&mut self) -> Result<Solution, BvpError> {
        let (params, settings) = (self.params, self.settings);
        let u = self.u.clone();
        let mut sol = assemble_solution(&params, &settings, self.discretisation_mut(), &u)?;
        sol.stats.newton_iterations = self.work.iterations;
        sol.stats.residual_evaluations = self.work.residuals;
        sol.stats.jacobian_evaluations = self.work.jacobians;
        sol.stats.residual_norm = self.work.fnorm;
        Ok(sol)
    }
}

/// One Newton correction u ← u − J⁻¹ F(u) with the last factorisation, kept only if it
/// lowers the scaled residual (the factorisation may be from an earlier state when it is
/// being reused); u is left as it was otherwise.
fn polish(kin: &mut Kinsol<ElasticSystem>, u: &mut [f64], f_scale: &[f64]) {
    let norm = |f: &[f64]| {
        f.iter()
            .zip(f_scale)
            .fold(0.0f64, |a, (x, s)| a.max((x * s).abs()))
    };
    let disc = &mut kin.system_mut().disc;
    let mut f = vec![0.0; u.len()];
    if disc.residual(u, &mut f).is_err() {
        return;
    }
    let before = norm(&f);
    let mut dx = vec![0.0; u.len()];
    if kin.solve_with_last_factorization(&mut dx, &f).is_err() {
        return;
    }
    let trial: Vec<f64> = u.iter().zip(&dx).map(|(a, d)| a - d).collect();
    if kin.system_mut().disc.residual(&trial, &mut f).is_ok() && norm(&f) < before {
        u.copy_from_slice(&trial);
    }
}

/// Solve on a given mesh (it must hold the scene's breakpoints as nodes).
pub fn solve_on_mesh(
    params: &Params,
    settings: &SolverSettings,
    mesh: Mesh,
    warm: Option<&Solution>,
) -> Result<Solution, BvpError> {
    solve_on_mesh_to(params, settings, mesh, warm, Convergence::ToTolerance)
}

/// The share of solver.tol a stalled Newton correction may be within to count as converged
/// in the adaptive solve and in a growth run under tol ([`Convergence::ToPrecision`]).
pub(crate) const NEWTON_SHARE: f64 = 0.02;

/// How far above newton_tol a stalled residual may lie for the correction's budget to be
/// believed: the correction is taken with the last setup's factorisation, which far from
/// the root may understate it (E_b = 1e-6, D = 1e4, C = 1 on 57 nodes stalled at a scaled
/// residual of 4e-7 with a correction of 2e-9, and the next mesh's Newton started from it
/// failed). The stalls the budget is for lie within a few tens of newton_tol.
const BUDGET_RESIDUAL_SPAN: f64 = 1e3;

/// [`solve_on_mesh`] for the adaptive solve: Newton converges to precision
/// ([`Convergence::ToPrecision`]), and a warm start that fails (a coarse mesh's
/// interpolant can lie outside the new mesh's basin: a soft shell's cornea layer it did
/// not resolve) starts again cold, with the continuation of [`ElasticSolver::solve_cold`].
pub(crate) fn solve_on_mesh_adaptive(
    params: &Params,
    settings: &SolverSettings,
    mesh: Mesh,
    warm: Option<&Solution>,
) -> Result<Solution, BvpError> {
    let to = Convergence::ToPrecision {
        budget: settings
            .newton_budget
            .or(settings.tol.map(|t| NEWTON_SHARE * t))
            .unwrap_or(0.0),
    };
    match solve_on_mesh_to(params, settings, mesh.clone(), warm, to) {
        Err(e) if warm.is_some() && !e.is_out_of_time() => {
            solve_on_mesh_to(params, settings, mesh, None, to).map_err(|_| e)
        }
        solved => solved,
    }
}

fn solve_on_mesh_to(
    params: &Params,
    settings: &SolverSettings,
    mesh: Mesh,
    warm: Option<&Solution>,
    convergence: Convergence,
) -> Result<Solution, BvpError> {
    let start = Instant::now();
    let mut solver = ElasticSolver::on_mesh_to(params, settings, mesh, convergence)?;
    let stages = match warm {
        Some(w) => {
            solver.u = resample(w, &solver.discretisation().mesh)?;
            solver.newton()?;
            0
        }
        None => solver.solve_cold()?,
    };
    let mut sol = solver.solution()?;
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
fn assemble_solution(
    params: &Params,
    settings: &SolverSettings,
    disc: &mut Discretisation,
    u: &[f64],
) -> Result<Solution, BvpError> {
    let quad = disc.quadratures(u).map_err(BvpError::Evaluation)?;
    let m = disc.mesh.len();
    disc.evaluate_at(u).map_err(BvpError::Evaluation)?;
    let ev = disc.evaluations();
    let y = |i: usize| Vec5::from_column_slice(&u[NY * i..NY * i + NY]);
    let values: Vec<[f64; NQ]> = (0..m)
        .map(|i| {
            let v = y(i);
            [v[0], v[1], v[2], v[3], v[4], quad.s[i], quad.z[i]]
        })
        .collect();
    let slope = |f: &Vec5, q: &[f64; 2]| [f[0], f[1], f[2], f[3], f[4], q[0], q[1]];
    let slope_left = (0..m - 1)
        .map(|i| slope(&ev.left(i).f, &quad.slope_left[i]))
        .collect();
    let slope_right = (0..m - 1)
        .map(|i| slope(&ev.right(i).f, &quad.slope_right[i]))
        .collect();
    // Node rows use the profile's own value at a breakpoint: the limit from below.
    let data = &disc.data;
    let rows: Vec<FieldRow> = (0..m)
        .map(|i| {
            let (mp, e) = if i == 0 {
                (&data.above[0], ev.left(0))
            } else {
                (&data.below[i], ev.right(i - 1))
            };
            field_row(mp, &values[i], e.alpha_s, e.tensions.tphi)
        })
        .collect();
    let dp = disc.shell.dp;
    let first_integral_max = (0..m)
        .map(|i| equations::first_integral(dp, &y(i)).abs())
        .fold(0.0, f64::max);
    let mesh = disc.mesh.clone();
    let stats = SolveStats {
        first_integral_max,
        nodes: m,
        uniform_nodes: mesh.uniform,
        breakpoint_nodes: mesh.inserted_breakpoints,
        pole_nodes: mesh.pole_nodes,
        cornea_nodes: mesh.cornea_nodes,
        cornea_alpha: disc.edge.alpha,
        ..SolveStats::default()
    };
    Ok(Solution {
        params: *params,
        scheme: settings.scheme,
        mesh,
        u: u.to_vec(),
        rows,
        interpolant: Interpolant {
            values,
            slope_left,
            slope_right,
        },
        stats,
        grown: (!is_reference(params, data)).then(|| data.clone()),
    })
}

/// True when `data` is the ungrown reference shell of `params` (so `Solution::at` may
/// evaluate the material data at any Σ).
fn is_reference(params: &Params, data: &super::discretisation::MaterialData) -> bool {
    data.above
        .iter()
        .all(|mp| *mp == reference_point(params, mp.sigma_ref, Side::Above))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_says_which_solve_of_the_continuation() {
        assert_eq!(Stage::Direct.to_string(), "the elastic solve");
        assert_eq!(
            Stage::Pressure {
                k: 3,
                n: 16,
                dp: 0.75
            }
            .to_string(),
            "the elastic solve, stage 3 of 16 of the pressure continuation (ΔP = 0.75)"
        );
        assert_eq!(
            Stage::Material { k: 9, n: 33 }.to_string(),
            "the elastic solve, stage 9 of 33 of the continuation in D and E_b"
        );
    }
}
