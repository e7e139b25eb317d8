//! Direct linear solvers (dense LU, band LU, KLU, almost-block-diagonal LU) owned by Rust, usable by KINSOL (and later
//! CVODE/IDA) or standalone through [`LinearSolver::setup`] / [`LinearSolver::solve`].

use std::rc::Rc;

use sundials_sys::{
    SUNLinSolFree, SUNLinSolInitialize, SUNLinSolSetup, SUNLinSolSolve, SUNLinSol_Band,
    SUNLinSol_Dense, SUNLinearSolver,
};

use super::block::new_block_solver;
use super::context::Context;
use super::error::{check, FlagFamily, SundialsError};
use super::klu::new_klu;
use super::matrix::{BandMatrix, BlockMatrix, DenseMatrix, Matrix, MatrixKind, SparseMatrix};
use super::nvector::NVector;
use eyeshell_linalg::ABD_NODE;

/// Which matrix and direct solver to use for an n×n system.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinearSolverSpec {
    Dense,
    /// Band LU with these bandwidths (clamped to n - 1).
    Band {
        upper: usize,
        lower: usize,
    },
    /// KLU on a CSR matrix with this pattern, fixed for the life of the solver
    /// (`row_ptr`: n + 1 offsets; `col_idx`: strictly increasing within each row).
    Klu {
        row_ptr: Vec<usize>,
        col_idx: Vec<usize>,
    },
    /// The almost-block-diagonal LU of `eyeshell_linalg::AbdLu`: n = 5 · nodes unknowns, `top`
    /// boundary rows at the start and 5 − top at the end (the elastic BVP: top = 3).
    Block {
        nodes: usize,
        top: usize,
    },
}

impl LinearSolverSpec {
    /// An n×n zero matrix of the kind this spec needs.
    pub fn matrix(&self, ctx: &Rc<Context>, n: usize) -> Result<Matrix, SundialsError> {
        Ok(match self {
            LinearSolverSpec::Dense => Matrix::Dense(DenseMatrix::new(ctx, n, n)?),
            LinearSolverSpec::Band { upper, lower } => {
                Matrix::Band(BandMatrix::new(ctx, n, *upper, *lower)?)
            }
            LinearSolverSpec::Klu { row_ptr, col_idx } => {
                if !super::klu_available() {
                    return Err(SundialsError::KluUnavailable);
                }
                Matrix::Sparse(SparseMatrix::new(ctx, n, row_ptr.clone(), col_idx.clone())?)
            }
            LinearSolverSpec::Block { nodes, top } => {
                if nodes.checked_mul(ABD_NODE) != Some(n) {
                    return Err(SundialsError::Invalid(format!(
                        "a block matrix of {nodes} nodes has {} unknowns, not {n}",
                        nodes.saturating_mul(ABD_NODE)
                    )));
                }
                Matrix::Block(BlockMatrix::new(ctx, *nodes, *top)?)
            }
        })
    }
}

/// A direct SUNLinearSolver, freed on drop. An integrator (KINSOL, CVODE or IDA) that
/// uses it must be freed before it, and it before its matrix; the owner's field order
/// guarantees that, and the `Rc<Context>` keeps the context alive until the last of them.
pub struct LinearSolver {
    raw: SUNLinearSolver,
    kind: MatrixKind,
    n: usize,
    /// KLU keeps a symbolic factorisation of the pattern with this fingerprint (compared
    /// on every setup and solve, so O(1) rather than the pattern itself).
    pattern: Option<u64>,
    factored: bool,
    _ctx: Rc<Context>,
}

impl LinearSolver {
    /// The direct solver matching `matrix`: dense LU, band LU or KLU.
    pub fn new(ctx: &Rc<Context>, matrix: &Matrix) -> Result<Self, SundialsError> {
        let n = matrix.nrows();
        if matrix.ncols() != n {
            return Err(SundialsError::Invalid(format!(
                "linear solver needs a square matrix, got {}",
                matrix.describe()
            )));
        }
        let template = NVector::new(ctx, n)?;
        // SAFETY: template, matrix and ctx are live and were created in ctx; the
        // constructors only inspect `template` (they keep no reference to it).
        let (raw, name, pattern) = unsafe {
            match matrix {
                Matrix::Dense(a) => (
                    SUNLinSol_Dense(template.raw(), a.raw(), ctx.raw()),
                    "SUNLinSol_Dense",
                    None,
                ),
                Matrix::Band(a) => (
                    SUNLinSol_Band(template.raw(), a.raw(), ctx.raw()),
                    "SUNLinSol_Band",
                    None,
                ),
                Matrix::Sparse(a) => (
                    new_klu(template.raw(), a.raw(), ctx.raw())?,
                    "SUNLinSol_KLU",
                    Some(a.fingerprint()),
                ),
                Matrix::Block(_) => (new_block_solver(ctx)?, "SUNLinSolNewEmpty", None),
            }
        };
        if raw.is_null() {
            return Err(SundialsError::NullHandle(name));
        }
        let ls = LinearSolver {
            raw,
            kind: matrix.kind(),
            n,
            pattern,
            factored: false,
            _ctx: Rc::clone(ctx),
        };
        // SAFETY: raw is a live linear solver.
        check(
            "SUNLinSolInitialize",
            unsafe { SUNLinSolInitialize(raw) },
            FlagFamily::SunLs,
            None,
        )?;
        Ok(ls)
    }

    /// A matrix for `spec` and its solver.
    pub fn for_spec(
        ctx: &Rc<Context>,
        n: usize,
        spec: &LinearSolverSpec,
    ) -> Result<(Matrix, Self), SundialsError> {
        let matrix = spec.matrix(ctx, n)?;
        let solver = Self::new(ctx, &matrix)?;
        Ok((matrix, solver))
    }

    pub fn kind(&self) -> MatrixKind {
        self.kind
    }

    pub fn n(&self) -> usize {
        self.n
    }

    fn check_matrix(&self, matrix: &Matrix) -> Result<(), SundialsError> {
        if matrix.kind() != self.kind || matrix.nrows() != self.n || matrix.ncols() != self.n {
            return Err(SundialsError::Invalid(format!(
                "a {:?} solver of size {} cannot use a {} matrix",
                self.kind,
                self.n,
                matrix.describe()
            )));
        }
        if let (Some(fingerprint), Matrix::Sparse(a)) = (self.pattern, matrix) {
            if a.fingerprint() != fingerprint {
                return Err(SundialsError::Invalid(
                    "the KLU solver was created for a different sparsity pattern".into(),
                ));
            }
        }
        Ok(())
    }

    /// Factorise `matrix` (in place for dense and band: afterwards it holds the LU factors).
    pub fn setup(&mut self, matrix: &mut Matrix) -> Result<(), SundialsError> {
        self.check_matrix(matrix)?;
        matrix.before_setup();
        self.factored = false;
        // SAFETY: both handles are live and compatible (checked above).
        let flag = unsafe { SUNLinSolSetup(self.raw, matrix.raw()) };
        let detail = match matrix {
            Matrix::Block(m) if flag != 0 => m.last_error().map(str::to_string),
            _ => None,
        };
        check("SUNLinSolSetup", flag, FlagFamily::SunLs, detail)?;
        self.factored = true;
        Ok(())
    }

    /// Solve A x = b with the factorisation from the last [`setup`](Self::setup) of `matrix`.
    pub fn solve(
        &mut self,
        matrix: &mut Matrix,
        x: &mut NVector,
        b: &NVector,
    ) -> Result<(), SundialsError> {
        self.check_matrix(matrix)?;
        if x.len() != self.n || b.len() != self.n {
            return Err(SundialsError::Invalid(format!(
                "solve needs vectors of length {}, got x {} and b {}",
                self.n,
                x.len(),
                b.len()
            )));
        }
        if !self.factored {
            return Err(SundialsError::Invalid(
                "solve called before a successful setup".into(),
            ));
        }
        // SAFETY: all handles live and compatible; direct solvers copy b into x and solve
        // in place, they do not write b.
        let flag = unsafe { SUNLinSolSolve(self.raw, matrix.raw(), x.raw(), b.raw(), 0.0) };
        check("SUNLinSolSolve", flag, FlagFamily::SunLs, None)
    }

    pub(crate) fn raw(&self) -> SUNLinearSolver {
        self.raw
    }
}

impl Drop for LinearSolver {
    fn drop(&mut self) {
        // SAFETY: raw came from a SUNLinSol constructor and is freed once; any integrator
        // that pointed at it has been freed first by its owner.
        unsafe {
            SUNLinSolFree(self.raw);
        }
    }
}
