//! The equilibrium equations at one material point (MODEL.md §3), with their exact
//! Jacobian. The unknowns are y = (κ, r, θ, q_s, t_s):
//! - the traction t_s instead of α_s keeps it continuous across jumps of the material data
//!   (MODEL.md §4); α_s comes back from the constitutive law at each point (t_s is strictly
//!   increasing in α_s);
//! - the shear q_s = Q / r instead of Q: near the pole Q = O(r²) carries the information
//!   that fixes t_s there (through the first integral) in digits far below the round-off
//!   of Q elsewhere. With Q as unknown the pole condition amplifies Q's round-off into t_s
//!   by 1/(r sin θ) ~ 1/(ε² κ) (1e7 at ε = 1e-3, 1e17 at ε = 1e-8); with q_s, by
//!   1/sin θ ~ 1/(ε κ). (At ε = 1e-3 the 2e-7 error of t_s at Σ = ε is the O(ε²)
//!   truncation of the pole conditions, the same for both; it falls to 2e-9 at ε = 1e-4.)
//!
//! In the material coordinate Σ (d/dΣ = γ d/dσ, γ = ∂σ/∂Σ), with P = t_φ:
//!   κ'   = γ α_s [ (sin θ / r − κ) cos θ / r − q_s / E_b ]
//!   r'   = γ α_s cos θ
//!   θ'   = γ α_s κ
//!   q_s' = γ α_s [ ΔP − κ t_s − sin θ P / r − q_s cos θ / r ]      (Q' / r − Q r' / r²)
//!   t_s' = γ α_s [ κ q_s + (P − t_s) cos θ / r ]

use crate::model::constitutive::{FibreDirection, Law, Tensions};
use nalgebra::{SMatrix, SVector};

pub type Vec5 = SVector<f64, 5>;
pub type Mat5 = SMatrix<f64, 5, 5>;

/// Component indices of y.
pub const KAPPA: usize = 0;
pub const R: usize = 1;
pub const THETA: usize = 2;
pub const QS: usize = 3;
pub const TS: usize = 4;

/// Names of the components of y, for error messages.
pub const NAMES: [&str; 5] = ["kappa", "r", "theta", "q_s", "t_s"];

/// The constants of the shell that enter the equations.
#[derive(Clone, Copy, Debug)]
pub struct Shell {
    pub law: Law,
    /// Bending stiffness E_b.
    pub e_b: f64,
    /// Pressure difference ΔP.
    pub dp: f64,
}

/// The unloaded shell's data at one material point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialPoint {
    /// Σ, the material label.
    pub sigma_ref: f64,
    /// σ, arclength of the grown unloaded shell.
    pub sigma: f64,
    /// ρ, radius of the grown unloaded shell.
    pub rho: f64,
    /// ζ, thickness of the grown unloaded shell.
    pub zeta: f64,
    /// γ = ∂σ/∂Σ.
    pub gamma: f64,
    /// Fibre direction, when the scene has fibres.
    pub fibre: Option<FibreDirection>,
}

/// The right side f(Σ, y), its Jacobian ∂f/∂y, and what the point's constitutive solve gave.
#[derive(Clone, Copy, Debug)]
pub struct PointEval {
    pub f: Vec5,
    pub jac: Mat5,
    pub alpha_s: f64,
    /// ∂α_s/∂r and ∂α_s/∂t_s (implicit-function theorem on t_s(α_s, r/ρ) = t_s).
    pub alpha_s_r: f64,
    pub alpha_s_ts: f64,
    /// Tensions and their partials at (α_s, α_φ).
    pub tensions: Tensions,
}

/// Why the equations cannot be evaluated at a state.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum PointError {
    /// r ≤ 0 or not finite: the shell has passed through the axis.
    #[error("r ≤ 0: the shell has passed through its axis")]
    NonPositiveRadius,
    /// A component of y is not finite.
    #[error("an unknown is not finite")]
    NotFinite,
    /// The constitutive law could not be inverted for α_s.
    #[error("no stretch α_s gives this t_s")]
    StretchNotFound,
}

/// α_s at a point from the unknowns, with the tensions and the IFT derivatives.
#[inline]
pub fn stretch(shell: &Shell, mp: &MaterialPoint, r: f64, ts: f64, guess: f64) -> Result<(f64, f64, f64, Tensions), PointError> {
    if !(r > 0.0) || !r.is_finite() {
        return Err(PointError::NonPositiveRadius);
    }
    let phi = r / mp.rho;
    let (a, t) = shell
        .law
        .alpha_s_from_ts(mp.zeta, mp.fibre, ts, phi, guess)
        .ok_or(PointError::StretchNotFound)?;
    let a_ts = 1.0 / t.ts_a;
    let a_r = -t.ts_phi / (t.ts_a * mp.rho);
    Ok((a, a_r, a_ts, t))
}

/// f and ∂f/∂y at one point. `guess` seeds the α_s solve.
#[inline]
pub fn evaluate(shell: &Shell, mp: &MaterialPoint, y: &Vec5, guess: f64) -> Result<PointEval, PointError> {
    if !y.iter().all(|v| v.is_finite()) {
        return Err(PointError::NotFinite);
    }
    let (kappa, r, theta, q, ts) = (y[KAPPA], y[R], y[THETA], y[QS], y[TS]);
    let (a, a_r, a_ts, t) = stretch(shell, mp, r, ts, guess)?;
    let g = mp.gamma;
    let (sn, cs) = theta.sin_cos();
    let inv_r = 1.0 / r;
    let eb = shell.e_b;
    // t_φ along the solution: total derivatives through α_s(r, t_s).
    let p = t.tphi;
    let p_r = t.tphi_a * a_r + t.tphi_phi / mp.rho;
    let p_ts = t.tphi_a * a_ts;

    // Each right side is γ α_s g(y); its row is γ (α_s ∂g/∂y + g ∂α_s/∂y), where α_s
    // depends on r and t_s only. `grad` holds ∂g/∂(κ, r, θ, q_s, t_s).
    let mut f = Vec5::zeros();
    let mut j = Mat5::zeros();
    let mut row = |k: usize, gv: f64, grad: [f64; 5]| {
        f[k] = g * a * gv;
        for c in 0..5 {
            j[(k, c)] = g * a * grad[c];
        }
        j[(k, R)] += g * gv * a_r;
        j[(k, TS)] += g * gv * a_ts;
    };
    let u = sn * inv_r - kappa;
    let r2 = inv_r * inv_r;
    row(
        KAPPA,
        u * cs * inv_r - q / eb,
        [-cs * inv_r, -sn * cs * r2 * inv_r - u * cs * r2, (cs * cs - sn * sn) * r2 + kappa * sn * inv_r, -1.0 / eb, 0.0],
    );
    row(R, cs, [0.0, 0.0, -sn, 0.0, 0.0]);
    row(THETA, kappa, [1.0, 0.0, 0.0, 0.0, 0.0]);
    row(
        QS,
        shell.dp - kappa * ts - sn * p * inv_r - q * cs * inv_r,
        [
            -ts,
            -sn * p_r * inv_r + sn * p * r2 + q * cs * r2,
            -cs * p * inv_r + q * sn * inv_r,
            -cs * inv_r,
            -kappa - sn * p_ts * inv_r,
        ],
    );
    let d = p - ts;
    row(
        TS,
        kappa * q + d * cs * inv_r,
        [q, p_r * cs * inv_r - d * cs * r2, -d * sn * inv_r, kappa, (p_ts - 1.0) * cs * inv_r],
    );

    Ok(PointEval { f, jac: j, alpha_s: a, alpha_s_r: a_r, alpha_s_ts: a_ts, tensions: t })
}

/// The first integral divided by r, q_s cos θ + t_s sin θ − r ΔP / 2: the pole condition.
pub fn first_integral_over_r(dp: f64, y: &Vec5) -> f64 {
    let (sn, cs) = y[THETA].sin_cos();
    y[QS] * cs + y[TS] * sn - 0.5 * y[R] * dp
}

/// The first integral Q cos θ + r t_s sin θ − r² ΔP / 2 (Q = r q_s), zero along a closed
/// shell (MODEL.md §3).
pub fn first_integral(dp: f64, y: &Vec5) -> f64 {
    y[R] * first_integral_over_r(dp, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∂f/∂y against central differences, with and without fibres.
    #[test]
    fn point_jacobian_matches_differences() {
        for d in [None, Some(200.0)] {
            let shell = Shell { law: Law { c: 100.0, d }, e_b: 18.0, dp: 2.0 };
            let mp = MaterialPoint {
                sigma_ref: 3.0,
                sigma: 3.1,
                rho: 2.9,
                zeta: 0.6,
                gamma: 1.05,
                fibre: d.map(|_| FibreDirection::from_angle(1.1)),
            };
            let y = Vec5::new(0.11, 3.0, 0.33, 0.4, 7.0);
            let e = evaluate(&shell, &mp, &y, 1.0).unwrap();
            for c in 0..5 {
                let h = 1e-6 * y[c].abs().max(1e-2);
                let mut yp = y;
                let mut ym = y;
                yp[c] += h;
                ym[c] -= h;
                let fd = (evaluate(&shell, &mp, &yp, 1.0).unwrap().f - evaluate(&shell, &mp, &ym, 1.0).unwrap().f) / (2.0 * h);
                for row in 0..5 {
                    let (a, b) = (e.jac[(row, c)], fd[row]);
                    assert!((a - b).abs() < 1e-6 * (1.0 + a.abs()), "d={d:?} ({row},{c}): {a} vs {b}");
                }
            }
        }
    }
}
