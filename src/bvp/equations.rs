//! The equilibrium equations at one material point (MODEL.md §3), with their exact
//! Jacobian. The unknowns are y = (κ, r, θ, Q, t_s): carrying the traction t_s instead of
//! α_s keeps it continuous across jumps of the material data (MODEL.md §4), and α_s comes
//! back from the constitutive law at each point (t_s is strictly increasing in α_s).
//!
//! In the material coordinate Σ (d/dΣ = γ d/dσ, γ = ∂σ/∂Σ):
//!   κ' = γ α_s [ (sin θ / r − κ) cos θ / r − Q / (r E_b) ]
//!   r' = γ α_s cos θ
//!   θ' = γ α_s κ
//!   Q' = γ α_s [ r ΔP − κ r t_s − sin θ t_φ ]
//!   t_s' = γ (α_s / r) [ κ Q + (t_φ − t_s) cos θ ]

use crate::model::constitutive::{FibreDirection, Law, Tensions};
use nalgebra::{SMatrix, SVector};

pub type Vec5 = SVector<f64, 5>;
pub type Mat5 = SMatrix<f64, 5, 5>;

/// Component indices of y.
pub const KAPPA: usize = 0;
pub const R: usize = 1;
pub const THETA: usize = 2;
pub const Q: usize = 3;
pub const TS: usize = 4;

/// Names of the components of y, for error messages.
pub const NAMES: [&str; 5] = ["kappa", "r", "theta", "Q", "t_s"];

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
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointError {
    /// r ≤ 0 or not finite: the shell has passed through the axis.
    NonPositiveRadius,
    /// A component of y is not finite.
    NotFinite,
    /// The constitutive law could not be inverted for α_s.
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
    let (kappa, r, theta, q, ts) = (y[KAPPA], y[R], y[THETA], y[Q], y[TS]);
    let (a, a_r, a_ts, t) = stretch(shell, mp, r, ts, guess)?;
    let g = mp.gamma;
    let (sn, cs) = theta.sin_cos();
    let inv_r = 1.0 / r;
    let eb = shell.e_b;
    // t_φ along the solution: total derivatives through α_s(r, t_s).
    let p = t.tphi;
    let p_r = t.tphi_a * a_r + t.tphi_phi / mp.rho;
    let p_ts = t.tphi_a * a_ts;

    let mut f = Vec5::zeros();
    let mut j = Mat5::zeros();

    // κ' = γ a g0
    let u = sn * inv_r - kappa;
    let g0 = u * cs * inv_r - q * inv_r / eb;
    let g0_k = -cs * inv_r;
    let g0_r = -sn * cs * inv_r * inv_r * inv_r - u * cs * inv_r * inv_r + q * inv_r * inv_r / eb;
    let g0_th = (cs * cs - sn * sn) * inv_r * inv_r + kappa * sn * inv_r;
    let g0_q = -inv_r / eb;
    f[KAPPA] = g * a * g0;
    j[(KAPPA, KAPPA)] = g * a * g0_k;
    j[(KAPPA, R)] = g * (a * g0_r + g0 * a_r);
    j[(KAPPA, THETA)] = g * a * g0_th;
    j[(KAPPA, Q)] = g * a * g0_q;
    j[(KAPPA, TS)] = g * g0 * a_ts;

    // r' = γ a cos θ
    f[R] = g * a * cs;
    j[(R, R)] = g * a_r * cs;
    j[(R, THETA)] = -g * a * sn;
    j[(R, TS)] = g * a_ts * cs;

    // θ' = γ a κ
    f[THETA] = g * a * kappa;
    j[(THETA, KAPPA)] = g * a;
    j[(THETA, R)] = g * a_r * kappa;
    j[(THETA, TS)] = g * a_ts * kappa;

    // Q' = γ a g3, g3 = r ΔP − κ r t_s − sin θ t_φ
    let g3 = r * shell.dp - kappa * r * ts - sn * p;
    f[Q] = g * a * g3;
    j[(Q, KAPPA)] = -g * a * r * ts;
    j[(Q, R)] = g * (a * (shell.dp - kappa * ts - sn * p_r) + g3 * a_r);
    j[(Q, THETA)] = -g * a * cs * p;
    j[(Q, TS)] = g * (a * (-kappa * r - sn * p_ts) + g3 * a_ts);

    // t_s' = γ w g4, w = a / r, g4 = κ Q + (t_φ − t_s) cos θ
    let w = a * inv_r;
    let w_r = a_r * inv_r - a * inv_r * inv_r;
    let w_ts = a_ts * inv_r;
    let g4 = kappa * q + (p - ts) * cs;
    f[TS] = g * w * g4;
    j[(TS, KAPPA)] = g * w * q;
    j[(TS, R)] = g * (w * p_r * cs + g4 * w_r);
    j[(TS, THETA)] = -g * w * (p - ts) * sn;
    j[(TS, Q)] = g * w * kappa;
    j[(TS, TS)] = g * (w * (p_ts - 1.0) * cs + g4 * w_ts);

    Ok(PointEval { f, jac: j, alpha_s: a, alpha_s_r: a_r, alpha_s_ts: a_ts, tensions: t })
}

/// The first integral Q cos θ + r t_s sin θ − r² ΔP / 2, zero along a closed shell.
pub fn first_integral(dp: f64, y: &Vec5) -> f64 {
    let (sn, cs) = y[THETA].sin_cos();
    y[Q] * cs + y[R] * y[TS] * sn - 0.5 * y[R] * y[R] * dp
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
