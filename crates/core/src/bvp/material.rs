//! The unloaded shell's data at the points the schemes use (docs/MODEL.md §1, §4). Before any
//! growth the unloaded shell is the reference sphere: σ = Σ, ρ = R0 sin(Σ/R0), ζ = H(Σ),
//! γ = 1. Fibre directions are evaluated only when the scene has fibres.

use super::discretisation::MaterialData;
use super::equations::MaterialPoint;
use crate::mesh::Mesh;
use crate::model::constitutive::FibreDirection;
use crate::model::params::Params;
use crate::model::profiles::{self, Side};

/// The reference (ungrown) shell's data at Σ, from `side` at a breakpoint.
pub fn reference_point(p: &Params, sigma_ref: f64, side: Side) -> MaterialPoint {
    MaterialPoint {
        sigma_ref,
        sigma: sigma_ref,
        rho: p.r0 * (sigma_ref / p.r0).sin(),
        zeta: profiles::thickness(p, sigma_ref, side),
        gamma: 1.0,
        fibre: p
            .has_fibres()
            .then(|| FibreDirection::from_angle(profiles::fibre_angle(p, sigma_ref, side))),
    }
}

/// The reference shell's data on a mesh: nodes from both sides and interval midpoints.
pub fn reference_data(p: &Params, mesh: &Mesh) -> MaterialData {
    let x = &mesh.nodes;
    MaterialData {
        above: x
            .iter()
            .map(|&s| reference_point(p, s, Side::Above))
            .collect(),
        below: x
            .iter()
            .map(|&s| reference_point(p, s, Side::Below))
            .collect(),
        mid: x
            .windows(2)
            .map(|w| reference_point(p, 0.5 * (w[0] + w[1]), Side::Above))
            .collect(),
    }
}
