//! Material profiles, functions of the material coordinate Σ fixed for ever (docs/MODEL.md §4):
//! the thickness H(Σ), the fibre angle ψ(Σ) and the growth capacity g_c(Σ).
//!
//! H jumps (by 1.7e-7 mm) at Σ_e = πR0/2 and ψ has kinks at a, b and Σ_e. The mesh makes
//! these breakpoints nodes, and each interval evaluates the data from its own side, so
//! a profile is asked for its value at Σ approached from below or from above.

use super::params::{Params, Thickness};
use std::f64::consts::PI;

/// Which one-sided limit of piecewise data to take at a breakpoint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The limit from Σ' < Σ (the data of the interval that ends at Σ).
    Below,
    /// The limit from Σ' > Σ (the data of the interval that starts at Σ).
    Above,
}

/// Σ_e = πR0/2, the equator of the reference sphere.
pub fn equator(r0: f64) -> f64 {
    0.5 * PI * r0
}

/// The breakpoints of the fibre angle: (a, b, Σ_e), with b = Σ_e/4 and a = b/5.
pub fn fibre_breakpoints(r0: f64) -> (f64, f64, f64) {
    let se = equator(r0);
    let b = se / 4.0;
    (b / 5.0, b, se)
}

/// Thickness H(Σ) of the initial shell. The non-uniform profile's own definition puts
/// Σ = πR0/2 on the first piece, which is `Side::Below`.
pub fn thickness(p: &Params, sigma_ref: f64, side: Side) -> f64 {
    match p.thickness {
        Thickness::Uniform => p.h0,
        Thickness::NonUniform => {
            let se = equator(p.r0);
            let first = sigma_ref < se || (sigma_ref == se && side == Side::Below);
            if first {
                0.65 - 0.2 * ((sigma_ref - PI * p.r0 / 6.0) / 1.5).tanh()
            } else {
                0.475 + 0.025 * (sigma_ref - 0.7 * PI * p.r0).tanh()
            }
        }
    }
}

/// Fibre angle ψ(Σ), measured from e_φ, with the paper's misprint fixed: the third piece
/// is 0.25 + 0.05 − 0.17 cos(·) (the paper's 0.15 makes ψ jump at b and Σ_e). ψ is
/// continuous; `side` only picks the piece at a kink.
pub fn fibre_angle(p: &Params, sigma_ref: f64, side: Side) -> f64 {
    let (a, b, se) = fibre_breakpoints(p.r0);
    let l = p.length();
    let before = |x: f64| sigma_ref < x || (sigma_ref == x && side == Side::Below);
    let psi_over_pi = if before(a) {
        0.25
    } else if before(b) {
        0.25 + 0.06 * (PI * (sigma_ref - a) / (b - a)).cos() - 0.06
    } else if before(se) {
        0.25 + 0.05 - 0.17 * (PI * (sigma_ref - b) / (se - b)).cos()
    } else {
        0.25 + 0.22 * (PI * (sigma_ref - se) / (l - se)).cos()
    };
    PI * psi_over_pi
}

/// Growth capacity g_c(Σ) = (η0/2)(1 + tanh((Γ − Σ)/δ)) (docs/MODEL.md §4).
pub fn growth_capacity(eta0: f64, gamma: f64, delta: f64, sigma_ref: f64) -> f64 {
    0.5 * eta0 * (1.0 + ((gamma - sigma_ref) / delta).tanh())
}

/// The points of (0, L) where the scene's material data jump or kink: πR0/2 always (H
/// jumps there when non-uniform, and ψ kinks), and a, b when there are fibres.
pub fn breakpoints(p: &Params) -> Vec<f64> {
    let (a, b, se) = fibre_breakpoints(p.r0);
    let mut pts = if p.has_fibres() {
        vec![a, b, se]
    } else {
        vec![se]
    };
    let l = p.length();
    pts.retain(|&x| x > 0.0 && x < l);
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fibre_params() -> Params {
        Params {
            thickness: Thickness::NonUniform,
            d: 200.0,
            ..Params::default()
        }
    }

    #[test]
    fn psi_is_continuous_with_the_misprint_fixed() {
        let p = fibre_params();
        let (a, b, se) = fibre_breakpoints(p.r0);
        for x in [a, b, se] {
            let lo = fibre_angle(&p, x, Side::Below);
            let hi = fibre_angle(&p, x, Side::Above);
            assert!((lo - hi).abs() < 1e-15, "ψ jumps at {x}: {lo} vs {hi}");
        }
        assert!((fibre_angle(&p, b, Side::Above) / PI - (0.25 - 0.12)).abs() < 1e-15);
        assert!((fibre_angle(&p, se, Side::Above) / PI - 0.47).abs() < 1e-15);
        assert!((fibre_angle(&p, 0.0, Side::Above) - PI / 4.0).abs() < 1e-15);
    }

    #[test]
    fn thickness_jumps_by_the_documented_amount() {
        let p = fibre_params();
        let se = equator(p.r0);
        let jump = thickness(&p, se, Side::Below) - thickness(&p, se, Side::Above);
        assert!((jump.abs() - 1.709e-7).abs() < 1e-9, "jump = {jump:e}");
        assert!(
            (thickness(&p, se, Side::Below) - thickness(&p, se - 1e-9, Side::Above)).abs() < 1e-9
        );
    }

    #[test]
    fn breakpoints_follow_the_scene() {
        let mut p = Params::default();
        assert_eq!(breakpoints(&p), vec![equator(10.0)]);
        p.d = 100.0;
        assert_eq!(breakpoints(&p).len(), 3);
    }

    #[test]
    fn growth_capacity_is_half_at_gamma() {
        assert!((growth_capacity(70.0, 8.0, 4.0, 8.0) - 35.0).abs() < 1e-14);
    }
}
