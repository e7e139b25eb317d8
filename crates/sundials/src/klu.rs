//! The KLU sparse direct solver (SuiteSparse), bound by our build.rs because sundials-sys
//! only binds it with its `klu` feature (which would also change how it finds SUNDIALS).
//!
//! Compiled only with `cfg(eyeshell_klu)`, which build.rs sets when sunlinsol_klu.h, klu.h
//! and the libraries exist; otherwise asking for KLU gives `SundialsError::KluUnavailable`.

use sundials_sys::{N_Vector, SUNContext, SUNLinearSolver, SUNMatrix};

use super::error::SundialsError;

#[cfg(eyeshell_klu)]
#[allow(non_snake_case, non_upper_case_globals, dead_code)]
mod ffi {
    include!(concat!(env!("OUT_DIR"), "/klu_bindings.rs"));
}

/// `SUNLinSol_KLU(y, A, ctx)`.
///
/// # Safety
/// `y` must be a live serial vector, `a` a live CSR/CSC sparse matrix and `ctx` the live
/// context both were created in.
#[cfg(eyeshell_klu)]
pub(crate) unsafe fn new_klu(
    y: N_Vector,
    a: SUNMatrix,
    ctx: SUNContext,
) -> Result<SUNLinearSolver, SundialsError> {
    let raw = ffi::SUNLinSol_KLU(y, a, ctx);
    if raw.is_null() {
        return Err(SundialsError::NullHandle("SUNLinSol_KLU"));
    }
    Ok(raw)
}

/// KLU was not found at build time.
///
/// # Safety
/// None needed; `unsafe` only to match the signature of the real constructor.
#[cfg(not(eyeshell_klu))]
pub(crate) unsafe fn new_klu(
    _y: N_Vector,
    _a: SUNMatrix,
    _ctx: SUNContext,
) -> Result<SUNLinearSolver, SundialsError> {
    Err(SundialsError::KluUnavailable)
}
