//! The numerics: exact solutions, observed orders, analytic against finite-difference Jacobians, the first integral, growth by every integrator.
//!
//! One test binary for the group: one link instead of one per module.

mod common;

mod adapt;
mod api_never_panics;
mod block_solver;
mod convergence;
mod custom_eye;
mod dae_jacobian;
mod default_tables;
mod exact_solution;
mod growth;
mod growth_ida;
mod growth_tol_sweep;
mod jacobian;
mod max_seconds;
mod property_jacobian;
mod property_residual;
mod run_rays;
mod sensitivities;
mod solve_features;
