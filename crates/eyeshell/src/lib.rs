//! eyeshell: the morphoelastic shell model of eye growth (Kimpton, Walker et al.), solved
//! through SUNDIALS.
//!
//! The sclera is a thin, pressurised, growing shell. At every instant it is in elastic
//! equilibrium, a stiff two-point boundary value problem in arclength ([`Scene::solve`]);
//! over years it grows where the retina lies in front of the eye's best-focus surface for
//! blue light ([`Scene::grow`]). The equations, profiles and the paper's errata are in
//! `docs/MODEL.md`, whose sections the module comments cite.
//!
//! # Use
//!
//! ```
//! use eyeshell::Scene;
//!
//! let mut scene = Scene::default_scene();          // or Scene::from_path("scene.toml")?
//! scene.set("solver.nodes", 201)?;                  // any key of `eyeshell keys`
//! let sol = scene.solve()?;                         // the loaded shell
//! let pole = sol.at(scene.solver.epsilon)?;         // continuous in Σ
//! println!("r = {:.6} mm, Newton {} iterations", pole.r, sol.stats.newton_iterations);
//! assert!(sol.stats.first_integral_max < 1e-8);
//! # Ok::<(), eyeshell::Error>(())
//! ```
//!
//! The curated entry points are [`Scene`] (read, [`Scene::set`], [`Scene::solve`],
//! [`Scene::grow`]), [`Solution`], [`Growth`], [`Sweep`] and the one [`Error`]. Below them
//! the layers are public for those who need them (studies, custom observers, other
//! integrators): [`model`] (physics only), [`mesh`], [`bvp`], [`growth`], [`scene`],
//! [`rundir`] (run directories on disk), [`sweep`] and [`interop`] (other people's formats:
//! MAT v5 and NPZ files, the bvp4c-shaped export, comparisons against them). Data flows one way: scene → model →
//! mesh → discretisation → SUNDIALS (the `eyeshell-sundials` crate) → results. The library
//! prints nothing.

mod api;
pub mod discrete;
pub mod error;
pub mod fit;
pub mod hash;
pub mod interop;
mod json;
pub mod number;
pub mod outputs;
pub mod plan;
pub mod problem;
pub mod rundir;
pub mod scene;
pub mod sweep;

pub mod text;

// The numerics live in eyeshell-core, which touches no file; they are re-exported at the
// paths they have always had, so `eyeshell::growth::grow` and `crate::bvp::...` are as before.
pub use eyeshell_core::{bvp, deadline, growth, mesh, model};

pub use api::Growth;
pub use bvp::Solution;
pub use error::{BadInput, Error, Failure, Origin, Stage, Subject};
pub use scene::sweep::Sweep;
pub use scene::Scene;

// The Rust examples of the README and the user guide are compiled and run with the doctests
// (tests/cli/docs.rs checks that every file holding a ```rust block is included here).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
struct ReadmeDoctests;

#[cfg(doctest)]
#[doc = include_str!("../../../docs/guide/rust.md")]
struct GuideRustDoctests;
