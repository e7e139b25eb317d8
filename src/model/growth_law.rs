//! The growth laws (MODEL.md §5): growth only relieves tension and never shrinks.
//!   Dρ/Dt   = η [r − ρ]⁺
//!   Dγ_s/Dt = η γ_s [α_s − 1]⁺        (γ_s = ∂σ/∂Σ; the local form of Dσ/Dt = ∫ η [α_s − 1]⁺ dσ)
//! with η = g_c(Σ) g_v(Σ, t). The rates are only Lipschitz: the [·]⁺ kinks are kept as they
//! are (no smoothing).

/// How the thickness of the unloaded shell follows growth (MODEL.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThicknessLaw {
    /// ζ = H: no growth across the thickness (γ_n = 1), the paper's choice.
    None,
    /// ζ = H / (γ_s γ_φ), γ_φ = ρ / R(Σ): mass conserved.
    Mass,
}

/// [x]⁺ = max(x, 0).
#[inline]
pub fn positive(x: f64) -> f64 {
    x.max(0.0)
}

/// Dρ/Dt = η [r − ρ]⁺.
#[inline]
pub fn rho_rate(eta: f64, r: f64, rho: f64) -> f64 {
    eta * positive(r - rho)
}

/// Dγ_s/Dt = η γ_s [α_s − 1]⁺.
#[inline]
pub fn gamma_rate(eta: f64, gamma_s: f64, alpha_s: f64) -> f64 {
    eta * gamma_s * positive(alpha_s - 1.0)
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
        assert_eq!(rho_rate(70.0, 9.0, 10.0), 0.0);
        assert_eq!(gamma_rate(70.0, 1.2, 0.99), 0.0);
        assert!((rho_rate(70.0, 10.1, 10.0) - 7.0).abs() < 1e-12);
        assert!((gamma_rate(2.0, 1.5, 1.1) - 0.3).abs() < 1e-12);
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
