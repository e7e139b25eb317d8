//! A thin, safe layer over SUNDIALS 6.x (Debian's libsundials-dev, bound by `sundials-sys`
//! and, for KLU, by our build.rs): the only `unsafe` code of the workspace lives in this crate.
//!
//! Why a layer: the C API hands out raw handles that must be freed in the right order, reports
//! failure through integer flags and a printing error handler, and calls back into Rust through
//! `extern "C"` functions that must never unwind. Here every handle is an owned type freed on
//! drop (each keeps its [`Context`] alive through an `Rc`), every flag becomes a
//! [`SundialsError`] that names it and carries SUNDIALS's own message (captured, not printed),
//! and every callback runs under `catch_unwind`.
//!
//! The pieces ([`NVector`], [`Matrix`], [`LinearSolver`], the callback guard) are independent
//! of KINSOL so that the integrators ([`Cvode`], [`Ida`]) sit next to [`Kinsol`] and reuse
//! them; what CVODE and IDA share beyond that (options, checks, the memory and the calls
//! that mean the same in both, the trampolines' state) is written once in `integrator.rs`.
//! The structured direct solvers are eyeshell-linalg's (safe Rust); this crate adapts them
//! to SUNDIALS: its almost-block-diagonal LU as a SUNDIALS matrix and linear solver
//! ([`LinearSolverSpec::Block`]), and SUNDIALS' KLU as one of its solvers ([`KluSolver`]).

mod block;
mod callback;
mod context;
mod custom;
mod cvode;
mod error;
mod fastops;
mod ida;
mod idas;
mod integrator;
mod kinsol;
mod klu;
mod klu_solver;
mod linsol;
mod matrix;
mod nvector;

pub use callback::{CallbackError, CallbackResult};
pub use context::Context;
pub use cvode::{Cvode, CvodeLinearSolver, CvodeOptions, CvodeStats, OdeSystem};
pub use error::{SundialsError, RECOVERABLE_NOTE};
pub use ida::{DaeSystem, Ida, IdaLinearSolver, IdaOptions, IdaStats};
pub use idas::{IdaSensStats, SensitivityOptions};
pub use kinsol::{Kinsol, KinsolOptions, KinsolStats, NonlinearSystem, Strategy};
pub use klu_solver::KluSolver;
pub use linsol::{LinearSolver, LinearSolverSpec};
pub use matrix::{
    BandMatrix, BandMut, BlockMatrix, CsrMut, DenseMatrix, DenseMut, JacobianMatrix, Matrix,
    MatrixKind, MatrixSink, SparseMatrix,
};
pub use nvector::NVector;

/// The SUNDIALS headers this crate was compiled against (from build.rs).
pub const BUILD_SUNDIALS_INCLUDE: &str = env!("EYESHELL_SUNDIALS_INCLUDE");
/// The SUNDIALS version those headers declare, e.g. "6.4.1" (from build.rs).
pub const BUILD_SUNDIALS_VERSION: &str = env!("EYESHELL_SUNDIALS_VERSION");
/// This crate's build-script output directory: `target/<profile>/build/eyeshell-sundials-<hash>/out`.
/// Lets tools inspect the sibling `sundials-sys-*` build directories of the same build.
pub const BUILD_OUT_DIR: &str = env!("OUT_DIR");

mod version_ffi {
    #![allow(non_snake_case, dead_code)]
    include!(concat!(env!("OUT_DIR"), "/version_bindings.rs"));
}

/// The version of the SUNDIALS library actually linked at run time (`SUNDIALSGetVersion`),
/// e.g. "6.4.1".
pub fn version() -> String {
    let mut buf = [0 as std::os::raw::c_char; 64];
    // SAFETY: the buffer is writable for its whole length, which we pass.
    let flag = unsafe { version_ffi::SUNDIALSGetVersion(buf.as_mut_ptr(), buf.len() as i32) };
    if flag != 0 {
        return String::from("unknown");
    }
    // SAFETY: SUNDIALSGetVersion wrote a NUL-terminated string into the buffer; the last
    // byte is forced to NUL in case it did not.
    buf[buf.len() - 1] = 0;
    unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

/// Whether the KLU sparse direct solver was found at build time (`cfg(eyeshell_klu)`).
pub fn klu_available() -> bool {
    cfg!(eyeshell_klu)
}
