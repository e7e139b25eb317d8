//! Where the growth state lives (docs/MODEL.md §5): at every material point the elastic scheme
//! evaluates — the nodes, both sides of a node where the thickness jumps, and (for
//! Hermite–Simpson) the interval midpoints. The growth laws are local in Σ, so carrying
//! ρ and γ_s = ∂σ/∂Σ at exactly those points gives the elastic problem its data with no
//! interpolation, and keeps γ_s one-sided where α_s (and so its growth) jumps.
//!
//! Choice of state: (ρ, γ_s) rather than (ρ, σ). The local form Dγ_s/Dt = η γ_s [α_s − 1]⁺
//! makes each rate depend on its own point only (a block-diagonal ∂G/∂p), where σ's
//! integral form couples every point to all those before it; σ is recovered by the
//! scheme's own quadrature of γ_s, and σ_ε = ε γ_s(ε) over the truncated cap.

use super::{GrowthParams, ThicknessLaw};
use crate::bvp::discretisation::MaterialData;
use crate::bvp::equations::MaterialPoint;
use crate::bvp::settings::Scheme;
use crate::mesh::Mesh;
use crate::model::constitutive::FibreDirection;
use crate::model::growth_law;
use crate::model::params::Params;
use crate::model::profiles::{self, Side};

/// Entries of the state per point: ρ then γ_s.
pub const NP: usize = 2;

/// The material points that carry growth, and their fixed data.
#[derive(Clone, Debug)]
pub struct GrowthPoints {
    /// Σ of each point.
    pub sigma_ref: Vec<f64>,
    /// Which point each slot of `MaterialData` reads: node i from above, from below, midpoint i.
    pub above: Vec<usize>,
    pub below: Vec<usize>,
    pub mid: Vec<usize>,
    /// Initial thickness H(Σ), one-sided at a jump.
    h: Vec<f64>,
    /// Initial radius R(Σ) = R0 sin(Σ/R0).
    pub rho_ref: Vec<f64>,
    /// Growth capacity g_c(Σ).
    pub capacity: Vec<f64>,
    /// The points in Σ order (a jump node's point from below first), for the crossing of
    /// φ_max (`super::crossing`).
    pub by_sigma: Vec<usize>,
    fibre: Vec<Option<FibreDirection>>,
    law: ThicknessLaw,
    steps: Vec<f64>,
    epsilon: f64,
    hermite_simpson: bool,
}

impl GrowthPoints {
    pub fn new(p: &Params, g: &GrowthParams, mesh: &Mesh, scheme: Scheme) -> GrowthPoints {
        let m = mesh.len();
        let mut pts = GrowthPoints {
            sigma_ref: vec![],
            above: vec![],
            below: vec![],
            mid: vec![],
            h: vec![],
            rho_ref: vec![],
            capacity: vec![],
            by_sigma: vec![],
            fibre: vec![],
            law: g.thickness_law,
            steps: (0..m - 1).map(|i| mesh.step(i)).collect(),
            epsilon: mesh.nodes[0],
            hermite_simpson: scheme == Scheme::HermiteSimpson,
        };
        let add = |pts: &mut GrowthPoints, x: f64, side: Side| {
            pts.sigma_ref.push(x);
            pts.h.push(profiles::thickness(p, x, side));
            pts.rho_ref.push(p.r0 * (x / p.r0).sin());
            pts.capacity
                .push(profiles::growth_capacity(g.eta0, g.gamma, g.delta, x));
            pts.fibre.push(
                p.has_fibres()
                    .then(|| FibreDirection::from_angle(profiles::fibre_angle(p, x, side))),
            );
            pts.sigma_ref.len() - 1
        };
        for (i, &x) in mesh.nodes.iter().enumerate() {
            let jumps = i > 0
                && i < m - 1
                && profiles::thickness(p, x, Side::Below) != profiles::thickness(p, x, Side::Above);
            let below = add(&mut pts, x, Side::Below);
            let above = if jumps {
                add(&mut pts, x, Side::Above)
            } else {
                below
            };
            pts.below.push(below);
            pts.above.push(above);
        }
        // Node 0 has no interval below it: its one point is the limit from above.
        pts.h[pts.above[0]] = profiles::thickness(p, mesh.nodes[0], Side::Above);
        if pts.hermite_simpson {
            for w in mesh.nodes.windows(2) {
                let k = add(&mut pts, 0.5 * (w[0] + w[1]), Side::Above);
                pts.mid.push(k);
            }
        }
        pts.by_sigma = (0..pts.sigma_ref.len()).collect();
        let sigma = &pts.sigma_ref;
        pts.by_sigma.sort_by(|&a, &b| sigma[a].total_cmp(&sigma[b]));
        pts
    }

    /// The point a node's output rows read: node 0 from above, every other node from below
    /// (at a breakpoint, the limit from below, as the elastic rows).
    pub fn node_point(&self, i: usize) -> usize {
        if i == 0 {
            self.above[0]
        } else {
            self.below[i]
        }
    }

    /// The thickness law the points' ζ follows.
    pub fn law(&self) -> ThicknessLaw {
        self.law
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.sigma_ref.len()
    }

    pub fn is_empty(&self) -> bool {
        self.sigma_ref.is_empty()
    }

    /// The ungrown state: ρ = R(Σ), γ_s = 1.
    pub fn initial_state(&self) -> Vec<f64> {
        self.rho_ref.iter().flat_map(|&r| [r, 1.0]).collect()
    }

    /// ζ at point k in state `p`.
    pub fn zeta(&self, k: usize, p: &[f64]) -> f64 {
        growth_law::thickness(
            self.law,
            self.h[k],
            p[NP * k + 1],
            p[NP * k],
            self.rho_ref[k],
        )
    }

    /// The unloaded shell's data for the elastic scheme in state `p`. σ comes from the
    /// scheme's quadrature of γ_s, with σ_ε = ε γ_s over the truncated cap.
    pub fn material_data(&self, p: &[f64]) -> MaterialData {
        let mut data = MaterialData::default();
        self.material_data_into(p, &mut data);
        data
    }

    /// [`Self::material_data`] written over `data`'s buffers (a residual's, every call).
    pub fn material_data_into(&self, p: &[f64], data: &mut MaterialData) {
        let m = self.above.len();
        let gamma = |k: usize| p[NP * k + 1];
        let point = |k: usize, s: f64| MaterialPoint {
            sigma_ref: self.sigma_ref[k],
            sigma: s,
            rho: p[NP * k],
            zeta: self.zeta(k, p),
            gamma: gamma(k),
            fibre: self.fibre[k],
        };
        let (above, below, mid) = (&mut data.above, &mut data.below, &mut data.mid);
        above.clear();
        below.clear();
        mid.clear();
        let mut sigma = self.epsilon * gamma(self.above[0]);
        for i in 0..m {
            above.push(point(self.above[i], sigma));
            below.push(point(self.below[i], sigma));
            if i + 1 < m {
                let h = self.steps[i];
                let (a, b) = (gamma(self.above[i]), gamma(self.below[i + 1]));
                let next = sigma
                    + if self.hermite_simpson {
                        h / 6.0 * (a + 4.0 * gamma(self.mid[i]) + b)
                    } else {
                        0.5 * h * (a + b)
                    };
                mid.push(if self.hermite_simpson {
                    point(self.mid[i], 0.5 * (sigma + next) + h / 8.0 * (a - b))
                } else {
                    // The trapezoidal scheme never reads midpoints; keep the slots well-formed.
                    point(self.above[i], sigma)
                });
                sigma = next;
            }
        }
    }
}
