//! SUNDIALS' KLU as an [`eyeshell_linalg::DirectSolver`] of a [`Csr`] matrix, so that the
//! safe solvers of eyeshell-linalg can use it (alone, as the robust half of a
//! [`eyeshell_linalg::Fallback`], or for a Schur complement: [`KluSolver::REDUCED`]), and
//! SUNDIALS' errors as [`LinalgError`]s.

use std::rc::Rc;

use eyeshell_linalg::{Csr, DirectSolver, LinalgError, Reduced};

use crate::{Context, LinearSolver, LinearSolverSpec, Matrix, NVector, SundialsError};

impl From<SundialsError> for LinalgError {
    fn from(e: SundialsError) -> Self {
        LinalgError::Backend(Box::new(e))
    }
}

/// SUNDIALS' KLU on the CSR matrix in its own order (KLU orders for fill itself).
pub struct KluSolver {
    matrix: Matrix,
    solver: LinearSolver,
    b: NVector,
    x: NVector,
    _ctx: Rc<Context>,
}

impl KluSolver {
    /// [`eyeshell_linalg::SchurSolver`]'s reduced matrix factored by KLU.
    pub const REDUCED: Reduced = Reduced::Sparse(KluSolver::boxed);

    fn boxed(pattern: &Csr) -> Result<Box<dyn DirectSolver>, LinalgError> {
        Ok(Box::new(KluSolver::new(pattern)?))
    }

    pub fn new(pattern: &Csr) -> Result<Self, LinalgError> {
        let ctx = Context::new()?;
        let spec = LinearSolverSpec::Klu {
            row_ptr: pattern.row_ptr().to_vec(),
            col_idx: pattern.col_idx().to_vec(),
        };
        let (matrix, solver) = LinearSolver::for_spec(&ctx, pattern.n(), &spec)?;
        let (b, x) = (
            NVector::new(&ctx, pattern.n())?,
            NVector::new(&ctx, pattern.n())?,
        );
        Ok(KluSolver {
            matrix,
            solver,
            b,
            x,
            _ctx: ctx,
        })
    }
}

impl DirectSolver for KluSolver {
    /// KLU refactors with the pivot order of its first factorisation, and SUNDIALS reports
    /// a zero pivot there as a failure instead of pivoting afresh (seen in growth at rtol
    /// 1e-2, where the steps change the matrix a lot): then factor anew from scratch.
    fn factor(&mut self, a: &Csr) -> Result<(), LinalgError> {
        let Matrix::Sparse(m) = &mut self.matrix else {
            unreachable!("made for KLU")
        };
        m.copy_values(a.values())?;
        if self.solver.setup(&mut self.matrix).is_ok() {
            return Ok(());
        }
        self.solver = LinearSolver::new(&self._ctx, &self.matrix)?;
        self.solver.setup(&mut self.matrix)?;
        Ok(())
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        self.b.as_mut_slice().copy_from_slice(b);
        self.solver.solve(&mut self.matrix, &mut self.x, &self.b)?;
        x.copy_from_slice(self.x.as_slice());
        Ok(())
    }
}
