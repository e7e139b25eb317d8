//! The two halves of a solver SUNDIALS sees as "ours": an empty SUNLinearSolver of type
//! DIRECT whose setup and solve are the caller's, and an empty "token" SUNMatrix that only
//! carries the caller's content. IDA's custom solver (ida.rs) and the block LU (block.rs)
//! are both built from them. DIRECT, with a matrix, because that is what keeps the
//! integrators calling lsetup, the Jacobian function and (IDA) the cj scaling of the
//! correction; the matrix ops they call are getid and zero (see those modules).

use std::os::raw::{c_int, c_void};

use sundials_sys::{
    realtype, N_Vector, SUNLinSolFreeEmpty, SUNLinSolNewEmpty, SUNLinearSolver, SUNLinearSolver_ID,
    SUNLinearSolver_ID_SUNLINEARSOLVER_CUSTOM, SUNLinearSolver_Type,
    SUNLinearSolver_Type_SUNLINEARSOLVER_DIRECT, SUNMatFreeEmpty, SUNMatNewEmpty, SUNMatrix,
    SUNMatrix_ID, SUNMatrix_ID_SUNMATRIX_CUSTOM, SUNLS_SUCCESS,
};

use super::context::Context;
use super::error::SundialsError;

/// SUNLinSolSetup's signature.
pub(crate) type SetupFn = unsafe extern "C" fn(SUNLinearSolver, SUNMatrix) -> c_int;
/// SUNLinSolSolve's signature.
pub(crate) type SolveFn =
    unsafe extern "C" fn(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, realtype) -> c_int;

/// An empty DIRECT solver with `setup` and `solve`, freed (without content) by its free op.
/// Its content is NULL until the caller sets it.
pub(crate) fn direct_solver(
    ctx: &Context,
    setup: SetupFn,
    solve: SolveFn,
) -> Result<SUNLinearSolver, SundialsError> {
    // SAFETY: ctx is live; the result is checked for NULL at once.
    let ls = unsafe { SUNLinSolNewEmpty(ctx.raw()) };
    if ls.is_null() {
        return Err(SundialsError::NullHandle("SUNLinSolNewEmpty"));
    }
    // SAFETY: ls is live with an ops table whose ops are all NULL. The integrators and
    // KINSOL 6.4 require gettype and solve; initialize, space, numiters, ... go through
    // wrappers that treat NULL as success or zero.
    unsafe {
        let ops = &mut *(*ls).ops;
        ops.gettype = Some(direct_gettype);
        ops.getid = Some(custom_solver_id);
        ops.setup = Some(setup);
        ops.solve = Some(solve);
        ops.free = Some(free_solver);
    }
    Ok(ls)
}

/// An empty matrix carrying `content`, destroyed by SUNMatFreeEmpty (which leaves the
/// content to its owner) and whose zero op does nothing (the owner clears what it needs).
pub(crate) fn token_matrix(
    ctx: &Context,
    content: *mut c_void,
) -> Result<SUNMatrix, SundialsError> {
    // SAFETY: ctx is live; the result is checked for NULL at once.
    let a = unsafe { SUNMatNewEmpty(ctx.raw()) };
    if a.is_null() {
        return Err(SundialsError::NullHandle("SUNMatNewEmpty"));
    }
    // SAFETY: a is a live, empty matrix with an ops table (every op NULL); we own it.
    unsafe {
        (*a).content = content;
        let ops = &mut *(*a).ops;
        ops.getid = Some(custom_matrix_id);
        ops.zero = Some(no_zero);
        ops.destroy = Some(SUNMatFreeEmpty);
    }
    Ok(a)
}

unsafe extern "C" fn direct_gettype(_ls: SUNLinearSolver) -> SUNLinearSolver_Type {
    SUNLinearSolver_Type_SUNLINEARSOLVER_DIRECT
}

unsafe extern "C" fn custom_solver_id(_ls: SUNLinearSolver) -> SUNLinearSolver_ID {
    SUNLinearSolver_ID_SUNLINEARSOLVER_CUSTOM
}

/// Free the solver object only: its content, if any, belongs to somebody else.
unsafe extern "C" fn free_solver(ls: SUNLinearSolver) -> c_int {
    // SAFETY: ls came from SUNLinSolNewEmpty; called once, from its owner's drop.
    unsafe { SUNLinSolFreeEmpty(ls) };
    SUNLS_SUCCESS as c_int
}

unsafe extern "C" fn custom_matrix_id(_a: SUNMatrix) -> SUNMatrix_ID {
    SUNMatrix_ID_SUNMATRIX_CUSTOM
}

/// Nothing: the token's owner keeps (and clears) its own matrix.
unsafe extern "C" fn no_zero(_a: SUNMatrix) -> c_int {
    0
}
