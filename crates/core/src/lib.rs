//! eyeshell-core: the numerics of the morphoelastic shell model of eye growth (Kimpton,
//! Walker et al.): the physics ([`model`]), the material mesh ([`mesh`]), the elastic
//! boundary value problem ([`bvp`]), growth ([`growth`]) and the fit of growth to data ([`fit`]), solved through SUNDIALS
//! (`eyeshell-sundials`) and the safe solvers of `eyeshell-linalg`.
//!
//! This crate reads and writes no files: scenes, run directories, sweeps and other people's
//! formats are the `eyeshell` crate's, which re-exports these modules at the same paths
//! (`eyeshell::growth`, `eyeshell::bvp`, ...). Most users want `eyeshell`'s facade
//! (`eyeshell::Scene`).

pub mod bvp;
pub mod deadline;
pub mod fit;
pub mod growth;
pub mod mesh;
pub mod model;
pub mod names;
pub mod outputs;
/// The two problems (in growth/problem.rs, beside the growth settings they hold), at the
/// path `crate::problem`.
pub use growth::problem;
pub mod text;
