//! The elastic problem's discrete equations F(u) = 0 in the user's hands: the residual and
//! the analytic Jacobian that KINSOL's Newton iteration uses (docs/MODEL.md §3; the
//! schemes of docs/guide/solver.md), so that a solution can be checked, or the
//! discretisation differentiated, outside eyeshell.
//!
//! The state u is the unknowns at the nodes of the mesh that `solver.nodes` lays (with its
//! breakpoint, pole and cornea nodes), interleaved by node: u = [y_0, y_1, …, y_{M−1}],
//! y = (κ, r, θ, q_s, t_s) with q_s = Q / r, 5 M numbers: a solution's
//! `u` ([`crate::Solution`]) is one. The
//! equations are, in order, the three pole conditions at Σ = ε (r = σ_ε α_s, θ = σ_ε α_s κ,
//! the first integral over r), five per interval (the scheme's step for κ, r, θ, q_s, t_s),
//! and the two cornea conditions at Σ = L (r = r*, θ = θ*). Newton stops when the largest
//! residual scaled by [`DiscreteProblem::scales`] is below `solver.newton_tol`.

use crate::bvp::discretisation::Discretisation;
use crate::bvp::solve::discretise;
use crate::text::number;
use crate::{Error, Origin, Scene, Subject};

/// The unknowns at a node, in order.
pub const UNKNOWNS: [&str; 5] = ["κ", "r", "θ", "q_s", "t_s"];

/// The scene's discrete elastic problem on the mesh of `solver.nodes`.
#[derive(Clone, Debug)]
pub struct DiscreteProblem {
    disc: Discretisation,
    f_scale: Vec<f64>,
}

/// A sparse matrix in compressed rows: row i holds the columns
/// `col_idx[row_ptr[i]..row_ptr[i + 1]]` (increasing) with the values beside them.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    pub n: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<usize>,
    pub values: Vec<f64>,
}

/// The values of a fixed pattern, written by the Jacobian's assembly.
struct PatternSink<'a>(&'a mut SparseMatrix);

impl eyeshell_linalg::MatrixSink for PatternSink<'_> {
    fn nrows(&self) -> usize {
        self.0.n
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        let m = &mut *self.0;
        let (a, b) = (m.row_ptr[i], m.row_ptr[i + 1]);
        // The assembly writes only its own pattern's entries.
        if let Ok(k) = m.col_idx[a..b].binary_search(&j) {
            m.values[a + k] = v;
        }
    }
}

impl Scene {
    /// The discrete equations of the scene's elastic problem, on the mesh `solver.nodes`
    /// lays. Refused when `solver.tol` or `solver.richardson` is set: their mesh is the
    /// adapted one, not known before the solve.
    pub fn discrete_problem(&self) -> Result<DiscreteProblem, Error> {
        if self.solver.tol.is_some() || self.solver.richardson {
            let key = if self.solver.tol.is_some() {
                "solver.tol"
            } else {
                "solver.richardson"
            };
            return Err(Error::input(
                Subject::Key(key.into()),
                format!(
                    "the scene sets {key}, whose mesh is adapted during the solve; the discrete \
                     equations are those of the mesh of solver.nodes (unset {key})"
                ),
            )
            .with_origin(Origin::Scene(self.origin.clone())));
        }
        let disc = discretise(&self.params, &self.solver)?;
        let (_, f_scale) = disc.scales(self.params.r0);
        Ok(DiscreteProblem { disc, f_scale })
    }
}

/// The equations cannot be evaluated at the state given: the caller's (r ≤ 0 at a node, a
/// stretch the membrane law cannot reach).
fn not_evaluable(e: crate::bvp::discretisation::EvalFailure) -> Error {
    Error::input(
        Subject::Argument("state".into()),
        crate::bvp::BvpError::Evaluation(e).to_string(),
    )
    .with_origin(Origin::Argument)
}

impl DiscreteProblem {
    /// The number of unknowns (and of equations), 5 × nodes.
    pub fn len(&self) -> usize {
        self.disc.len()
    }

    pub fn is_empty(&self) -> bool {
        self.disc.is_empty()
    }

    /// Σ at the mesh's nodes.
    pub fn nodes(&self) -> &[f64] {
        &self.disc.mesh.nodes
    }

    /// The equations' scales: Newton's convergence test is max_k |F_k(u)| · scale_k ≤
    /// `solver.newton_tol` (each row divided by the typical size of its unknown).
    pub fn scales(&self) -> &[f64] {
        &self.f_scale
    }

    /// Is `state` a state of this problem: 5 × nodes finite numbers?
    fn check(&self, state: &[f64]) -> Result<(), Error> {
        let (n, m) = (self.len(), self.disc.mesh.len());
        if state.len() != n {
            return Err(Error::input(
                Subject::Argument("state".into()),
                format!(
                    "the state has {} values; the scene's mesh has {m} nodes × 5 unknowns \
                     (κ, r, θ, q_s, t_s by node, as Solution.state) = {n}",
                    state.len()
                ),
            )
            .with_value(format!("{} values", state.len()))
            .with_origin(Origin::Argument));
        }
        if let Some(k) = state.iter().position(|v| !v.is_finite()) {
            return Err(Error::input(
                Subject::Argument("state".into()),
                format!(
                    "the state's value {k} ({} at node {}) is {}",
                    UNKNOWNS[k % 5],
                    k / 5,
                    number(state[k])
                ),
            )
            .with_value(number(state[k]))
            .with_origin(Origin::Argument));
        }
        Ok(())
    }

    /// F(state): the discrete equations' residuals, unscaled, in the order of the module's
    /// doc.
    pub fn residual(&mut self, state: &[f64]) -> Result<Vec<f64>, Error> {
        self.check(state)?;
        let mut f = vec![0.0; self.len()];
        self.disc.residual(state, &mut f).map_err(not_evaluable)?;
        Ok(f)
    }

    /// ∂F/∂u at `state`, the analytic Jacobian (every entry of its band pattern, zeros
    /// included).
    pub fn jacobian(&mut self, state: &[f64]) -> Result<SparseMatrix, Error> {
        self.check(state)?;
        let (row_ptr, col_idx) = self.disc.pattern();
        let mut m = SparseMatrix {
            n: self.len(),
            values: vec![0.0; col_idx.len()],
            row_ptr,
            col_idx,
        };
        self.disc
            .jacobian(state, &mut PatternSink(&mut m))
            .map_err(not_evaluable)?;
        Ok(m)
    }
}
