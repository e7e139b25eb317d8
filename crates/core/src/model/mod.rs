//! The physics, and nothing of the solvers (docs/MODEL.md §1–6): parameters, material
//! profiles, the constitutive law, the cornea, the growth law, the visual stimulus and the
//! model's components.

pub mod components;
pub mod constitutive;
pub mod cornea;
mod default_tables;
pub mod eye;
pub mod eyewear;
pub mod growth_law;
pub mod images;
pub mod optics;
pub mod params;
pub mod profiles;
pub mod rule;
pub mod stimulus;

/// A set of parameters for which the model itself has no answer.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ModelError {
    #[error("{} = {} is above the cornea's limit: the largest admissible ΔP is {} kPa (4 C_c H_c / R_c · (6/7) · 7^(-1/6))", crate::names::Quantity::Pressure, crate::text::number(*dp), crate::text::decimals6(*max))]
    PressureAboveCorneaLimit { dp: f64, max: f64 },
    #[error("{} = {} must be non-negative", crate::names::Quantity::Pressure, crate::text::number(*dp))]
    NegativePressure { dp: f64 },
}
