//! The almost-block-diagonal solver ([`AbdLu`]) as a SUNDIALS matrix and linear solver, so
//! that KINSOL (or CVODE/IDA) factors the shell's Jacobians with it.
//!
//! How it plugs in: a custom SUNMatrix (a "token" made by SUNMatNewEmpty whose content is
//! the Rust [`AbdLu`]) and a custom SUNLinearSolver of type DIRECT (SUNLinSolNewEmpty, ops
//! gettype, getid, setup, solve, free). DIRECT rather than MATRIX_EMBEDDED because KINSOL
//! 6.4 then does what the band solver gets: at each linear setup it calls SUNMatZero on the
//! matrix, the Jacobian function (our trampoline, which assembles straight into the blocks)
//! and SUNLinSolSetup, which factors; SUNLinSolSolve solves with the factors. The matrix ops
//! KINSOL 6.4 calls on a DIRECT solver's matrix with a user Jacobian are SUNMatZero only
//! (kinLsSetup); IDA 6.4 the same (see ida.rs). The matrix's zero op does nothing: the
//! Jacobian trampoline clears what needs clearing ([`AbdLu::zero_boundary`], see
//! `Matrix::fill_jacobian`), so no band of zeros is written between Jacobians.
//!
//! Flags: a singular factorisation returns SUNLS_LUFACT_FAIL (positive, recoverable, as the
//! band solver's zero pivot) and keeps its message for the caller ([`BlockMatrix::last_error`]);
//! a panic inside an op is caught and returned as SUNLS_PACKAGE_FAIL_UNREC.

use std::os::raw::c_int;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::ptr::NonNull;
use std::rc::Rc;

use sundials_sys::{
    realtype, N_Vector, SUNLinearSolver, SUNMatDestroy, SUNMatrix, SUNLS_LUFACT_FAIL,
    SUNLS_PACKAGE_FAIL_UNREC, SUNLS_SUCCESS,
};

use super::context::Context;
use super::custom;
use super::error::SundialsError;
use super::nvector;
use eyeshell_linalg::{AbdLu, AbdLuFactors, LinalgError};

/// What the token matrix's content points at. `tag` (first, `repr(C)`) lets the solver ops
/// refuse a matrix that is not one of ours.
#[repr(C)]
struct BlockState {
    tag: u64,
    lu: AbdLu,
    /// The factors of the last successful setup (None before one, and after a failed one).
    factors: Option<AbdLuFactors>,
    /// Why the last setup or solve failed (None after a success).
    last_error: Option<String>,
}

/// "ABD-LU\0\0" in ASCII.
const TAG: u64 = u64::from_le_bytes(*b"ABD-LU\0\0");

/// An almost-block-diagonal SUNMatrix: a token SUNDIALS passes around, whose content is an
/// [`AbdLu`] owned here. Destroyed on drop (the token, then the Rust state).
pub struct BlockMatrix {
    raw: SUNMatrix,
    state: NonNull<BlockState>,
}

impl BlockMatrix {
    /// A zero matrix of `nodes` 5×5 node blocks with `top` boundary rows at the start.
    pub fn new(ctx: &Rc<Context>, nodes: usize, top: usize) -> Result<Self, SundialsError> {
        let lu = AbdLu::new(nodes, top).map_err(|e| SundialsError::Invalid(e.to_string()))?;
        let state = NonNull::from(Box::leak(Box::new(BlockState {
            tag: TAG,
            lu,
            factors: None,
            last_error: None,
        })));
        // Its zero op does nothing: the Jacobian trampoline clears the boundary rows before
        // it assembles.
        match custom::token_matrix(ctx, state.as_ptr().cast()) {
            Ok(raw) => Ok(BlockMatrix { raw, state }),
            Err(e) => {
                // SAFETY: the state was leaked just above and is owned by nobody else.
                drop(unsafe { Box::from_raw(state.as_ptr()) });
                Err(e)
            }
        }
    }

    pub fn lu(&self) -> &AbdLu {
        // SAFETY: SUNDIALS reaches the state only inside calls made through &mut self or
        // an integrator's solve (which needs the owner's &mut); none is running.
        unsafe { &self.state.as_ref().lu }
    }

    pub fn lu_mut(&mut self) -> &mut AbdLu {
        // SAFETY: as in `lu`, with exclusive access.
        unsafe { &mut self.state.as_mut().lu }
    }

    /// Why the last factorisation or solve through SUNDIALS failed, if it did.
    pub fn last_error(&self) -> Option<&str> {
        // SAFETY: as in `lu`.
        unsafe { self.state.as_ref().last_error.as_deref() }
    }

    pub(crate) fn raw(&self) -> SUNMatrix {
        self.raw
    }
}

impl Drop for BlockMatrix {
    fn drop(&mut self) {
        // SAFETY: raw came from SUNMatNewEmpty and is destroyed once, by its destroy op
        // (SUNMatFreeEmpty, which leaves the content alone); solvers and integrators that
        // held it were dropped first (owners' field order). Then the state, leaked in new,
        // is freed once.
        unsafe {
            SUNMatDestroy(self.raw);
            drop(Box::from_raw(self.state.as_ptr()));
        }
    }
}

/// The custom SUNLinearSolver for [`BlockMatrix`] (freed by `LinearSolver`'s drop through
/// its free op). It holds no content: the factors live in the matrix, as for band LU.
pub(crate) fn new_block_solver(ctx: &Rc<Context>) -> Result<SUNLinearSolver, SundialsError> {
    custom::direct_solver(ctx, block_setup, block_solve)
}

/// The state behind a token matrix made by [`BlockMatrix::new`].
///
/// # Safety
/// `a` must be such a matrix, alive, and no other reference to its state may exist.
unsafe fn state<'a>(a: SUNMatrix) -> Option<&'a mut BlockState> {
    if a.is_null() || (*a).content.is_null() || (*(*a).ops).getid.is_none() {
        return None;
    }
    let st = &mut *((*a).content as *mut BlockState);
    (st.tag == TAG).then_some(st)
}

/// SUNLinSolSetup: factor the blocks as the Jacobian function left them.
unsafe extern "C" fn block_setup(_ls: SUNLinearSolver, a: SUNMatrix) -> c_int {
    // SAFETY: SUNDIALS passes the matrix registered with this solver; during the call no
    // Rust reference to its state is alive (the owner is inside the integrator's solve).
    let Some(st) = (unsafe { state(a) }) else {
        return SUNLS_PACKAGE_FAIL_UNREC;
    };
    let old = st.factors.take();
    match catch_unwind(AssertUnwindSafe(|| st.lu.factor_reusing(old))) {
        Ok(Ok(factors)) => {
            st.factors = Some(factors);
            st.last_error = None;
            SUNLS_SUCCESS as c_int
        }
        Ok(Err(e)) => {
            let flag = match e {
                LinalgError::Singular(_) => SUNLS_LUFACT_FAIL as c_int,
                _ => SUNLS_PACKAGE_FAIL_UNREC,
            };
            st.last_error = Some(e.to_string());
            flag
        }
        Err(_) => {
            st.last_error = Some("block LU factorisation panicked".into());
            SUNLS_PACKAGE_FAIL_UNREC
        }
    }
}

/// SUNLinSolSolve: x = A⁻¹ b with the factors of the last setup (x and b may be one vector).
unsafe extern "C" fn block_solve(
    _ls: SUNLinearSolver,
    a: SUNMatrix,
    x: N_Vector,
    b: N_Vector,
    _tol: realtype,
) -> c_int {
    // SAFETY: as in block_setup.
    let Some(st) = (unsafe { state(a) }) else {
        return SUNLS_PACKAGE_FAIL_UNREC;
    };
    // SAFETY: x and b are live serial vectors; b is read (copied) before x is written, and
    // when they are the same vector only the mutable slice is made.
    let out = unsafe { nvector::slice_mut(x) };
    if x != b {
        let input = unsafe { nvector::slice(b) };
        if input.len() != out.len() {
            return SUNLS_PACKAGE_FAIL_UNREC;
        }
        out.copy_from_slice(input);
    }
    let Some(factors) = &st.factors else {
        st.last_error = Some("block LU solve without a factorisation".into());
        return SUNLS_PACKAGE_FAIL_UNREC;
    };
    match catch_unwind(AssertUnwindSafe(|| factors.solve_in_place(out))) {
        Ok(Ok(())) => SUNLS_SUCCESS as c_int,
        Ok(Err(e)) => {
            st.last_error = Some(e.to_string());
            SUNLS_PACKAGE_FAIL_UNREC
        }
        Err(_) => {
            st.last_error = Some("block LU solve panicked".into());
            SUNLS_PACKAGE_FAIL_UNREC
        }
    }
}
