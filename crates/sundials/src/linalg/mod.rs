//! Linear algebra for the Newton systems of the coupled growth DAE, knowing
//! nothing of eyes: a CSR matrix with a fixed pattern that the Jacobian is assembled into,
//! a band matrix bordered by one dense row and column, and three direct solvers of the
//! assembled matrix:
//! - [`SchurSolver`]: eliminates 2×2 blocks of unknowns whose rows are local (block lower
//!   triangular among themselves), leaving a bordered band in the other unknowns;
//! - [`InterleavedBand`]: band LU of the whole matrix in a permuted (interleaved) order,
//!   with one unknown kept out as the border;
//! - [`KluSolver`]: SUNDIALS' KLU on the CSR matrix as it is;
//!
//! and [`Fallback`], which pairs a fast solver with a robust one for the factorisations
//! the fast one refuses.
//!
//! [`AbdLu`] factors the almost-block-diagonal Jacobians of the elastic BVP (5×5 node
//! blocks; KINSOL uses it through `LinearSolverSpec::Block`), [`AbdLu6`] the Schur
//! solver's reduced matrix S (6×6 node blocks, bordered: [`BorderedAbd`]) for
//! `Reduced::Block`.
//!
//! The band LU ([`BandLu`]) is safe Rust here; KLU is SUNDIALS' (through the safe layer
//! in `crate`).

mod abd;
mod band_lu;
mod bordered;
mod csr;
mod fallback;
mod schur;

pub use abd::{Abd, AbdLu, AbdLu6, NODE as ABD_NODE};
pub use band_lu::BandLu;
pub use bordered::{Bordered, BorderedAbd, BorderedBand, Bordering, InterleavedBand, KluSolver};
pub use csr::Csr;
pub use fallback::{Fallback, MakeSolver};
pub use schur::{Reduced, SchurSolver};

use crate::SundialsError;

/// Why a factorisation or solve failed.
#[derive(Debug, thiserror::Error)]
pub enum LinalgError {
    /// A pivot block or the border's Schur complement is (numerically) singular.
    #[error("singular matrix: {0}")]
    Singular(String),
    #[error(transparent)]
    Sundials(#[from] SundialsError),
    /// The assembler wrote entries outside the fixed pattern (a bug in the assembler).
    #[error("{0} entries were assembled outside the matrix's pattern")]
    OutsidePattern(usize),
    /// A solve with no successful factorisation since the matrix was last written.
    #[error("solve without a successful factorisation")]
    NotFactored,
    /// A matrix too large to store (its size or bandwidths are a mistake).
    #[error("matrix too large: {0}")]
    Size(String),
    /// A pattern that does not have the structure the solver needs.
    #[error("matrix structure: {0}")]
    Structure(String),
}

/// A direct solver of a matrix assembled into a [`Csr`].
pub trait DirectSolver {
    /// Factorise `a` (its values as assembled now; the pattern is the one given at creation).
    fn factor(&mut self, a: &Csr) -> Result<(), LinalgError>;
    /// x = A⁻¹ b with the last factorisation.
    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError>;
    /// Factorisations handed to a more robust solver so far ([`Fallback`]); 0 for others.
    fn fallbacks(&self) -> usize {
        0
    }
}
