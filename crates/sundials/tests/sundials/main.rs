//! The SUNDIALS layer against SUNDIALS itself: every wrapper, flag and callback path, and the linkage to Debian's 6.x.
//!
//! One test binary for the group: one link instead of one per module.

mod sundials_support;

mod cvode;
mod ida;
mod idas;
mod kinsol;
mod kinsol_block;
mod kinsol_factorization;
mod klu_solver;
mod linkage;
mod linsol;
