//! An elastic solution in the form of MATLAB's bvp4c (docs/MODEL.md §3, §4): `x`, `y` with
//! the rows (κ, α_s, r, θ, Q) of the published scripts, and `yp` = f(x, y), so that deval's
//! cubic Hermite on (x, y, yp) is eyeshell's own interpolant ([`super::Solution::at`]).
//!
//! - **Differential rows.** κ′, r′, θ′ are the right side f of docs/MODEL.md §3 at the node,
//!   evaluated with the node's data, and Q′ = (r q_s)′ = r′ q_s + r q_s′ from the same f:
//!   exact for the node's state, not a difference of the discrete solution.
//! - **The algebraic row α_s.** t_s = T(α_s, r/ρ; ζ, ψ) fixes α_s, so its yp is the
//!   derivative of α_s along the same flow: α_s′ = ∂α_s/∂r · r′ + ∂α_s/∂t_s · t_s′ +
//!   ∂α_s/∂Σ, the last the data's own slope at fixed (r, t_s), −(∂T/∂Σ)/(∂T/∂α_s), with
//!   ∂T/∂Σ by fourth-order differences of the explicit tension over the reference data
//!   (no α_s solve, so round-off stays near 1e-13 relative) on the node's side.
//! - **Interfaces.** Where the data are not smooth (the thickness jump at Σ_e when H is
//!   non-uniform; with fibres the kinks of ψ at a, b and Σ_e), `x` holds the node twice,
//!   as bvp4c holds a multipoint problem's interface: the first copy is the limit from
//!   below (fields.csv's row there), the second from above (α_s, α_n, h, t_φ and yp from
//!   the data above). deval then never carries a slope across a jump or a kink.
//!
//! Only the reference (ungrown) shell's data are known between nodes, and that is what an
//! elastic solve is; a grown shell's states are exported by growth's own layout.

use super::discretisation::EvalFailure;
use super::equations::{self, MaterialPoint, Shell, Vec5, KAPPA, QS, R, THETA, TS};
use super::material::reference_point;
use super::solve::shell_of;
use super::{BvpError, FieldRow};
use crate::model::constitutive::Tensions;
use crate::model::params::{Params, Thickness};
use crate::model::profiles::{self, Side};

/// The rows of bvp4c's `y` (and `yp`), in order: the published scripts' unknowns.
pub const Y_ROWS: [&str; 5] = ["kappa", "alpha_s", "r", "theta", "Q"];

/// An elastic solution as bvp4c holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvp4cForm {
    /// Σ at the nodes, each interface twice.
    pub x: Vec<f64>,
    /// Every field at each point of `x` (at an interface, each copy from its own side).
    pub rows: Vec<FieldRow>,
    /// d/dΣ of (κ, α_s, r, θ, Q) at each point of `x`: f(x, y) on the differential rows.
    pub yp: Vec<[f64; 5]>,
}

impl Bvp4cForm {
    /// Row `k` of `y` (in the order of [`Y_ROWS`]) over `x`.
    pub fn y_row(&self, k: usize) -> Vec<f64> {
        self.rows.iter().map(|r| y_of(r)[k]).collect()
    }

    /// Row `k` of `yp` over `x`.
    pub fn yp_row(&self, k: usize) -> Vec<f64> {
        self.yp.iter().map(|d| d[k]).collect()
    }
}

fn y_of(r: &FieldRow) -> [f64; 5] {
    [r.kappa, r.alpha_s, r.r, r.theta, r.q]
}

/// The interfaces of the scene: the breakpoints where some datum is not smooth (with a
/// uniform thickness and no fibres, Σ_e is a node of the mesh but nothing changes there).
pub fn interfaces(p: &Params) -> Vec<f64> {
    if p.has_fibres() || p.thickness == Thickness::NonUniform {
        profiles::breakpoints(p)
    } else {
        Vec::new()
    }
}

/// The solution on the reference shell of `params`, given by every field at its nodes
/// (`rows`, fields.csv's rows: at a breakpoint the limit from below), in bvp4c's form.
pub fn bvp4c_form(params: &Params, rows: &[FieldRow]) -> Result<Bvp4cForm, BvpError> {
    let shell = shell_of(params);
    let cuts = interfaces(params);
    let n = rows.len();
    let mut form = Bvp4cForm {
        x: Vec::with_capacity(n + cuts.len()),
        rows: Vec::with_capacity(n + cuts.len()),
        yp: Vec::with_capacity(n + cuts.len()),
    };
    for (i, row) in rows.iter().enumerate() {
        let interior = i > 0 && i + 1 < n;
        let sides: &[Side] = if interior && cuts.contains(&row.sigma_ref) {
            &[Side::Below, Side::Above]
        } else if i + 1 == n && n > 1 {
            &[Side::Below]
        } else {
            &[Side::Above]
        };
        for &side in sides {
            let (r, yp) = one_sided(params, &shell, &cuts, row, side).map_err(|why| {
                BvpError::Evaluation(EvalFailure {
                    node: i,
                    sigma_ref: row.sigma_ref,
                    why,
                })
            })?;
            form.x.push(row.sigma_ref);
            // fields.csv's row is the node's own (bit for bit what the solve wrote); only
            // an interface's copy from above is new.
            let second = sides.len() == 2 && side == Side::Above;
            form.rows.push(if second { r } else { *row });
            form.yp.push(yp);
        }
    }
    Ok(form)
}

/// The node's fields and yp with the data of `side`.
fn one_sided(
    p: &Params,
    shell: &Shell,
    cuts: &[f64],
    row: &FieldRow,
    side: Side,
) -> Result<(FieldRow, [f64; 5]), equations::PointError> {
    let s = row.sigma_ref;
    let mp = reference_point(p, s, side);
    let qs = row.q / row.r;
    let y = Vec5::new(row.kappa, row.r, row.theta, qs, row.t_s);
    let e = equations::evaluate(shell, &mp, &y, row.alpha_s)?;
    let f = e.f;
    let d_sigma = tension_slope(p, shell, cuts, s, side, e.alpha_s, row.r);
    let alpha_s_slope = e.alpha_s_r * f[R] + e.alpha_s_ts * f[TS] - d_sigma / e.tensions.ts_a;
    let q_slope = f[R] * qs + row.r * f[QS];
    let alpha_n = 1.0 / (e.alpha_s * (row.r / mp.rho));
    let fields = FieldRow {
        alpha_s: e.alpha_s,
        alpha_n,
        h: mp.zeta * alpha_n,
        t_phi: e.tensions.tphi,
        ..*row
    };
    Ok((fields, [f[KAPPA], alpha_s_slope, f[R], f[THETA], q_slope]))
}

/// ∂T/∂Σ at fixed (α_s, r): the slope of the tension t_s(α_s, r/ρ(Σ); ζ(Σ), ψ(Σ)) that the
/// reference data alone give. ρ = R0 sin(Σ/R0) enters exactly (∂α_φ/∂Σ = −α_φ ρ′/ρ, whose
/// differences would lose digits at the pole, where ρ ≈ Σ); ζ and ψ by fourth-order
/// differences at fixed α_φ on `side` of Σ (one-sided at an interface and at the cornea,
/// central elsewhere), with a step that keeps every point inside the smooth piece of the
/// data that holds Σ.
fn tension_slope(
    p: &Params,
    shell: &Shell,
    cuts: &[f64],
    s: f64,
    side: Side,
    alpha_s: f64,
    r: f64,
) -> f64 {
    let mp = reference_point(p, s, side);
    let phi = r / mp.rho;
    let exact = mp_tensions(shell, &mp, alpha_s, phi).ts_phi * (-phi * (s / p.r0).cos() / mp.rho);
    let t = |x: f64| {
        let data: MaterialPoint = reference_point(p, x, side);
        mp_tensions(shell, &data, alpha_s, phi).ts
    };
    let (lo, hi) = (0.0, p.length());
    // The room on each side before the data stop being smooth (or ρ vanishes at the pole).
    let below = cuts
        .iter()
        .filter(|&&c| c < s)
        .fold(s - lo, |m, &c| m.min(s - c));
    let above = cuts
        .iter()
        .filter(|&&c| c > s)
        .fold(hi - s, |m, &c| m.min(c - s));
    // With d < 0 the same weights give the backward difference.
    let one_sided = |d: f64| {
        (-25.0 * t(s) + 48.0 * t(s + d) - 36.0 * t(s + 2.0 * d) + 16.0 * t(s + 3.0 * d)
            - 3.0 * t(s + 4.0 * d))
            / (12.0 * d)
    };
    // 1e-3 mm: the differences' truncation (d⁴ ∂⁵T/∂Σ⁵) and round-off (1e-16 T / d) both
    // stay near 1e-13 of T on the data's scales (mm, tanh widths of 1 to 1.5 mm).
    const STEP: f64 = 1e-3;
    let (up, down) = (STEP.min(above / 4.0), STEP.min(below / 4.0));
    match side {
        // Below is asked for only at an interface and at the cornea's node.
        Side::Below => exact + one_sided(-down),
        Side::Above if cuts.contains(&s) => exact + one_sided(up),
        Side::Above => {
            let d = up.min(down);
            exact + (t(s - 2.0 * d) - 8.0 * t(s - d) + 8.0 * t(s + d) - t(s + 2.0 * d)) / (12.0 * d)
        }
    }
}

/// The tensions at stretches (α_s, α_φ) with the data of `mp`.
fn mp_tensions(shell: &Shell, mp: &MaterialPoint, alpha_s: f64, phi: f64) -> Tensions {
    shell.law.tensions(mp.zeta, mp.fibre, alpha_s, phi)
}
