//! The border unknown d of the coupled DAE (docs/MODEL.md §6): the drive where the retina
//! crosses φ_max, or the drive averaged over an integrated region, and the partials its row
//! of the Newton matrix takes from every point it reads.

use super::RateDeriv;
use crate::growth::crossing::Crossing;
use crate::growth::integral::Integral;

/// What the border unknown d stands for: the drive where the retina crosses φ_max (a local
/// rule), or the drive averaged over the integrated region (every point reads it).
pub(crate) enum Border {
    Crossing(Crossing),
    Integral(Integral),
}

impl Border {
    pub(super) fn value(&self) -> f64 {
        match self {
            Border::Crossing(c) => c.value,
            Border::Integral(i) => i.value,
        }
    }

    /// Each point the border reads, with the border's partials in that point's view.
    pub(super) fn terms(&self) -> Vec<(usize, Term)> {
        match self {
            Border::Crossing(c) => c
                .points()
                .iter()
                .map(|&(k, weight, slope)| (k, Term::Crossing { weight, slope }))
                .collect(),
            Border::Integral(i) => i
                .partials
                .iter()
                .enumerate()
                .filter(|(_, p)| **p != Default::default())
                .map(|(k, p)| (k, Term::Integral([p.drive, p.angle, p.z, p.r])))
                .collect(),
        }
    }
}

/// One point's part of the border: ∂D* = Σ_i L_i (∂drive_i − p'(φ_i) ∂φ_i) for the crossing
/// (its Lagrange weight and the interpolant's slope there), the integral's partials in the
/// point's (drive, φ, z_ret, r_ret) for the region.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Term {
    Crossing { weight: f64, slope: f64 },
    Integral([f64; 4]),
}

impl RateDeriv {
    /// ∂(border's quantity)/∂(local state) of this point for its term.
    pub(super) fn border_row(&self, t: &Term) -> [f64; 6] {
        match *t {
            Term::Crossing { weight, slope } => {
                std::array::from_fn(|q| weight * (self.drive[q] - slope * self.angle[q]))
            }
            Term::Integral(c) => std::array::from_fn(|q| {
                c[0] * self.drive[q]
                    + c[1] * self.angle[q]
                    + c[2] * self.retina[0][q]
                    + c[3] * self.retina[1][q]
            }),
        }
    }
}
