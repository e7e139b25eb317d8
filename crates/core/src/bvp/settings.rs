//! The numerical settings of the elastic solve: scheme, linear solver, mesh and Newton
//! (solver.* keys). The model (docs/MODEL.md) knows nothing of them.

/// Which finite-difference scheme discretises the BVP (docs/MODEL.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Trapezoidal rule: order 2.
    Trapezoid,
    /// Hermite–Simpson = 3-stage Lobatto IIIA (bvp4c's scheme): order 4.
    HermiteSimpson,
}

impl Scheme {
    /// The scheme's classical order of accuracy.
    pub fn order(self) -> u32 {
        match self {
            Scheme::Trapezoid => 2,
            Scheme::HermiteSimpson => 4,
        }
    }
}

/// Which direct linear solver factors the Newton matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinearSolverKind {
    /// SUNDIALS band LU.
    Band,
    /// SuiteSparse KLU through SUNDIALS' sunlinsol_klu.
    Klu,
    /// The almost-block-diagonal LU of 5×5 node blocks (`linalg::AbdLu`), assembled
    /// straight into its blocks.
    Block,
}

/// solver.max_nodes' default.
pub const DEFAULT_MAX_NODES: usize = 200_000;

/// Numerical settings of one elastic solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// solver.nodes: number of uniform nodes on [ε, L]; breakpoints and pole nodes come on top.
    pub nodes: usize,
    /// solver.epsilon: pole truncation ε (mm).
    pub epsilon: f64,
    /// solver.scheme.
    pub scheme: Scheme,
    /// solver.linear (default: block).
    pub linear: LinearSolverKind,
    /// solver.newton_tol: KINSOL's tolerance on the scaled residual (max norm).
    pub newton_tol: f64,
    /// solver.max_newton: the most Newton iterations per solve.
    pub max_newton: usize,
    /// solver.pole_grading: insert geometrically graded nodes next to the pole (docs/MODEL.md §3 trap).
    pub pole_grading: bool,
    /// solver.cornea_grading: grade the nodes next to the cornea when the bending boundary
    /// layer there, of width √(E_b / t_s), is thinner than the mesh spacing (the membrane
    /// limit, small E_b).
    pub cornea_grading: bool,
    /// solver.max_seconds: the wall-clock bound on one solve (on a whole growth run, whose
    /// solves share it); None, the default, is no bound. See [`crate::deadline`].
    pub max_seconds: Option<f64>,
    /// When `max_seconds` counts from: None, each solver's creation; set by a job of
    /// several stages (an adaptive solve, a growth run with `tol`) to its start, so that
    /// all its solvers share one bound. Not a scene key.
    pub clock_start: Option<std::time::Instant>,
    /// solver.tol: the global error asked for; None, the default, lets `nodes` lay the mesh.
    /// When set, the mesh is adapted until the estimated error of every reported field
    /// (κ, α_s, r, θ, Q, absolute, in fields.csv's units) is at most tol
    /// ([`crate::bvp::adapt`]).
    pub tol: Option<f64>,
    /// solver.max_nodes: the most nodes an adapted mesh may have (its halved mesh's, the
    /// one reported).
    pub max_nodes: usize,
    /// solver.richardson: report Richardson's extrapolation of the solutions on M and M
    /// halved (order p + 2), with its error estimated from M halved twice.
    pub richardson: bool,
    /// The threads a growth round under `tol` may use for its three runs: 1 runs them one
    /// after another, 2 or more runs the two test runs beside the delivered one (a round
    /// has no more to share); None, the default, is 2 when the machine has a second core.
    /// The results are the same bit for bit. Not a scene key: `eyeshell grow --jobs`, or
    /// the environment's `EYESHELL_JOBS`.
    pub threads: Option<usize>,
    /// Newton to precision, within this absolute budget: a solve whose residual stalls at
    /// round-off above newton_tol has converged when its Newton correction is within
    /// newton_tol (scaled) or within the budget (in the fields' units). None, the default:
    /// such a stall is a precision limit, reported. Not a scene key: a growth run under
    /// `tol` sets it to a share of tol, as the adaptive elastic solve does.
    pub newton_budget: Option<f64>,
}

impl SolverSettings {
    /// These settings with `solver.max_seconds`' clock started: now, unless a job started
    /// it earlier. A job of several stages calls this once and hands the result on.
    pub fn clock_started(&self) -> SolverSettings {
        SolverSettings {
            clock_start: Some(self.clock_start.unwrap_or_else(std::time::Instant::now)),
            ..*self
        }
    }
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            nodes: 501,
            epsilon: 1e-3,
            scheme: Scheme::HermiteSimpson,
            // The fastest at every N from 51 to 20001, cold and warm (BENCHMARKS.md,
            // "The almost-block-diagonal solver").
            linear: LinearSolverKind::Block,
            newton_tol: 1e-10,
            max_newton: 50,
            pole_grading: true,
            cornea_grading: true,
            max_seconds: None,
            clock_start: None,
            tol: None,
            max_nodes: DEFAULT_MAX_NODES,
            richardson: false,
            threads: None,
            newton_budget: None,
        }
    }
}
