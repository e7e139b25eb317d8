//! eyeshell: the morphoelastic shell model of eye growth (Kimpton, Walker et al.).
//!
//! Data flows one way: a scene is read ([`scene`]), the physics is assembled ([`model`]),
//! the material nodes are laid ([`mesh`]), the equations are discretised and solved
//! ([`bvp`], [`growth`]) through the safe layer over SUNDIALS (the `eyeshell-sundials`
//! crate), and results are written to run directories ([`rundir`], [`sweep`]). The model
//! is described in docs/MODEL.md, whose sections the module comments cite.

#![forbid(unsafe_code)]

pub mod bvp;
pub mod error;
pub mod growth;
pub mod mesh;
pub mod model;
pub mod rundir;
pub mod scene;
pub mod sweep;

pub use error::Error;
