//! The elastic boundary value problem in space (docs/MODEL.md §1–4): residuals of the two
//! schemes on the material nodes, the analytic banded Jacobian, the KINSOL driver and a
//! continuous interpolant of the solution.

/// The columns of `fields.csv` and `at.csv`, in order.
pub const COLUMNS: [&str; 14] = [
    "Sigma",
    "sigma",
    "kappa",
    "alpha_s",
    "r",
    "theta",
    "Q",
    "z",
    "s",
    "alpha_phi",
    "alpha_n",
    "h",
    "t_s",
    "t_phi",
];

/// Every field of the loaded shell at one material point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FieldRow {
    /// Σ: arclength in the initial shell.
    pub sigma_ref: f64,
    /// σ: arclength in the grown, unloaded shell.
    pub sigma: f64,
    pub kappa: f64,
    pub alpha_s: f64,
    pub r: f64,
    pub theta: f64,
    pub q: f64,
    pub z: f64,
    pub s: f64,
    pub alpha_phi: f64,
    pub alpha_n: f64,
    /// Loaded thickness h = ζ α_n.
    pub h: f64,
    pub t_s: f64,
    pub t_phi: f64,
}

impl FieldRow {
    /// The row of values in the order of [`COLUMNS`].
    pub fn from_values(v: [f64; 14]) -> FieldRow {
        let [sigma_ref, sigma, kappa, alpha_s, r, theta, q, z, s, alpha_phi, alpha_n, h, t_s, t_phi] =
            v;
        FieldRow {
            sigma_ref,
            sigma,
            kappa,
            alpha_s,
            r,
            theta,
            q,
            z,
            s,
            alpha_phi,
            alpha_n,
            h,
            t_s,
            t_phi,
        }
    }

    /// The values in the order of [`COLUMNS`].
    pub fn values(&self) -> [f64; 14] {
        [
            self.sigma_ref,
            self.sigma,
            self.kappa,
            self.alpha_s,
            self.r,
            self.theta,
            self.q,
            self.z,
            self.s,
            self.alpha_phi,
            self.alpha_n,
            self.h,
            self.t_s,
            self.t_phi,
        ]
    }
}

/// Solver diagnostics of one elastic solve (summary.json records every field by name:
/// eyeshell's `rundir::record`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveStats {
    pub newton_iterations: usize,
    pub residual_evaluations: usize,
    pub jacobian_evaluations: usize,
    /// KINSOL's final scaled residual norm (max norm).
    pub residual_norm: f64,
    /// max over nodes of |Q cos θ + r t_s sin θ − r² ΔP / 2| (docs/MODEL.md §3).
    pub first_integral_max: f64,
    /// All nodes of the mesh.
    pub nodes: usize,
    /// The uniform nodes asked for (solver.nodes).
    pub uniform_nodes: usize,
    /// Material breakpoints inserted as nodes.
    pub breakpoint_nodes: usize,
    /// Graded nodes inserted next to the pole.
    pub pole_nodes: usize,
    /// Graded nodes inserted next to the cornea (membrane limit).
    pub cornea_nodes: usize,
    /// Cornea stretch α from Adkins' equation.
    pub cornea_alpha: f64,
    /// Stages of pressure continuation used (0 when Newton converged directly).
    pub continuation_stages: usize,
    pub wall_seconds: f64,
    /// With solver.tol: the estimated global error of the reported solution.
    pub error_estimate: Option<ErrorEstimate>,
    /// With solver.tol: the meshes laid after the first.
    pub mesh_refinements: Option<usize>,
    /// With solver.tol: the nodes of each pass's reported (halved) mesh, the last the final.
    pub pass_nodes: Option<Vec<usize>>,
}

/// The estimated global error of a solution (solver.tol): the largest over the nodes of
/// each field's absolute error, in fields.csv's units, and the largest of the five.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorEstimate {
    pub kappa: f64,
    pub alpha_s: f64,
    pub r: f64,
    pub theta: f64,
    pub q: f64,
    pub overall: f64,
}

pub mod adapt;
pub mod bvp4c;
// The discretisation is public for the numerics tests and the benches (its residual and
// Jacobian are checked and timed directly), not as API.
#[doc(hidden)]
pub mod discretisation;
pub(crate) mod equations;
pub(crate) mod interpolant;
pub(crate) mod material;
pub mod settings;
pub mod solve;
pub use solve::Solution;

use crate::deadline::OutOfTime;
use crate::mesh::MeshError;
use crate::model::params::Params;
use crate::text::{decimals6, number};
use discretisation::EvalFailure;
use eyeshell_sundials::SundialsError;
use settings::SolverSettings;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BvpError {
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Sundials(#[from] SundialsError),
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error("Σ = {} is outside the shell [{}, {}]", number(*sigma), number(*lo), number(*hi))]
    OutOfRange { sigma: f64, lo: f64, hi: f64 },
    #[error("Newton did not converge at ΔP = {} after {iterations} iterations (scaled residual {residual_norm:.3e}); worst equation: {equation} at node {node} (Σ = {}): {reason}", number(*dp), decimals6(*sigma_ref))]
    NewtonFailed {
        dp: f64,
        iterations: usize,
        residual_norm: f64,
        node: usize,
        sigma_ref: f64,
        equation: &'static str,
        reason: String,
    },
    #[error("the equations cannot be evaluated at node {} (Σ = {}): {}", .0.node, decimals6(.0.sigma_ref), .0.why)]
    Evaluation(EvalFailure),
    #[error("Newton stalled at a scaled residual of {residual:.2e} on {nodes} nodes, its Newton correction only {step:.1e} (scaled): the residual's round-off; {newton} = {} is below what double precision reaches on this mesh: ask for {newton} = {} or more", number(*newton_tol), number(precision_reached(*residual)), newton = crate::names::Quantity::NewtonTolerance)]
    PrecisionLimit {
        newton_tol: f64,
        residual: f64,
        step: f64,
        nodes: usize,
    },
    #[error(transparent)]
    OutOfTime(#[from] OutOfTime),
    #[error("{0}")]
    Unreached(adapt::Unreached),
}

/// The newton_tol a stalled residual shows to be within reach: the power of ten above it.
fn precision_reached(residual: f64) -> f64 {
    10f64.powf(residual.log10().ceil())
}

impl BvpError {
    /// Did `solver.max_seconds` stop the solve? (Then nothing is tried again.)
    pub fn is_out_of_time(&self) -> bool {
        matches!(self, BvpError::OutOfTime(_))
    }

    /// Is there no point in a continuation after this? Out of time, or a Newton iterate
    /// already at the round-off of its residual (a gentler path reaches the same root).
    pub(crate) fn ends_continuation(&self) -> bool {
        matches!(
            self,
            BvpError::OutOfTime(_) | BvpError::PrecisionLimit { .. }
        )
    }
}

/// Solve the elastic BVP, warm-started from `warm` when given. With `solver.tol` (and no
/// warm start) the mesh is adapted to it, and with `solver.richardson` the extrapolated
/// solution is reported ([`adapt`]).
pub fn solve(
    params: &Params,
    settings: &SolverSettings,
    warm: Option<&Solution>,
) -> Result<Solution, BvpError> {
    if (settings.tol.is_some() || settings.richardson) && warm.is_none() {
        return adapt::solve_to_tolerance(params, settings);
    }
    solve::solve_on_mesh(params, settings, solve::mesh_of(params, settings)?, warm)
}
