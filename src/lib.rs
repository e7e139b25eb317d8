//! eyeshell: the morphoelastic shell model of eye growth (Kimpton, Walker et al.).
//!
//! Data flows one way: a scene is read ([`scene`]), the physics is assembled ([`model`]),
//! the material nodes are laid ([`mesh`]), the equations are discretised and solved
//! ([`bvp`]) through a thin safe layer over SUNDIALS ([`sundials`]), and results are
//! written ([`output`]). The model is described in docs/MODEL.md, whose sections the module
//! comments cite.

pub mod bvp;
pub mod cli;
pub mod error;
pub mod growth;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod output;
pub mod study;
pub mod scene;
pub mod sundials;

pub use error::Error;
