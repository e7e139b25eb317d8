//! The growth laws (docs/MODEL.md §5): growth only relieves tension and never shrinks.
//!   Dρ/Dt   = η [r − ρ]⁺
//!   Dγ_s/Dt = η γ_s [α_s − 1]⁺        (γ_s = ∂σ/∂Σ; the local form of Dσ/Dt = ∫ η [α_s − 1]⁺ dσ)
//! with η = g_c(Σ) g_v(Σ, t). The rates are only Lipschitz: the [·]⁺ kinks are kept as they
//! are (no smoothing).

/// How the thickness of the unloaded shell follows growth (docs/MODEL.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThicknessLaw {
    /// ζ = H: no growth across the thickness (γ_n = 1), the paper's choice.
    None,
    /// ζ = H / (γ_s γ_φ), γ_φ = ρ / R(Σ): mass conserved.
    Mass,
}

/// \[x\]⁺ = max(x, 0).
#[inline]
pub fn positive(x: f64) -> f64 {
    x.max(0.0)
}

/// \[x\]⁺ and its derivative, with the kink rounded over |x| < w when w > 0 (an explicit,
/// off-by-default option, `growth.kink_width`, for measuring what the kinks cost the time
/// integrators: docs/MODEL.md §5): (x + w)²/(4w) there, C¹ with x above and 0 below. With w = 0
/// it is max(x, 0) exactly, with the derivative of the branch taken (1 for x > 0, else 0).
#[inline]
pub fn positive_smooth(x: f64, w: f64) -> (f64, f64) {
    if x >= w {
        if x > 0.0 {
            (x, 1.0)
        } else {
            (0.0, 0.0)
        }
    } else if x <= -w {
        (0.0, 0.0)
    } else {
        ((x + w) * (x + w) / (4.0 * w), (x + w) / (2.0 * w))
    }
}

/// Dρ/Dt = η [r − ρ]⁺ (kink rounded over `w`).
#[inline]
pub fn rho_rate(eta: f64, r: f64, rho: f64, w: f64) -> f64 {
    eta * positive_smooth(r - rho, w).0
}

/// Dγ_s/Dt = η γ_s [α_s − 1]⁺ (kink rounded over `w`).
#[inline]
pub fn gamma_rate(eta: f64, gamma_s: f64, alpha_s: f64, w: f64) -> f64 {
    eta * gamma_s * positive_smooth(alpha_s - 1.0, w).0
}

/// ζ of the grown shell with initial thickness `h`; `rho_ref` = R(Σ) = R0 sin(Σ/R0) is the
/// initial radius, so γ_φ = ρ / R(Σ).
#[inline]
pub fn thickness(law: ThicknessLaw, h: f64, gamma_s: f64, rho: f64, rho_ref: f64) -> f64 {
    match law {
        ThicknessLaw::None => h,
        ThicknessLaw::Mass => h / (gamma_s * rho / rho_ref),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growth_never_shrinks() {
        assert_eq!(rho_rate(70.0, 9.0, 10.0, 0.0), 0.0);
        assert_eq!(gamma_rate(70.0, 1.2, 0.99, 0.0), 0.0);
        assert!((rho_rate(70.0, 10.1, 10.0, 0.0) - 7.0).abs() < 1e-12);
        assert!((gamma_rate(2.0, 1.5, 1.1, 0.0) - 0.3).abs() < 1e-12);
    }

    /// The rounded \[x\]⁺ is C¹, exact outside |x| < w, and max(x, 0) with w = 0.
    #[test]
    fn rounded_kink_is_c1_and_exact_outside() {
        let w = 0.1;
        for x in [-0.1, 0.1] {
            let (a, b) = (positive_smooth(x - 1e-12, w), positive_smooth(x + 1e-12, w));
            assert!(
                (a.0 - b.0).abs() < 1e-11 && (a.1 - b.1).abs() < 1e-10,
                "{x}: {a:?} {b:?}"
            );
        }
        assert_eq!(positive_smooth(0.3, w), (0.3, 1.0));
        assert_eq!(positive_smooth(-0.3, w), (0.0, 0.0));
        assert!((positive_smooth(0.0, w).0 - 0.025).abs() < 1e-16);
        for x in [-1.0, 0.0, 2.5] {
            assert_eq!(positive_smooth(x, 0.0).0, positive(x));
        }
        assert_eq!(positive_smooth(0.0, 0.0).1, 0.0);
    }

    #[test]
    fn mass_law_conserves_volume() {
        // H · (area element R dΣ) = ζ · (ρ γ_s dΣ).
        let (h, g, rho, rref) = (0.65, 1.3, 12.0, 10.0);
        let z = thickness(ThicknessLaw::Mass, h, g, rho, rref);
        assert!((z * rho * g - h * rref).abs() < 1e-12);
        assert_eq!(thickness(ThicknessLaw::None, h, g, rho, rref), h);
    }
}
