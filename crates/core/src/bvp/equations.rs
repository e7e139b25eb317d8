//! The equilibrium equations at one material point (docs/MODEL.md §3), with their exact
//! Jacobian. The unknowns are y = (κ, r, θ, q_s, t_s):
//! - the traction t_s instead of α_s keeps it continuous across jumps of the material data
//!   (docs/MODEL.md §4); α_s comes back from the constitutive law at each point (t_s is strictly
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
//!
//! The material enters only through the membrane law at each point (t_s, t_φ and their
//! partials in (α_s, α_φ)) and the point's data (ρ, ζ, γ, and ψ with fibres). With t_s as
//! the unknown, nothing differentiates the material data along Σ: no dζ/dΣ, dψ/dΣ or dρ/dσ
//! term exists in f or ∂f/∂y (see `model::components`).
//!
//! [`Equations<R>`] is the shell with its membrane component R fixed at compile time
//! (docs/MODEL.md §2: neo-Hookean, or reinforced by fibres): the discretisation resolves the
//! scene's component once per pass and calls [`Equations::evaluate`], so the fibre-free f
//! and ∂f/∂y contain no fibre code. [`evaluate`] and [`stretch`] take a [`Shell`] of
//! either kind and dispatch once per call.

use crate::model::components::Membrane;
use crate::model::constitutive::{
    FibreDirection, Fibres, Law, MembraneLaw, NoFibres, Reinforcement, Tensions,
};
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

impl Shell {
    /// The scene's membrane component: neo-Hookean, or reinforced by fibres.
    pub fn membrane(&self) -> Membrane {
        Membrane::from(self.law)
    }
}

/// The shell's equations with the membrane law's reinforcement R fixed at compile time.
#[derive(Clone, Copy, Debug)]
pub struct Equations<R: Reinforcement> {
    law: MembraneLaw<R>,
    /// Pressure difference ΔP.
    dp: f64,
    /// 1/E_b, so that a point evaluation multiplies instead of dividing.
    inv_e_b: f64,
}

impl Equations<NoFibres> {
    /// A fibre-free shell: `shell.law.d` is ignored.
    pub fn neo_hookean(shell: &Shell) -> Self {
        Equations::new(MembraneLaw::neo_hookean(shell.law.c), shell)
    }
}

impl Equations<Fibres> {
    /// A shell with fibres of stiffness D.
    pub fn reinforced(shell: &Shell, d: f64) -> Self {
        Equations::new(MembraneLaw::reinforced(shell.law.c, d), shell)
    }
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
    /// sin θ and cos θ at the point (the quadratures and the growth rates reuse them).
    pub sin_theta: f64,
    pub cos_theta: f64,
}

impl PointEval {
    /// A slot not yet evaluated: zeros, and α_s = NaN, which no evaluation leaves.
    pub fn unset() -> PointEval {
        PointEval {
            f: Vec5::zeros(),
            jac: Mat5::zeros(),
            alpha_s: f64::NAN,
            alpha_s_r: 0.0,
            alpha_s_ts: 0.0,
            tensions: Tensions::default(),
            sin_theta: 0.0,
            cos_theta: 1.0,
        }
    }

    /// True once an evaluation has been written here.
    pub fn is_set(&self) -> bool {
        !self.alpha_s.is_nan()
    }
}

/// Why the equations cannot be evaluated at a state.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
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

/// α_s at a point from the unknowns, with the tensions and the IFT derivatives
/// (dispatching once on the shell's membrane component; see [`Equations::stretch`]).
#[inline]
pub fn stretch(
    shell: &Shell,
    mp: &MaterialPoint,
    r: f64,
    ts: f64,
    guess: f64,
) -> Result<(f64, f64, f64, Tensions), PointError> {
    match shell.membrane() {
        Membrane::NeoHookean { .. } => Equations::neo_hookean(shell).stretch(mp, r, ts, guess),
        Membrane::Reinforced { d, .. } => Equations::reinforced(shell, d).stretch(mp, r, ts, guess),
    }
}

/// f and ∂f/∂y at one point. `guess` seeds the α_s solve (dispatching once on the shell's
/// membrane component; see [`Equations::evaluate`]). The assembly calls
/// [`Equations::evaluate_part`]; this allocating form serves one-off points (the tests,
/// bvp4c's yp at the nodes).
pub fn evaluate(
    shell: &Shell,
    mp: &MaterialPoint,
    y: &Vec5,
    guess: f64,
) -> Result<PointEval, PointError> {
    match shell.membrane() {
        Membrane::NeoHookean { .. } => Equations::neo_hookean(shell).evaluate(mp, y, guess),
        Membrane::Reinforced { d, .. } => Equations::reinforced(shell, d).evaluate(mp, y, guess),
    }
}

impl<R: Reinforcement> Equations<R> {
    /// The shell's E_b and ΔP with the membrane law `law`.
    pub fn new(law: MembraneLaw<R>, shell: &Shell) -> Self {
        Equations {
            law,
            dp: shell.dp,
            inv_e_b: 1.0 / shell.e_b,
        }
    }

    /// α_s at a point from the unknowns, with the tensions and the IFT derivatives
    /// ∂α_s/∂r, ∂α_s/∂t_s. The point's fibre data are read only when R has fibres.
    #[inline]
    pub fn stretch(
        &self,
        mp: &MaterialPoint,
        r: f64,
        ts: f64,
        guess: f64,
    ) -> Result<(f64, f64, f64, Tensions), PointError> {
        if !r.is_finite() || r <= 0.0 {
            return Err(PointError::NonPositiveRadius);
        }
        let phi = r / mp.rho;
        let (a, t) = self
            .law
            .alpha_s_from_ts(mp.zeta, R::direction(&mp.fibre), ts, phi, guess)
            .ok_or(PointError::StretchNotFound)?;
        let a_ts = 1.0 / t.ts_a;
        let a_r = -t.ts_phi * a_ts / mp.rho;
        Ok((a, a_r, a_ts, t))
    }

    /// f and ∂f/∂y at one point. `guess` seeds the α_s solve.
    pub fn evaluate(
        &self,
        mp: &MaterialPoint,
        y: &Vec5,
        guess: f64,
    ) -> Result<PointEval, PointError> {
        let mut out = PointEval::unset();
        self.evaluate_part(mp, y, guess, &mut out, Part::Full)?;
        Ok(out)
    }

    /// What `part` asks of one point, written in place (the assembly's buffers: no
    /// 300-byte copies); on error `out` is left as it was.
    /// [`Part::Values`] leaves ∂f/∂y and ∂α_s/∂(r, t_s) as they were; [`Part::Derivatives`]
    /// reads α_s and the tensions from `out`, which must hold the values at this `y` and
    /// these data, and writes the rest: every number as the full evaluation writes it.
    #[inline]
    pub fn evaluate_part(
        &self,
        mp: &MaterialPoint,
        y: &Vec5,
        guess: f64,
        out: &mut PointEval,
        part: Part,
    ) -> Result<(), PointError> {
        if !y.iter().all(|v| v.is_finite()) {
            return Err(PointError::NotFinite);
        }
        let (kappa, r, theta, q, ts) = (y[KAPPA], y[R], y[THETA], y[QS], y[TS]);
        let (a, t) = match part {
            Part::Derivatives => (out.alpha_s, out.tensions),
            Part::Values | Part::Full => {
                if !r.is_finite() || r <= 0.0 {
                    return Err(PointError::NonPositiveRadius);
                }
                self.law
                    .alpha_s_from_ts(mp.zeta, R::direction(&mp.fibre), ts, r / mp.rho, guess)
                    .ok_or(PointError::StretchNotFound)?
            }
        };
        let g = mp.gamma;
        let (sn, cs) = theta.sin_cos();
        let inv_r = 1.0 / r;
        let inv_eb = self.inv_e_b;
        let p = t.tphi;
        let u = sn * inv_r - kappa;
        let d = p - ts;
        // Each right side is γ α_s g(y).
        let gv = [
            u * cs * inv_r - q * inv_eb,
            cs,
            kappa,
            self.dp - kappa * ts - sn * p * inv_r - q * cs * inv_r,
            kappa * q + d * cs * inv_r,
        ];
        for (fk, gk) in out.f.iter_mut().zip(gv) {
            *fk = g * a * gk;
        }
        out.alpha_s = a;
        out.tensions = t;
        out.sin_theta = sn;
        out.cos_theta = cs;
        if matches!(part, Part::Values) {
            return Ok(());
        }
        // The IFT derivatives of α_s(r, t_s), as [`Self::stretch`] has them.
        let a_ts = 1.0 / t.ts_a;
        let a_r = -t.ts_phi * a_ts / mp.rho;
        // t_φ along the solution: total derivatives through α_s(r, t_s).
        let p_r = t.tphi_a * a_r + t.tphi_phi / mp.rho;
        let p_ts = t.tphi_a * a_ts;
        // Each row is γ (α_s ∂g/∂y + g ∂α_s/∂y), where α_s depends on r and t_s only.
        // `grad` holds ∂g/∂(κ, r, θ, q_s, t_s). Every entry of ∂f/∂y is written.
        let r2 = inv_r * inv_r;
        let grads = [
            [
                -cs * inv_r,
                -sn * cs * r2 * inv_r - u * cs * r2,
                (cs * cs - sn * sn) * r2 + kappa * sn * inv_r,
                -inv_eb,
                0.0,
            ],
            [0.0, 0.0, -sn, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0, 0.0],
            [
                -ts,
                -sn * p_r * inv_r + sn * p * r2 + q * cs * r2,
                -cs * p * inv_r + q * sn * inv_r,
                -cs * inv_r,
                -kappa - sn * p_ts * inv_r,
            ],
            [
                q,
                p_r * cs * inv_r - d * cs * r2,
                -d * sn * inv_r,
                kappa,
                (p_ts - 1.0) * cs * inv_r,
            ],
        ];
        let j = &mut out.jac;
        for (k, (grad, gk)) in grads.iter().zip(gv).enumerate() {
            for c in 0..5 {
                j[(k, c)] = g * a * grad[c];
            }
            j[(k, R)] += g * gk * a_r;
            j[(k, TS)] += g * gk * a_ts;
        }
        out.alpha_s_r = a_r;
        out.alpha_s_ts = a_ts;
        Ok(())
    }
}

/// What an evaluation of a point writes ([`Equations::evaluate_part`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// f, α_s, the tensions, sin θ and cos θ: what a residual, the quadratures and the
    /// growth rates read.
    Values,
    /// ∂f/∂y and ∂α_s/∂(r, t_s) besides, from the values already in the slot (the same y).
    Derivatives,
    /// Both, from scratch.
    Full,
}

/// ∂f and ∂α_s with respect to a point's data (ρ, ζ, γ) at fixed y: what the coupled growth
/// Jacobian needs of the elastic equations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DataPartials {
    pub f_rho: Vec5,
    pub f_zeta: Vec5,
    pub f_gamma: Vec5,
    /// ∂α_s/∂ρ and ∂α_s/∂ζ at fixed (r, t_s).
    pub alpha_s_rho: f64,
    pub alpha_s_zeta: f64,
}

/// The data partials from the evaluation `e` of f at (`mp`, `y`). α_s solves
/// ζ τ_s(α_s, φ) = t_s with φ = r/ρ, so ρ enters through φ only and ζ as a factor:
///   ∂α_s/∂ρ = −φ ∂α_s/∂r,   ∂α_s/∂ζ = −(t_s/ζ) ∂α_s/∂t_s;
/// t_φ = ζ τ_φ(α_s, φ) follows along, and f = γ α_s g(y, t_φ) with g_QS ∋ −sin θ t_φ / r,
/// g_TS ∋ t_φ cos θ / r.
pub fn data_partials(mp: &MaterialPoint, y: &Vec5, e: &PointEval) -> DataPartials {
    let (r, theta) = (y[R], y[THETA]);
    let t = &e.tensions;
    let (a, g) = (e.alpha_s, mp.gamma);
    let a_rho = -e.alpha_s_r * r / mp.rho;
    let a_zeta = -(t.ts / mp.zeta) * e.alpha_s_ts;
    let p_rho = t.tphi_a * a_rho - t.tphi_phi * r / (mp.rho * mp.rho);
    let p_zeta = t.tphi / mp.zeta + t.tphi_a * a_zeta;
    let (sn, cs) = theta.sin_cos();
    let g_of_y = e.f / (g * a);
    let dg_dp = Vec5::new(0.0, 0.0, 0.0, -sn / r, cs / r);
    DataPartials {
        f_rho: g * (a_rho * g_of_y + (a * p_rho) * dg_dp),
        f_zeta: g * (a_zeta * g_of_y + (a * p_zeta) * dg_dp),
        f_gamma: e.f / g,
        alpha_s_rho: a_rho,
        alpha_s_zeta: a_zeta,
    }
}

/// A constant of the shell that the equations can be differentiated by (for the forward
/// sensitivities, docs/MODEL.md §10): the membrane's C and D (docs/MODEL.md §2), E_b and ΔP (§3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShellConstant {
    Modulus,
    FibreStiffness,
    Bending,
    Pressure,
}

/// ∂f and ∂α_s with respect to one shell constant at fixed y (and fixed material data).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConstantPartials {
    pub f: Vec5,
    pub alpha_s: f64,
}

/// The partials of f and α_s in the shell constant `which`, from the evaluation `e` of f at
/// (`mp`, `y`) with the shell's constants. The tensions are linear in C and D at fixed
/// stretches, t = C T_C(α_s, φ) + D T_D(α_s, φ), so their partials at fixed (α_s, φ) are the
/// law's own tensions with (C, D) = (1, 0) or (0, 1); α_s solves t_s(α_s, φ; C, D) = t_s, so
///   ∂α_s/∂C = −(∂t_s/∂C)/(∂t_s/∂α_s)   (implicit function theorem, as [`data_partials`]),
/// and t_φ follows along. E_b enters only f_κ ∋ −γ α_s q_s / E_b, ΔP only f_{q_s} ∋ γ α_s ΔP.
pub fn constant_partials(
    shell: &Shell,
    which: ShellConstant,
    mp: &MaterialPoint,
    y: &Vec5,
    e: &PointEval,
) -> ConstantPartials {
    let (a, g) = (e.alpha_s, mp.gamma);
    let mut out = ConstantPartials::default();
    let unit = match which {
        ShellConstant::Bending => {
            out.f[KAPPA] = g * a * y[QS] / (shell.e_b * shell.e_b);
            return out;
        }
        ShellConstant::Pressure => {
            out.f[QS] = g * a;
            return out;
        }
        ShellConstant::Modulus => Law {
            c: 1.0,
            d: shell.law.d.map(|_| 0.0),
        },
        ShellConstant::FibreStiffness => Law {
            c: 0.0,
            d: Some(1.0),
        },
    };
    let (r, theta) = (y[R], y[THETA]);
    let fibre = shell.law.d.and(mp.fibre);
    let per = unit.tensions(mp.zeta, fibre, a, r / mp.rho);
    let t = &e.tensions;
    let a_x = -per.ts * e.alpha_s_ts;
    let p_x = per.tphi + t.tphi_a * a_x;
    let (sn, cs) = theta.sin_cos();
    let g_of_y = e.f / (g * a);
    let dg_dp = Vec5::new(0.0, 0.0, 0.0, -sn / r, cs / r);
    out.f = g * (a_x * g_of_y + (a * p_x) * dg_dp);
    out.alpha_s = a_x;
    out
}

/// The first integral divided by r, q_s cos θ + t_s sin θ − r ΔP / 2: the pole condition.
pub fn first_integral_over_r(dp: f64, y: &Vec5) -> f64 {
    let (sn, cs) = y[THETA].sin_cos();
    y[QS] * cs + y[TS] * sn - 0.5 * y[R] * dp
}

/// The first integral Q cos θ + r t_s sin θ − r² ΔP / 2 (Q = r q_s), zero along a closed
/// shell (docs/MODEL.md §3).
pub fn first_integral(dp: f64, y: &Vec5) -> f64 {
    y[R] * first_integral_over_r(dp, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fibre-free equations never read a point's fibre data.
    #[test]
    fn fibre_free_equations_ignore_fibre_data() {
        let shell = Shell {
            law: Law { c: 100.0, d: None },
            e_b: 18.0,
            dp: 2.0,
        };
        let bare = MaterialPoint {
            sigma_ref: 3.0,
            sigma: 3.1,
            rho: 2.9,
            zeta: 0.6,
            gamma: 1.05,
            fibre: None,
        };
        let with = MaterialPoint {
            fibre: Some(FibreDirection::from_angle(0.2)),
            ..bare
        };
        let y = Vec5::new(0.11, 3.2, 0.33, 0.4, 7.0);
        let eq = Equations::neo_hookean(&shell);
        let (a, b) = (
            eq.evaluate(&bare, &y, 1.0).unwrap(),
            eq.evaluate(&with, &y, 1.0).unwrap(),
        );
        assert_eq!((a.f, a.jac, a.alpha_s), (b.f, b.jac, b.alpha_s));
        assert_eq!(evaluate(&shell, &with, &y, 1.0).unwrap().f, a.f);
    }

    /// The values alone, then their derivatives from them, write exactly the numbers one
    /// full evaluation writes (with and without fibres), and the values alone leave the
    /// derivatives' slots as they were.
    #[test]
    fn values_then_derivatives_are_the_full_evaluation() {
        for d in [None, Some(200.0)] {
            let (shell, mp, y) = test_point(d);
            let run = |eq: &dyn Fn(&mut PointEval, Part)| {
                let mut full = PointEval::unset();
                eq(&mut full, Part::Full);
                let mut split = PointEval::unset();
                split.jac[(2, 3)] = 7.0;
                split.alpha_s_r = 5.0;
                eq(&mut split, Part::Values);
                assert_eq!(split.f, full.f);
                assert_eq!(split.alpha_s, full.alpha_s);
                assert_eq!(split.tensions, full.tensions);
                assert_eq!(
                    (split.sin_theta, split.cos_theta),
                    (full.sin_theta, full.cos_theta)
                );
                assert_eq!((split.jac[(2, 3)], split.alpha_s_r), (7.0, 5.0));
                eq(&mut split, Part::Derivatives);
                assert_eq!(split.jac, full.jac);
                assert_eq!(
                    (split.alpha_s_r, split.alpha_s_ts),
                    (full.alpha_s_r, full.alpha_s_ts)
                );
                assert_eq!(split.f, full.f);
            };
            match d {
                None => {
                    let eq = Equations::neo_hookean(&shell);
                    run(&|out, part| eq.evaluate_part(&mp, &y, 1.0, out, part).unwrap());
                }
                Some(d) => {
                    let eq = Equations::reinforced(&shell, d);
                    run(&|out, part| eq.evaluate_part(&mp, &y, 1.0, out, part).unwrap());
                }
            }
        }
    }

    /// A shell (with fibres of stiffness `d`, if any), a grown point and a state off
    /// equilibrium, for the derivative checks.
    fn test_point(d: Option<f64>) -> (Shell, MaterialPoint, Vec5) {
        let shell = Shell {
            law: Law { c: 100.0, d },
            e_b: 18.0,
            dp: 2.0,
        };
        let mp = MaterialPoint {
            sigma_ref: 3.0,
            sigma: 3.1,
            rho: 2.9,
            zeta: 0.6,
            gamma: 1.05,
            fibre: d.map(|_| FibreDirection::from_angle(1.1)),
        };
        (shell, mp, Vec5::new(0.11, 3.0, 0.33, 0.4, 7.0))
    }

    /// ∂f/∂(ρ, ζ, γ) and ∂α_s/∂(ρ, ζ) against central differences, with and without fibres.
    #[test]
    fn data_partials_match_differences() {
        for d in [None, Some(200.0)] {
            let (shell, mp, y) = test_point(d);
            let e = evaluate(&shell, &mp, &y, 1.0).unwrap();
            let dp = data_partials(&mp, &y, &e);
            let at = |m: MaterialPoint| evaluate(&shell, &m, &y, 1.0).unwrap();
            let h = 1e-6;
            type Case = (fn(&mut MaterialPoint, f64), Vec5, Option<f64>);
            let cases: [Case; 3] = [
                (|m, h| m.rho += h, dp.f_rho, Some(dp.alpha_s_rho)),
                (|m, h| m.zeta += h, dp.f_zeta, Some(dp.alpha_s_zeta)),
                (|m, h| m.gamma += h, dp.f_gamma, None),
            ];
            for (k, (bump, f_x, a_x)) in cases.into_iter().enumerate() {
                let (mut up, mut down) = (mp, mp);
                bump(&mut up, h);
                bump(&mut down, -h);
                let (eu, ed) = (at(up), at(down));
                let fd = (eu.f - ed.f) / (2.0 * h);
                for row in 0..5 {
                    assert!(
                        (f_x[row] - fd[row]).abs() < 1e-6 * (1.0 + fd[row].abs()),
                        "d={d:?} data {k} row {row}: {} vs {}",
                        f_x[row],
                        fd[row]
                    );
                }
                if let Some(a) = a_x {
                    let fd = (eu.alpha_s - ed.alpha_s) / (2.0 * h);
                    assert!((a - fd).abs() < 1e-7, "d={d:?} data {k}: α_s {a} vs {fd}");
                }
            }
        }
    }

    /// ∂f/∂(C, D, E_b, ΔP) and ∂α_s/∂(C, D) against central differences of the shell's
    /// constants, with and without fibres (D only with them).
    #[test]
    fn constant_partials_match_differences() {
        for d in [None, Some(200.0)] {
            let (shell, mp, y) = test_point(d);
            let e = evaluate(&shell, &mp, &y, 1.0).unwrap();
            let mut which = vec![
                ShellConstant::Modulus,
                ShellConstant::Bending,
                ShellConstant::Pressure,
            ];
            if d.is_some() {
                which.push(ShellConstant::FibreStiffness);
            }
            for w in which {
                let cp = constant_partials(&shell, w, &mp, &y, &e);
                let bumped = |h: f64| {
                    let mut s = shell;
                    match w {
                        ShellConstant::Modulus => s.law.c += h,
                        ShellConstant::FibreStiffness => s.law.d = s.law.d.map(|v| v + h),
                        ShellConstant::Bending => s.e_b += h,
                        ShellConstant::Pressure => s.dp += h,
                    }
                    evaluate(&s, &mp, &y, 1.0).unwrap()
                };
                let h = 1e-5;
                let (eu, ed) = (bumped(h), bumped(-h));
                let fd = (eu.f - ed.f) / (2.0 * h);
                for row in 0..5 {
                    assert!(
                        (cp.f[row] - fd[row]).abs() < 1e-7 * (1.0 + fd[row].abs()),
                        "d={d:?} {w:?} row {row}: {} vs {}",
                        cp.f[row],
                        fd[row]
                    );
                }
                let fa = (eu.alpha_s - ed.alpha_s) / (2.0 * h);
                assert!(
                    (cp.alpha_s - fa).abs() < 1e-9 * (1.0 + fa.abs()),
                    "d={d:?} {w:?}: α_s {} vs {fa}",
                    cp.alpha_s
                );
            }
        }
    }

    /// ∂f/∂y against central differences, with and without fibres.
    #[test]
    fn point_jacobian_matches_differences() {
        for d in [None, Some(200.0)] {
            let (shell, mp, y) = test_point(d);
            let e = evaluate(&shell, &mp, &y, 1.0).unwrap();
            for c in 0..5 {
                let h = 1e-6 * y[c].abs().max(1e-2);
                let mut yp = y;
                let mut ym = y;
                yp[c] += h;
                ym[c] -= h;
                let fd = (evaluate(&shell, &mp, &yp, 1.0).unwrap().f
                    - evaluate(&shell, &mp, &ym, 1.0).unwrap().f)
                    / (2.0 * h);
                for row in 0..5 {
                    let (a, b) = (e.jac[(row, c)], fd[row]);
                    assert!(
                        (a - b).abs() < 1e-6 * (1.0 + a.abs()),
                        "d={d:?} ({row},{c}): {a} vs {b}"
                    );
                }
            }
        }
    }
}
