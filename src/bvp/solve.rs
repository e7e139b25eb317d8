//! PLACEHOLDER (being written): the KINSOL driver.
use super::{FieldRow, SolveStats};
use crate::model::params::{Params, SolverSettings};

#[derive(Debug, thiserror::Error)]
pub enum BvpError {
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Sundials(#[from] crate::sundials::SundialsError),
    #[error("Σ = {sigma} is outside the shell [{lo}, {hi}]")]
    OutOfRange { sigma: f64, lo: f64, hi: f64 },
}

/// A converged elastic state on the material nodes, with a continuous interpolant.
#[derive(Clone, Debug)]
pub struct Solution {
    pub rows: Vec<FieldRow>,
    pub stats: SolveStats,
}

impl Solution {
    /// Every field at the material point Σ = `sigma_ref` (cubic Hermite, like bvp4c's deval).
    pub fn at(&self, sigma_ref: f64) -> Result<FieldRow, BvpError> {
        let _ = sigma_ref;
        todo!()
    }
}

/// Solve the elastic BVP, warm-started from `warm` when given.
pub fn solve(params: &Params, settings: &SolverSettings, warm: Option<&Solution>) -> Result<Solution, BvpError> {
    let _ = (params, settings, warm);
    todo!()
}
