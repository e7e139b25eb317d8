//! The cornea: a neo-Hookean sphere inflated uniformly (Adkins; docs/MODEL.md §3).
//!
//! ΔP = 4 C_c H_c / (α R_c) · (1 − α⁻⁶) for α ∈ (1, 7^(1/6)). The right side peaks at
//! α = 7^(1/6), so a larger ΔP has no inflated cornea at all: that is an error naming the
//! limit. The cornea fixes the shell's front edge: θ* = L/R_c, r* = α R_c sin(L/R_c),
//! z* = α R_c (1 + cos(L/R_c)).

use super::params::CorneaParams;
use super::ModelError;

/// The pressure of a cornea inflated to stretch `alpha`.
pub fn pressure(c: &CorneaParams, alpha: f64) -> f64 {
    4.0 * c.c * c.h / c.r0 * (1.0 / alpha - alpha.powi(-7))
}

/// The stretch at which the cornea's pressure peaks, 7^(1/6).
pub fn alpha_max() -> f64 {
    7f64.powf(1.0 / 6.0)
}

/// The largest pressure the cornea can hold: 4 C_c H_c / R_c · (6/7) · 7^(−1/6).
pub fn max_pressure(c: &CorneaParams) -> f64 {
    pressure(c, alpha_max())
}

/// The cornea's stretch α at pressure `dp`, to full double precision.
///
/// The pressure rises monotonically on (1, 7^(1/6)), so bisection on α − 1 (relative, so
/// that tiny pressures keep their digits) brackets the root to a few ulps; two Newton steps
/// on the same variable finish it.
pub fn stretch(c: &CorneaParams, dp: f64) -> Result<f64, ModelError> {
    let p_max = max_pressure(c);
    if !(dp >= 0.0) {
        return Err(ModelError::NegativePressure { dp });
    }
    if dp > p_max {
        return Err(ModelError::PressureAboveCorneaLimit { dp, max: p_max });
    }
    if dp == 0.0 {
        return Ok(1.0);
    }
    let k = 4.0 * c.c * c.h / c.r0;
    // In e = α − 1: p = k (1/α − α⁻⁷), written so that small e loses nothing to cancellation.
    let p_of = |e: f64| {
        let a = 1.0 + e;
        k * (a.powi(6) - 1.0) / a.powi(7)
    };
    let (mut lo, mut hi) = (0.0, alpha_max() - 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if p_of(mid) < dp {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut e = 0.5 * (lo + hi);
    for _ in 0..2 {
        let a = 1.0 + e;
        let dp_de = k * (-a.powi(-2) + 7.0 * a.powi(-8));
        if dp_de > 0.0 {
            let next = e - (p_of(e) - dp) / dp_de;
            if next > 0.0 && next < alpha_max() - 1.0 {
                e = next;
            }
        }
    }
    Ok(1.0 + e)
}

/// dα/dΔP at stretch `alpha`: the reciprocal of the law's slope,
/// dΔP/dα = 4 C_c H_c / R_c · (7 α⁻⁸ − α⁻²) (> 0 below 7^(1/6)); for forward sensitivities.
pub fn stretch_per_pressure(c: &CorneaParams, alpha: f64) -> f64 {
    let k = 4.0 * c.c * c.h / c.r0;
    1.0 / (k * (7.0 * alpha.powi(-8) - alpha.powi(-2)))
}

/// Where the cornea holds the shell's front edge (docs/MODEL.md §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorneaEdge {
    /// The cornea's stretch α.
    pub alpha: f64,
    /// θ* = L / R_c.
    pub theta: f64,
    /// r* = α R_c sin(L / R_c).
    pub r: f64,
    /// z* = α R_c (1 + cos(L / R_c)).
    pub z: f64,
}

/// The edge conditions at Σ = L for a shell of material length `length`.
pub fn edge(c: &CorneaParams, dp: f64, length: f64) -> Result<CorneaEdge, ModelError> {
    let alpha = stretch(c, dp)?;
    let phi = length / c.r0;
    Ok(CorneaEdge {
        alpha,
        theta: phi,
        r: alpha * c.r0 * phi.sin(),
        z: alpha * c.r0 * (1.0 + phi.cos()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> CorneaParams {
        CorneaParams {
            c: 100.0,
            h: 0.65,
            r0: 10.0,
        }
    }

    #[test]
    fn default_stretch_matches_model_md() {
        let a = stretch(&paper(), 2.0).unwrap();
        assert!((a - 1.0136216901111).abs() < 1e-12, "alpha = {a:.16}");
        // Full precision: the residual is at round-off.
        assert!((pressure(&paper(), a) - 2.0).abs() < 1e-14);
    }

    /// Tiny pressures keep their digits: α − 1 ≈ ΔP R_c / (24 C_c H_c).
    #[test]
    fn tiny_pressures_are_exact() {
        for dp in [1e-12, 1e-6, 1e-3] {
            let a = stretch(&paper(), dp).unwrap();
            let linear = dp * 10.0 / (24.0 * 100.0 * 0.65);
            // α is a double near 1: α − 1 is known to an ulp of 1 (2.2e-16) at best.
            assert!(
                (a - 1.0 - linear).abs() < 4.0 * f64::EPSILON + 1e-4 * linear,
                "dp {dp:e}: α − 1 = {:e}, linear {linear:e}",
                a - 1.0
            );
            // pressure() itself cancels near α = 1: about k·ε = 6e-15 of round-off.
            assert!(
                (pressure(&paper(), a) - dp).abs() <= 1e-13 + 1e-12 * dp,
                "dp {dp:e}"
            );
        }
    }

    #[test]
    fn pressure_above_limit_names_the_limit() {
        let max = max_pressure(&paper());
        assert!((max - 26.0 * 6.0 / 7.0 * 7f64.powf(-1.0 / 6.0)).abs() < 1e-12);
        let err = stretch(&paper(), max * 1.001).unwrap_err();
        assert!(err.to_string().contains(&format!("{max:.6}")), "{err}");
        assert!((stretch(&paper(), max).unwrap() - alpha_max()).abs() < 1e-7);
    }
}
