//! Direct solvers for square sparse matrices with structure, in safe Rust, knowing nothing
//! of where the matrices come from: a CSR matrix with a fixed pattern that a caller
//! assembles into ([`Csr`]), a matrix bordered by one dense row and column
//! ([`Bordered`]), and direct solvers of the assembled matrix ([`DirectSolver`]):
//! - [`SchurSolver`]: eliminates 2×2 blocks of unknowns whose rows are local (block lower
//!   triangular among themselves), leaving a bordered band in the other unknowns;
//! - [`InterleavedBand`]: band LU of the whole matrix in a permuted (interleaved) order,
//!   with one unknown kept out as the border;
//! - [`Fallback`], which pairs a fast solver with a robust one for the factorisations
//!   the fast one refuses.
//!
//! The factorisations under them: [`BandLu`] (band LU with partial pivoting) and
//! [`Abd`], the LU of almost-block-diagonal matrices with N×N node blocks ([`AbdLu`],
//! N = 5; [`AbdLu6`], N = 6, also bordered: [`BorderedAbd`]). Each matrix's `factor`
//! returns its factors ([`BandFactors`], [`AbdFactors`], [`BorderedFactors`]), and only
//! factors solve: a solve without a factorisation, or with a right side of the wrong
//! length, is an error ([`LinalgError::Length`]) or cannot be written, never a panic.
//!
//! A sparse LU from elsewhere plugs in as a [`DirectSolver`] (eyeshell-sundials adapts
//! SUNDIALS' KLU so, and hands it to [`SchurSolver`] as [`Reduced::Sparse`]); its errors
//! arrive as [`LinalgError::Backend`]. Matrices are written through [`MatrixSink`], the
//! one interface assemblers write into, whatever the storage behind it.

mod abd;
mod band_lu;
mod bordered;
mod csr;
mod fallback;
mod schur;

pub use abd::{Abd, AbdFactors, AbdLu, AbdLu6, AbdLu6Factors, AbdLuFactors, NODE as ABD_NODE};
pub use band_lu::{BandFactors, BandLu};
pub use bordered::{
    Bordered, BorderedAbd, BorderedBand, BorderedFactors, Bordering, InterleavedBand, Solve,
};
pub use csr::Csr;
pub use fallback::{Fallback, MakeSolver};
pub use schur::{MakeSparse, Reduced, SchurSolver};

/// A matrix an assembler writes into, entry by entry or a dense block at a time, whatever
/// its storage (band, almost block diagonal, or a library's own matrix). `set` overwrites.
pub trait MatrixSink {
    fn nrows(&self) -> usize;
    fn set(&mut self, i: usize, j: usize, v: f64);

    /// Set the dense sub-block of `values.len() / ncols` rows from row `row0` and `ncols`
    /// columns from column `col0` (row-major `values`). The default sets entry by entry; a
    /// block matrix copies an interval's block whole.
    fn set_block(&mut self, row0: usize, col0: usize, ncols: usize, values: &[f64]) {
        for (a, row) in values.chunks_exact(ncols).enumerate() {
            for (b, &v) in row.iter().enumerate() {
                self.set(row0 + a, col0 + b, v);
            }
        }
    }
}

/// Why a factorisation or solve failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinalgError {
    /// A pivot block or the border's Schur complement is (numerically) singular.
    #[error("singular matrix: {0}")]
    Singular(String),
    /// A solver from another library (a [`DirectSolver`] adapted to this crate) failed.
    #[error(transparent)]
    Backend(Box<dyn std::error::Error + Send + Sync>),
    /// The assembler wrote entries outside the fixed pattern (a bug in the assembler).
    #[error("{0} entries were assembled outside the matrix's pattern")]
    OutsidePattern(usize),
    /// A solve through a [`DirectSolver`] with no successful factorisation since the last
    /// failed one (the solves of the factors themselves cannot be called unfactored).
    #[error("solve without a successful factorisation")]
    NotFactored,
    /// A matrix too large to store (its size or bandwidths are a mistake).
    #[error("matrix too large: {0}")]
    Size(String),
    /// A vector, row or matrix of the wrong length or size for the solver given it (a bug
    /// in the caller).
    #[error("wrong length: {0}")]
    Length(String),
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
