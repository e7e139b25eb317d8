//! The numerics that need no scene, no file and no run directory (docs/MODEL.md §3, §5, §7,
//! §10): exact solutions, observed orders, analytic against finite-difference Jacobians, the first
//! integral, growth by every integrator, sensitivities, solver.tol and solver.max_seconds.
//! The tests that read scene files or call the files crate's API are eyeshell's
//! (crates/eyeshell/tests/numerics), and so is the growth solver.tol sweep: it needs core
//! alone but takes about 280 s of CPU, which would more than double this binary's time.
//!
//! One test binary for the group: one link instead of one per module.

mod common;

mod adapt;
mod block_solver;
mod convergence;
mod dae_jacobian;
mod default_tables;
mod exact_solution;
mod growth;
mod growth_ida;
mod jacobian;
mod max_seconds;
mod property_jacobian;
mod property_residual;
mod sensitivities;
mod solve_features;
