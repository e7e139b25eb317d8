//! Tolerance-driven elastic solves (`solver.tol`): the mesh is adapted until the estimated
//! global error of every reported field is at most the tolerance (docs/MODEL.md §3–4).
//!
//! **The estimate.** Each pass solves on a mesh M and on M halved ([`Mesh::halved`]), the
//! self-similar refinement under which the error expansion h^p C + … keeps C, so at M's
//! nodes the halved solution's error is (u_{h/2} − u_h) / (2^p − 1) (p = 4 for
//! Hermite–Simpson, 2 for the trapezoid); at the halved mesh's new nodes u_h is M's
//! interpolant. The halved solution is the one reported (fields.csv is on the halved
//! mesh), with the largest of these over its nodes. It estimates the error of the nodal
//! values, those of fields.csv; between nodes (`--at`) the interpolant adds its own,
//! O(h⁴) for Hermite–Simpson, and the truncation at ε (O(ε²), docs/MODEL.md §3) is not
//! part of it. Errors are absolute, per field, in the units
//! of fields.csv: κ (1/mm), α_s, r (mm), θ (rad), Q (kPa·mm²); the overall error is the
//! largest of the five.
//!
//! **Where the error is not yet asymptotic** the factor 1/(2^p − 1) is too small, and two
//! safety margins, both measured, take over. (1) The observed order: a pass also solves on
//! M0, M with every other node dropped ([`coarsened`]), and at each of M0's nodes where
//! the difference matters, log2(|u(M0) − u(M)| / |u(M) − u(M/2)|) below p puts
//! |u(M) − u(M/2)|/(2^{p_obs} − 1) in the estimate ([`pre_asymptotic`]). (2) The
//! estimate's record: each pass measures how far the last pass's estimate fell short of
//! that pass's error, against its own far finer solution, and every later estimate is
//! multiplied by that factor ([`measured_optimism`]); where the fibres go slack the
//! solution has a [·]⁺ kink (MODEL.md §2), less smooth than order 4 assumes, and the
//! estimate is optimistic by about the same factor at every resolution.
//!
//! **Soft shells.** A cold solve on the coarse start mesh that fails (E_b ≲ 1e-4: the
//! cornea's layer inside one interval) is tried again on the start mesh halved, up to
//! [`START_HALVINGS`] times; a warm start that fails on a new mesh is tried again cold,
//! with the continuation of a cold solve. Newton's iterate counts as converged when its
//! correction is within Newton's tolerance although the residual stalled at round-off
//! (`Convergence::ToPrecision`); the start is solved to [`START_NEWTON_TOL`] at most, and
//! a first pass solved so is never delivered. A Newton failure after a pass has been
//! estimated stops the solve as a tolerance out of reach, with the best estimate.
//!
//! **The adaptation.** The local error indicator of interval i is how far the halved
//! solution at the interval's midpoint lies from M's own interpolant there (cubic Hermite
//! for Hermite–Simpson, linear for the trapezoid), less the smooth part of the global
//! error difference: ≈ h_i^p |y^(p)| / c, times h_i it is the local error e_i ∝ h_i^{p+1}.
//! The global error is taken as K Σ e_i (K measured on this pass), and the next mesh
//! equidistributes e_i so that it should reach 0.3 tol ([`AIM`]). The new mesh is walked from each
//! fixed node (ε, the breakpoints, L) to the next with the smallest of: the spacing the
//! indicator asks for and the gradings, which bound the mesh reported, M halved: the pole's
//! (a spacing no larger than (1 − q)/q times the distance from the pole, and ε at the
//! pole), the cornea's (layer/4 near L, then growing at most as the distance from L) and a
//! twentieth of the shell ([`Floors::coarse_spacing`]). The first mesh ([`start_mesh`]) is
//! [`START_NODES`] uniform nodes laid the same way. Each new mesh starts Newton from the
//! last solution through its interpolant.
//!
//! **Richardson** (`solver.richardson`). A pass also solves on M halved twice, and reports
//! the extrapolation of (M/2, M/4) on M/2's nodes, order p + 2; its error is estimated at
//! M's nodes against the extrapolation of (M, M/2), over 2^{p+2} − 1. The local errors of
//! the (M, M/2) pair, raised to the power (p + 3)/(p + 1), lay the next mesh. Without
//! `solver.tol` one pass is made, on the mesh of `solver.nodes`.
//!
//! **Stopping.** A tolerance below the fields' round-off floor ([`round_off_floor`]: 256
//! ulps of the largest field, 6e-13 for r ≈ 11 mm) cannot be told from round-off; the
//! solve refines to that floor and stops. When the estimate no longer falls (at an observed
//! order below 1, two passes in a row), the arithmetic has run out too; when the next mesh
//! would exceed `solver.max_nodes`, it is out of reach. Either way the solve stops with the
//! best error and its nodes. `solver.max_seconds` bounds all the passes together.

use super::solve::{cornea_layer, mesh_of, solve_on_mesh_adaptive, Solution};
use super::{BvpError, ErrorEstimate, FieldRow};
use crate::bvp::settings::{Scheme, SolverSettings};
use crate::deadline::Deadline;
use crate::mesh::{Mesh, POLE_RATIO};
use crate::model::params::Params;
use crate::names::Quantity;
use crate::text::number;
use std::time::Instant;

/// Uniform nodes of the first, coarse mesh (pole and cornea gradings and breakpoints on top).
pub const START_NODES: usize = 11;
/// The most passes (each a solve on M and on M halved) before giving up.
pub const MAX_PASSES: usize = 12;
/// Each pass aims at this fraction of tol, so that a pass whose prediction is optimistic
/// (the first, from a coarse mesh, often is) still meets tol: a pass costs more than the
/// 35 % more nodes this asks for.
pub const AIM: f64 = 0.3;
/// A pass refines an interval at most this many times, and coarsens it at most 4 times.
const MAX_REFINE: f64 = 64.0;
const MAX_COARSEN: f64 = 4.0;

/// Why `solver.tol` was not reached.
#[derive(Clone, Debug, PartialEq)]
pub struct Unreached {
    pub tol: f64,
    pub best_error: f64,
    pub best_nodes: usize,
    pub why: UnreachedWhy,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UnreachedWhy {
    /// tol is below the fields' round-off floor ([`round_off_floor`]), which the estimate
    /// has reached.
    RoundOff { floor: f64 },
    /// The estimate stopped falling: round-off.
    Stalled,
    /// The next mesh would have more nodes than solver.max_nodes.
    NodeCap { max_nodes: usize },
    /// MAX_PASSES passes did not reach tol.
    Passes,
    /// Newton did not converge on the next, finer mesh (its scaled residual where it
    /// stopped), after a pass had solved and estimated.
    Newton { residual: f64 },
}

impl std::fmt::Display for Unreached {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} = {} cannot be reached: the best estimated error was {:.2e} with {} nodes; ",
            Quantity::Tolerance,
            number(self.tol),
            self.best_error,
            self.best_nodes
        )?;
        match self.why {
            UnreachedWhy::RoundOff { floor } => write!(
                f,
                "it is below the round-off floor of these fields ({floor:.1e}, {ROUND_OFF_ULPS} ulps of the largest): ask for a larger tol"
            ),
            UnreachedWhy::Stalled => write!(
                f,
                "the error stopped falling as the mesh was refined (round-off): ask for a larger tol"
            ),
            UnreachedWhy::NodeCap { max_nodes } => write!(
                f,
                "the next mesh would need more than {} = {max_nodes} nodes",
                Quantity::MaxNodes
            ),
            UnreachedWhy::Passes => write!(f, "{MAX_PASSES} refinements did not reach it"),
            UnreachedWhy::Newton { residual } => write!(
                f,
                "Newton did not converge on the next, finer mesh (scaled residual {residual:.1e}): ask for a larger tol"
            ),
        }
    }
}

/// The five reported fields of a row: κ, α_s, r, θ, Q.
fn five(row: &FieldRow) -> [f64; 5] {
    [row.kappa, row.alpha_s, row.r, row.theta, row.q]
}

/// The estimate of one pass: the global error of the fine (halved) solution per field, and
/// the local error e_i of each interval of the coarse mesh.
#[derive(Clone, Debug)]
pub struct PassEstimate {
    pub global: [f64; 5],
    pub local: Vec<f64>,
}

impl PassEstimate {
    pub fn overall(&self) -> f64 {
        self.global.iter().cloned().fold(0.0, f64::max)
    }

    pub fn error_estimate(&self) -> ErrorEstimate {
        let [kappa, alpha_s, r, theta, q] = self.global;
        ErrorEstimate {
            kappa,
            alpha_s,
            r,
            theta,
            q,
            overall: self.overall(),
        }
    }
}

/// The error of `fine` (on `coarse.mesh.halved()`) estimated against `coarse`.
pub fn estimate(coarse: &Solution, fine: &Solution) -> PassEstimate {
    let p = coarse.scheme.order() as i32;
    let factor = 1.0 / (2f64.powi(p) - 1.0);
    let m = coarse.mesh.len();
    let mut global = [0.0f64; 5];
    let mut include = |c: [f64; 5], f: [f64; 5]| {
        for k in 0..5 {
            global[k] = global[k].max(factor * (f[k] - c[k]).abs());
        }
    };
    for i in 0..m {
        include(five(&coarse.rows[i]), five(&fine.rows[2 * i]));
    }
    // The halved mesh's other nodes, against M's interpolant there: that adds M's
    // interpolation error (over 2^p − 1), so the estimate covers every node of fields.csv.
    for i in 0..m - 1 {
        let x = fine.mesh.nodes[2 * i + 1];
        if let Ok(c) = coarse.at(x) {
            include(five(&c), five(&fine.rows[2 * i + 1]));
        }
    }
    // The indicator compares the unknowns κ, r, θ and Q = r q_s (α_s follows from r and
    // t_s, and jumps at breakpoints, where no interpolant of it is meant to hold).
    let unknowns = |v: &[f64; super::interpolant::NQ]| [v[0], v[1], v[2], v[1] * v[3]];
    let cv = &coarse.interpolant.values;
    let fv = &fine.interpolant.values;
    let local = (0..m - 1)
        .map(|i| {
            let x = 0.5 * (coarse.mesh.nodes[i] + coarse.mesh.nodes[i + 1]);
            let interp = match coarse.scheme {
                Scheme::HermiteSimpson => coarse.interpolant.eval(&coarse.mesh, i, x),
                Scheme::Trapezoid => std::array::from_fn(|k| 0.5 * (cv[i][k] + cv[i + 1][k])),
            };
            let (c0, c1, cm) = (unknowns(&cv[i]), unknowns(&cv[i + 1]), unknowns(&interp));
            let (f0, f1, fm) = (
                unknowns(&fv[2 * i]),
                unknowns(&fv[2 * i + 2]),
                unknowns(&fv[2 * i + 1]),
            );
            let eta = (0..4)
                .map(|k| ((fm[k] - cm[k]) - 0.5 * ((f0[k] - c0[k]) + (f1[k] - c1[k]))).abs())
                .fold(0.0, f64::max);
            coarse.mesh.step(i) * eta
        })
        .collect();
    PassEstimate { global, local }
}

/// Newton's tolerance under `solver.tol`: its error must sit well below the
/// discretisation's.
pub fn newton_tol_for(settings: &SolverSettings) -> f64 {
    settings.tol.map_or(settings.newton_tol, |t| {
        settings.newton_tol.min(1e-2 * t).max(1e-13)
    })
}

/// Resolution of a field: differences below ROUND_OFF_ULPS · ε_mach · max|field| are
/// round-off (Newton stops at a scaled residual of 1e-13 at best).
const ROUND_OFF_ULPS: f64 = 256.0;

/// The smallest error the estimate can tell from round-off: the largest over the five
/// fields of ROUND_OFF_ULPS ulps of the field's largest magnitude.
pub fn round_off_floor(sol: &Solution) -> f64 {
    let mut size = [0.0f64; 5];
    for row in &sol.rows {
        for (k, v) in five(row).iter().enumerate() {
            size[k] = size[k].max(v.abs());
        }
    }
    ROUND_OFF_ULPS * f64::EPSILON * size.iter().cloned().fold(0.0, f64::max)
}

/// What the pole and cornea gradings and the shell's size demand of any spacing.
#[derive(Clone, Copy, Debug)]
pub struct Floors {
    pub epsilon: f64,
    pub length: f64,
    pub grade_pole: bool,
    /// The cornea's bending layer when the mesh grades into it.
    pub cornea_layer: Option<f64>,
}

impl Floors {
    /// The gradings `s` asks for on the shell of `params` (the cornea's layer as the start
    /// mesh of [`START_NODES`] would grade into it).
    pub fn of(params: &Params, s: &SolverSettings) -> Floors {
        let start = SolverSettings {
            nodes: START_NODES,
            ..*s
        };
        Floors {
            epsilon: s.epsilon,
            length: params.length(),
            grade_pole: s.pole_grading,
            cornea_layer: cornea_layer(params, &start),
        }
    }

    /// The largest spacing of the mesh M at x such that M halved, the mesh reported, keeps
    /// the gradings: each of its intervals, starting at y, no longer than ε, than
    /// (1 − q)/q (y − ε) (the pole's), than max(layer/4, (L − y)/3) (the cornea's) and
    /// than a twentieth of the shell. For M that is twice the pole's and the shell's, and at
    /// the cornea max(layer/2, (L − x)/2) (M halved's second half-step, nearer L, keeps its
    /// third).
    fn coarse_spacing(&self, x: f64) -> f64 {
        let mut h = (self.length - self.epsilon) / 10.0;
        if self.grade_pole {
            h = h.min(
                2.0 * self
                    .epsilon
                    .max((1.0 - POLE_RATIO) / POLE_RATIO * (x - self.epsilon)),
            );
        }
        if let Some(layer) = self.cornea_layer {
            h = h.min((0.5 * layer).max((self.length - x) / 2.0));
        }
        h
    }
}

/// The first, coarse mesh: [`START_NODES`] uniform nodes and the breakpoints, graded so
/// that its halving has the pole's and the cornea's gradings ([`Floors::coarse_spacing`]),
/// as every later mesh is. (Graded as a reported mesh, its halving would grade the pole twice
/// as finely as a uniform + graded mesh of the same spacing: on the exact sphere at tol
/// 1e-4, 55 nodes where 49 reach the same error.)
pub fn start_mesh(params: &Params, s: &SolverSettings) -> Result<Mesh, BvpError> {
    let uniform = SolverSettings {
        nodes: START_NODES,
        pole_grading: false,
        cornea_grading: false,
        ..*s
    };
    let mesh = mesh_of(params, &uniform)?;
    // Local errors that ask for the uniform spacing h everywhere (not for the short
    // intervals beside the breakpoints, which would spread to their neighbours).
    let h = (params.length() - s.epsilon) / (START_NODES - 1) as f64;
    let local: Vec<f64> = (0..mesh.intervals())
        .map(|i| (mesh.step(i) / h).powi(5))
        .collect();
    let floors = Floors::of(params, s);
    // The gradings add a few dozen nodes at most; past the cap (never seen), grade as usual.
    match equidistribute(&mesh, &local, 4, 1.0, &floors, 10 * START_NODES) {
        Ok(start) => Ok(start),
        Err(_) => Ok(mesh_of(params, s)?),
    }
}

/// The next mesh M: on each coarse interval the spacing that makes its local error
/// `target`, within the gradings' floors for M (so that M halved, the reported mesh, keeps
/// the gradings); breakpoints stay nodes. Err when it would have
/// more than `max_nodes` nodes: the walk stops there, before allocating more, and returns
/// the count it reached.
pub fn equidistribute(
    mesh: &Mesh,
    local: &[f64],
    order: u32,
    target: f64,
    floors: &Floors,
    max_nodes: usize,
) -> Result<Mesh, usize> {
    let power = 1.0 / (order as f64 + 1.0);
    let wanted: Vec<f64> = local
        .iter()
        .enumerate()
        .map(|(i, &e)| {
            let h = mesh.step(i);
            let ratio = if e > 0.0 {
                (target / e).powf(power)
            } else {
                MAX_COARSEN
            };
            h * ratio.clamp(1.0 / MAX_REFINE, MAX_COARSEN)
        })
        .collect();
    let mut fixed: Vec<usize> = vec![0];
    fixed.extend(mesh.breakpoint_nodes.iter().copied());
    fixed.push(mesh.len() - 1);
    fixed.sort_unstable();
    fixed.dedup();
    let mut nodes = vec![mesh.nodes[0]];
    let mut breakpoint_nodes = vec![];
    for w in fixed.windows(2) {
        let b = mesh.nodes[w[1]];
        let mut x = nodes[nodes.len() - 1];
        let mut j = w[0];
        loop {
            while j + 1 < w[1] && mesh.nodes[j + 1] <= x {
                j += 1;
            }
            let mut h = floors.coarse_spacing(x).min(wanted[j]);
            // Every coarse interval the step reaches into bounds it too.
            let mut k = j + 1;
            while k < w[1] && mesh.nodes[k] < x + h {
                h = h.min(wanted[k]);
                k += 1;
            }
            let rest = b - x;
            if rest <= h * (1.0 + 1e-9) {
                nodes.push(b);
                break;
            }
            x = if rest < 2.0 * h {
                x + 0.5 * rest
            } else {
                x + h
            };
            nodes.push(x);
            if nodes.len() > max_nodes {
                return Err(nodes.len());
            }
        }
        if mesh.breakpoint_nodes.contains(&w[1]) {
            breakpoint_nodes.push(nodes.len() - 1);
        }
        if nodes.len() > max_nodes {
            return Err(nodes.len());
        }
    }
    // The breakpoints in the order the coarse mesh lists them.
    let order_of: Vec<usize> = mesh
        .breakpoint_nodes
        .iter()
        .map(|&i| {
            let rank = fixed.iter().position(|&f| f == i).unwrap();
            breakpoint_nodes[rank - 1]
        })
        .collect();
    Ok(Mesh::adapted(nodes, order_of))
}

/// Richardson's extrapolation of `coarse` and `fine` (on `coarse.mesh.halved()`) at the
/// order p of the scheme, on M's nodes: every field, the unknowns, the node values and end
/// slopes of the interpolant, y_f + (y_f − y_c)/(2^p − 1). Its error is O(h^{p+2}).
pub fn extrapolate(coarse: &Solution, fine: &Solution) -> Solution {
    let q = 1.0 / (2f64.powi(coarse.scheme.order() as i32) - 1.0);
    let mix = |c: f64, f: f64| f + (f - c) * q;
    let mixn = |c: &[f64; super::interpolant::NQ], f: &[f64; super::interpolant::NQ]| {
        std::array::from_fn(|k| mix(c[k], f[k]))
    };
    let m = coarse.mesh.len();
    let rows = (0..m)
        .map(|i| {
            let (c, f) = (coarse.rows[i].values(), fine.rows[2 * i].values());
            FieldRow::from_values(std::array::from_fn(|k| mix(c[k], f[k])))
        })
        .collect();
    let u = (0..m)
        .flat_map(|i| {
            let (c, f) = (coarse.y(i), fine.y(2 * i));
            (0..5).map(move |k| mix(c[k], f[k]))
        })
        .collect();
    let (ci, fi) = (&coarse.interpolant, &fine.interpolant);
    let interpolant = super::interpolant::Interpolant {
        values: (0..m)
            .map(|i| mixn(&ci.values[i], &fi.values[2 * i]))
            .collect(),
        slope_left: (0..m - 1)
            .map(|i| mixn(&ci.slope_left[i], &fi.slope_left[2 * i]))
            .collect(),
        slope_right: (0..m - 1)
            .map(|i| mixn(&ci.slope_right[i], &fi.slope_right[2 * i + 1]))
            .collect(),
    };
    let mut stats = fine.stats.clone();
    stats.nodes = m;
    stats.uniform_nodes = coarse.stats.uniform_nodes;
    stats.breakpoint_nodes = coarse.stats.breakpoint_nodes;
    stats.pole_nodes = coarse.stats.pole_nodes;
    stats.cornea_nodes = coarse.stats.cornea_nodes;
    Solution {
        params: fine.params,
        scheme: fine.scheme,
        mesh: coarse.mesh.clone(),
        u,
        rows,
        interpolant,
        stats,
        grown: None,
    }
}

/// M with every other node dropped between its fixed nodes (ε, the breakpoints, L), and
/// the indices in M of the nodes kept: the mesh M halves, nearly (exactly where M was a
/// halving). None when nothing would be dropped.
fn coarsened(mesh: &Mesh) -> Option<(Mesh, Vec<usize>)> {
    let mut fixed: Vec<usize> = vec![0];
    fixed.extend(mesh.breakpoint_nodes.iter().copied());
    fixed.push(mesh.len() - 1);
    fixed.sort_unstable();
    fixed.dedup();
    let mut kept = vec![0usize];
    for w in fixed.windows(2) {
        let mut i = w[0] + 2;
        while i < w[1] {
            kept.push(i);
            i += 2;
        }
        kept.push(w[1]);
    }
    if kept.len() == mesh.len() {
        return None;
    }
    let nodes = kept.iter().map(|&i| mesh.nodes[i]).collect();
    let breakpoint_nodes = mesh
        .breakpoint_nodes
        .iter()
        .map(|b| kept.iter().position(|k| k == b).unwrap())
        .collect();
    Some((Mesh::adapted(nodes, breakpoint_nodes), kept))
}

/// Each field's estimate where the error is not yet asymptotic there: at each node of M0
/// (the mesh M halves, [`coarsened`]) the observed order p_j = log2(|u(M0) − u(M)| /
/// |u(M) − u(M/2)|); where it is below the scheme's p, (u(M/2) − u(M))/(2^p − 1) is too
/// small by (2^p − 1)/(2^p_j − 1), and the node's estimate is |u(M) − u(M/2)|/(2^p_j − 1)
/// (p_j at least 1). Node by node, because what is pre-asymptotic is local: a fibre's
/// [·]⁺ kink, where the fibres go slack, costs the solution its smoothness at one point
/// (MODEL.md §2), and a soft shell's cornea layer is resolved last. Only nodes whose
/// difference is at least a tenth of the field's largest count (an error crossing zero
/// makes the ratio meaningless where it is small), and none at the round-off floor.
/// Returns the largest per field.
fn pre_asymptotic(c0: &Solution, kept: &[usize], coarse: &Solution, fine: &Solution) -> [f64; 5] {
    let p = coarse.scheme.order() as f64;
    let floor = round_off_floor(fine);
    let diffs: Vec<([f64; 5], [f64; 5])> = kept
        .iter()
        .enumerate()
        .map(|(j, &i)| {
            let (a, b, c) = (
                five(&c0.rows[j]),
                five(&coarse.rows[i]),
                five(&fine.rows[2 * i]),
            );
            (
                std::array::from_fn(|k| (a[k] - b[k]).abs()),
                std::array::from_fn(|k| (b[k] - c[k]).abs()),
            )
        })
        .collect();
    std::array::from_fn(|k| {
        let top = diffs.iter().fold(0.0f64, |a, d| a.max(d.1[k]));
        let mut est = 0.0f64;
        for (d0, d1) in &diffs {
            let (d0, d1) = (d0[k], d1[k]);
            if d1 >= 0.1 * top && d1 > 16.0 * floor {
                let observed = (d0 / d1).log2().clamp(1.0, p);
                est = est.max(d1 / (2f64.powf(observed) - 1.0));
            }
        }
        est
    })
}

/// The error Richardson's extrapolation leaves where the solutions on M, M/2 and M/4 do not
/// yet fall at the scheme's order p (a soft shell's coarse mesh; the fibres' kink, where
/// they go slack, which converges an order lower): with u(h) − u = C h^q at the order q
/// observed node by node from the two differences, the extrapolation assuming p leaves
/// C (h/2)^q (2^{p−q} − 1)/(2^p − 1) at M/2, which is d₁ (2^{p−q} − 1)/((1 − 2^{−q})(2^p − 1))
/// in terms of d₁ = |u(M/2) − u(M/4)|. It vanishes as q reaches p, where the estimate from
/// the two extrapolations takes over. Measured before this term: on the default grid of the
/// parameter sweep the extrapolation's estimate fell to 0.13–0.9 of the true error in 9 of
/// 100 cases, all with the error in Q or κ near the fibres' kink or a soft shell's layer.
fn not_extrapolated(coarse: &Solution, fine: &Solution, finer: &Solution) -> [f64; 5] {
    let p = coarse.scheme.order() as f64;
    let floor = round_off_floor(finer);
    let diffs: Vec<([f64; 5], [f64; 5])> = (0..coarse.mesh.len())
        .map(|i| {
            let (a, b, c) = (
                five(&coarse.rows[i]),
                five(&fine.rows[2 * i]),
                five(&finer.rows[4 * i]),
            );
            (
                std::array::from_fn(|k| (a[k] - b[k]).abs()),
                std::array::from_fn(|k| (b[k] - c[k]).abs()),
            )
        })
        .collect();
    // Where d₁ is a small part of the field's largest, its ratio to d₀ is mostly the
    // solutions' round-off and the observed order noise (a soft shell's estimate stalled
    // on it, far above tol): those nodes are left to the extrapolations' estimate.
    let top: [f64; 5] = std::array::from_fn(|k| diffs.iter().fold(0.0f64, |a, d| a.max(d.1[k])));
    let mut est = [0.0f64; 5];
    for (d0, d1) in &diffs {
        for k in 0..5 {
            let (d0, d1) = (d0[k], d1[k]);
            if d1 > 16.0 * floor && d1 >= 0.01 * top[k] {
                let q = (d0 / d1).log2().clamp(1.0, p);
                let share =
                    (2f64.powf(p - q) - 1.0) / ((1.0 - 2f64.powf(-q)) * (2f64.powf(p) - 1.0));
                est[k] = est[k].max(d1 * share);
            }
        }
    }
    est
}

/// One pass's answer: the solution reported, its estimate and the local errors that lay
/// the next mesh (with the order they fall at).
struct PassResult {
    report: Solution,
    global: [f64; 5],
    local: Vec<f64>,
    order: u32,
}

/// A pass on mesh M (solved as `coarse`): solve on M halved (and, with Richardson, on M
/// halved twice), estimate, and say what to report.
fn pass(
    params: &Params,
    s: &SolverSettings,
    coarse: &Solution,
    work: &mut Work,
) -> Result<PassResult, BvpError> {
    let fine = work.solve(params, s, coarse.mesh.halved(), Some(coarse))?;
    let mut est = estimate(coarse, &fine);
    if !s.richardson {
        // With fibres the solution has a kink where they go slack ([·]⁺, MODEL.md §2), a
        // point the mesh does not know: the interval holding it converges an order lower
        // (measured: the estimate fell short by 2–2.6× on the fibre shells of E_b ≤ 0.05),
        // so its share of the error is (u(M/2) − u(M))/(2^{p−1} − 1).
        if params.has_fibres() {
            let p = s.scheme.order() as i32;
            let kink = (2f64.powi(p) - 1.0) / (2f64.powi(p - 1) - 1.0);
            for g in &mut est.global {
                *g *= kink;
            }
        }
        // The estimate where the observed order is below the scheme's: one more solve, on
        // M0 (about half M's nodes, an eighth of the pass's work).
        if let Some((m0, kept)) = coarsened(&coarse.mesh) {
            if let Ok(c0) = work.solve(params, s, m0, Some(coarse)) {
                let local = pre_asymptotic(&c0, &kept, coarse, &fine);
                for k in 0..5 {
                    est.global[k] = est.global[k].max(local[k]);
                }
            }
        }
        return Ok(PassResult {
            report: fine,
            global: est.global,
            local: est.local,
            order: s.scheme.order(),
        });
    }
    // Order p + 2: the extrapolations from (M, M/2) and (M/2, M/4) differ by the error of
    // the first, (2^{p+2} − 1) times that of the second, at M's nodes.
    let finer = work.solve(params, s, fine.mesh.halved(), Some(&fine))?;
    let first = extrapolate(coarse, &fine);
    let second = extrapolate(&fine, &finer);
    let p = s.scheme.order() + 2;
    let factor = 1.0 / (2f64.powi(p as i32) - 1.0);
    let mut global = [0.0f64; 5];
    for i in 0..coarse.mesh.len() {
        let (a, b) = (five(&first.rows[i]), five(&second.rows[2 * i]));
        for k in 0..5 {
            global[k] = global[k].max(factor * (b[k] - a[k]).abs());
        }
    }
    let unextrapolated = not_extrapolated(coarse, &fine, &finer);
    for k in 0..5 {
        global[k] = global[k].max(unextrapolated[k]);
    }
    // The local errors of order p + 1 from the (M, M/2) pair, raised to fall as h^{p+3}.
    let power = (p as f64 + 1.0) / (s.scheme.order() as f64 + 1.0);
    let local = est.local.iter().map(|e| e.powf(power)).collect();
    Ok(PassResult {
        report: second,
        global,
        local,
        order: p,
    })
}

/// The solves of an adaptive solve: the Newton work summed over them, and
/// `solver.max_seconds`, which bounds them all together (their clock starts with the first,
/// or earlier with the job's: `SolverSettings::clock_start`).
struct Work {
    /// When this adaptive solve began (its wall time).
    start: Instant,
    /// The clock started ([`SolverSettings::clock_started`]) and the bound it gives.
    clock_start: Option<Instant>,
    deadline: Deadline,
    iterations: usize,
    residuals: usize,
    jacobians: usize,
}

impl Work {
    fn new(settings: &SolverSettings) -> Work {
        let started = settings.clock_started();
        Work {
            start: Instant::now(),
            clock_start: started.clock_start,
            deadline: Deadline::since(started.clock_start, started.max_seconds),
            iterations: 0,
            residuals: 0,
            jacobians: 0,
        }
    }

    /// One solve on `mesh` (from `warm` when given) within the time left.
    fn solve(
        &mut self,
        params: &Params,
        s: &SolverSettings,
        mesh: Mesh,
        warm: Option<&Solution>,
    ) -> Result<Solution, BvpError> {
        let nodes = mesh.len();
        let deadline = self.deadline;
        let out_of_time = || {
            BvpError::OutOfTime(deadline.reached(format!(
                "in the solve on {nodes} nodes of {}'s adaptation",
                Quantity::Tolerance
            )))
        };
        if deadline.passed() {
            return Err(out_of_time());
        }
        let s = SolverSettings {
            clock_start: self.clock_start,
            ..*s
        };
        let sol = solve_on_mesh_adaptive(params, &s, mesh, warm).map_err(|e| match e {
            BvpError::OutOfTime(_) => out_of_time(),
            e => e,
        })?;
        self.iterations += sol.stats.newton_iterations;
        self.residuals += sol.stats.residual_evaluations;
        self.jacobians += sol.stats.jacobian_evaluations;
        Ok(sol)
    }
}

/// Solve to `solver.tol`, or with `solver.richardson` alone, extrapolate once on the mesh
/// of `solver.nodes`. Each pass solves on M and on M halved (and halved twice with
/// Richardson) until the reported solution's estimated error is at most tol. The solution
/// returned is on the last halved mesh (with Richardson: the extrapolation, on M halved),
/// with its estimate and the nodes of each pass in its stats.
pub fn solve_to_tolerance(
    params: &Params,
    settings: &SolverSettings,
) -> Result<Solution, BvpError> {
    let tol = settings.tol;
    let s = SolverSettings {
        nodes: if tol.is_some() {
            START_NODES
        } else {
            settings.nodes
        },
        newton_tol: newton_tol_for(settings),
        ..*settings
    };
    let floors = Floors::of(params, &s);
    let mut work = Work::new(settings);
    let start = if tol.is_some() {
        start_mesh(params, &s)?
    } else {
        mesh_of(params, &s)?
    };
    // The start only seeds the first pass: its Newton error enters that pass's estimate
    // (over 2^p − 1, which a coarse mesh's error dwarfs), never a reported solution. On a
    // soft shell's coarse mesh 1e-12 can lie below the residual's round-off.
    let loose = SolverSettings {
        newton_tol: s.newton_tol.max(START_NEWTON_TOL),
        ..s
    };
    let mut coarse = solve_start(params, &loose, start, &mut work)?;
    // The first pass too: it is accepted only if it solved at the strict tolerance.
    let mut pass_settings = loose;
    // The last pass's report and its estimate, to measure how far the estimate was from
    // the truth there against this pass's far finer solution.
    let mut previous: Option<(Solution, f64)> = None;
    let mut optimism = 1.0f64;
    let mut pass_nodes = vec![];
    let mut best: Option<(f64, usize)> = None;
    // The last pass's (error, nodes), and how many passes in a row the error stalled.
    let mut last: Option<(f64, usize)> = None;
    let mut stalls = 0;
    // A Newton solve that fails after a pass has solved and estimated (a finer mesh of a
    // soft shell, whose discrete equations need more digits than double precision has) ends
    // the adaptation with the best estimate so far, as a tolerance out of reach.
    let beyond = |e: BvpError, best: Option<(f64, usize)>| match (e, tol, best) {
        (BvpError::NewtonFailed { residual_norm, .. }, Some(tol), Some((error, nodes))) => {
            BvpError::Unreached(Unreached {
                tol,
                best_error: error,
                best_nodes: nodes,
                why: UnreachedWhy::Newton {
                    residual: residual_norm,
                },
            })
        }
        (e, ..) => e,
    };
    loop {
        let PassResult {
            report,
            global,
            local,
            order,
        } = pass(params, &pass_settings, &coarse, &mut work).map_err(|e| beyond(e, best))?;
        let strict = pass_settings.newton_tol <= s.newton_tol;
        pass_settings = s;
        let mut est = PassEstimate { global, local };
        if let Some((last_report, last_error)) = &previous {
            optimism = optimism.max(measured_optimism(
                last_report,
                *last_error,
                &report,
                est.overall(),
            ));
        }
        previous = Some((report.clone(), est.overall()));
        for g in &mut est.global {
            *g *= optimism;
        }
        let error = est.overall();
        pass_nodes.push(report.mesh.len());
        // Below a few hundred ulps of a field's size, the estimate is round-off, not error.
        let floor = round_off_floor(&report);
        if best.is_none_or(|(e, _)| error < e) {
            best = Some((error, report.mesh.len()));
        }
        let best_now = best.unwrap();
        let Some(tol) = tol else {
            return Ok(finish(report, &est, pass_nodes, &work));
        };
        let unreached = |why| {
            BvpError::Unreached(Unreached {
                tol,
                best_error: best_now.0,
                best_nodes: best_now.1,
                why,
            })
        };
        if error <= floor.max(tol) && tol < floor {
            return Err(unreached(UnreachedWhy::RoundOff { floor }));
        }
        if error <= tol && strict {
            return Ok(finish(report, &est, pass_nodes, &work));
        }
        // Twice in a row: once may be a coarse mesh's estimate, not yet asymptotic. An
        // error that stops falling far above round-off is a mesh that does not yet resolve
        // the shell (a soft shell's cornea layer spanning a few intervals), not round-off:
        // the next pass refines again, bounded by MAX_PASSES and max_nodes.
        let near_round_off = error <= STALL_ROUND_OFF * floor;
        if near_round_off && last.is_some_and(|(e, n)| stalled(e, n, error, report.mesh.len())) {
            stalls += 1;
            if stalls == 2 {
                return Err(unreached(UnreachedWhy::Stalled));
            }
        } else {
            stalls = 0;
        }
        last = Some((error, report.mesh.len()));
        if pass_nodes.len() >= MAX_PASSES {
            return Err(unreached(UnreachedWhy::Passes));
        }
        let target = next_target(&est, order, AIM * tol.max(floor));
        // The reported mesh of the next pass has at most max_nodes nodes: M halved has
        // 2M − 1, and with Richardson too the report is on M halved.
        let cap = settings.max_nodes.div_ceil(2);
        let Ok(mesh) = equidistribute(&coarse.mesh, &est.local, order, target, &floors, cap) else {
            let max_nodes = settings.max_nodes;
            return Err(unreached(UnreachedWhy::NodeCap { max_nodes }));
        };
        coarse = work
            .solve(params, &s, mesh, Some(&report))
            .map_err(|e| beyond(e, best))?;
    }
}

/// How much the last pass's estimate `last_error` of `last` fell short of its error, as
/// this pass's report `now` (estimated at `now_error`) measures it at `last`'s nodes:
/// 1 when it did not, at most [`MAX_OPTIMISM`]. The estimate is asymptotic, and where the
/// solution is less smooth than the scheme's order assumes (a fibre's [·]⁺ kink, where the
/// fibres go slack, MODEL.md §2) it is optimistic at every resolution by about the same
/// factor, which the next pass sees at no cost. Only when `now` is at least 4 times finer
/// (its own error does not blur the measurement).
fn measured_optimism(last: &Solution, last_error: f64, now: &Solution, now_error: f64) -> f64 {
    if !(last_error > 4.0 * now_error) {
        return 1.0;
    }
    let mut truth = 0.0f64;
    for row in &last.rows {
        if let Ok(r) = now.at(row.sigma_ref) {
            for (a, b) in five(row).iter().zip(five(&r)) {
                truth = truth.max((a - b).abs());
            }
        }
    }
    (truth / last_error).clamp(1.0, MAX_OPTIMISM)
}

/// The most [`measured_optimism`] corrects.
const MAX_OPTIMISM: f64 = 16.0;

/// How far above the round-off floor a stalled error may still be round-off: the
/// discrete equations of a soft shell amplify the residual's round-off by their
/// conditioning (about 1/E_b near the cornea), so 1e6 floors (about 6e-7 mm for r ≈ 11
/// mm); a stall above that is a mesh not yet asymptotic.
const STALL_ROUND_OFF: f64 = 1e6;

/// Newton's tolerance on the start mesh, at most.
const START_NEWTON_TOL: f64 = 1e-10;

/// How many times the start mesh is halved when a cold solve on it fails.
const START_HALVINGS: usize = 4;

/// The first solve, cold, on `start`. A soft shell (E_b ≲ 1e-4) on the coarse start mesh
/// is a different discrete problem from the shell's (its cornea layer spans one interval)
/// and may have no root near the sphere: then the start mesh is halved, up to
/// [`START_HALVINGS`] times, until Newton (with its continuation) converges. The error of
/// the first failure is the one reported if none does.
fn solve_start(
    params: &Params,
    s: &SolverSettings,
    start: Mesh,
    work: &mut Work,
) -> Result<Solution, BvpError> {
    let mut mesh = start;
    let mut first = None;
    for _ in 0..=START_HALVINGS {
        match work.solve(params, s, mesh.clone(), None) {
            Ok(sol) => return Ok(sol),
            Err(e) if e.is_out_of_time() => return Err(e),
            Err(e) => {
                first.get_or_insert(e);
            }
        }
        if 2 * mesh.len() > s.max_nodes {
            break;
        }
        mesh = mesh.halved();
    }
    Err(first.expect("at least one solve"))
}

/// Has the error stopped falling? From `e0` on `n0` nodes to `e1` on `n1`: the observed
/// order log(e0/e1) / log(n1/n0) is below 1 (the scheme's is 4 or 6) on a mesh at least
/// 20 % larger. (A pass that added fewer nodes, or that fell short of its aim, is no
/// evidence: the next pass aims again.)
fn stalled(e0: f64, n0: usize, e1: f64, n1: usize) -> bool {
    let growth = n1 as f64 / n0 as f64;
    growth >= 1.2 && e1 > 0.0 && (e0 / e1).ln() < growth.ln()
}

/// The local error τ every interval of the next mesh should have so that the global error
/// is `aim`: the global error is taken as K Σ e_i (K measured on this pass); equidistributed,
/// Σ e_i = n τ with n = Σ (e_i/τ)^{1/(p+1)}.
pub fn next_target(est: &PassEstimate, order: u32, aim: f64) -> f64 {
    let sum: f64 = est.local.iter().sum();
    if !(sum > 0.0) {
        return 0.0;
    }
    let k = est.overall() / sum;
    let q = 1.0 / (order as f64 + 1.0);
    let s_q: f64 = est.local.iter().map(|e| e.powf(q)).sum();
    (aim / (k * s_q)).powf(1.0 / (1.0 - q))
}

/// The reported solution with its estimate, the passes and the work of them all.
fn finish(
    mut report: Solution,
    est: &PassEstimate,
    pass_nodes: Vec<usize>,
    work: &Work,
) -> Solution {
    let stats = &mut report.stats;
    stats.error_estimate = Some(est.error_estimate());
    stats.mesh_refinements = Some(pass_nodes.len() - 1);
    stats.pass_nodes = Some(pass_nodes);
    stats.newton_iterations = work.iterations;
    stats.residual_evaluations = work.residuals;
    stats.jacobian_evaluations = work.jacobians;
    stats.continuation_stages = 0;
    stats.wall_seconds = work.start.elapsed().as_secs_f64();
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::profiles;

    fn fibre_params() -> Params {
        Params {
            d: 200.0,
            ..Params::default()
        }
    }

    /// A mesh laid by equidistribution keeps every breakpoint as a node (the same ones, in
    /// order), and every spacing within the pole's and the cornea's gradings.
    #[test]
    fn equidistributed_meshes_keep_breakpoints_and_gradings() {
        let p = fibre_params();
        let s = SolverSettings {
            nodes: START_NODES,
            ..SolverSettings::default()
        };
        let mesh = mesh_of(&p, &s).unwrap();
        let layer = 0.05;
        let floors = Floors {
            epsilon: s.epsilon,
            length: p.length(),
            grade_pole: true,
            cornea_layer: Some(layer),
        };
        // Local errors that vary by 12 orders of magnitude along the shell.
        let local: Vec<f64> = (0..mesh.intervals())
            .map(|i| 10f64.powi(-(((i * 7) % 13) as i32)))
            .collect();
        let next = equidistribute(&mesh, &local, 4, 1e-9, &floors, 100_000).unwrap();
        let bps = profiles::breakpoints(&p);
        assert_eq!(next.breakpoint_nodes.len(), bps.len());
        for (k, &b) in bps.iter().enumerate() {
            assert_eq!(next.nodes[next.breakpoint_nodes[k]], b);
        }
        assert!(next.nodes.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(next.nodes[0], s.epsilon);
        assert_eq!(*next.nodes.last().unwrap(), p.length());
        // The reported mesh, M halved, keeps the gradings.
        let reported = next.halved();
        let q = (1.0 - POLE_RATIO) / POLE_RATIO;
        let l = p.length();
        for i in 0..reported.intervals() {
            let (x, h) = (reported.nodes[i], reported.step(i));
            let pole = s.epsilon.max(q * (x - s.epsilon));
            let cornea = (0.25 * layer).max((l - x) / 3.0);
            // A step cut short before a fixed node is split in two equal halves, each at
            // most the spacing allowed at its start.
            assert!(
                h <= 1.0000001 * pole.min(cornea),
                "interval {i} at {x}: {h}"
            );
        }
        // The first interval is no longer than ε, as the pole grading's.
        assert!(reported.step(0) <= s.epsilon * (1.0 + 1e-12));
        // So does the start mesh's halving.
        let start = start_mesh(&p, &s).unwrap().halved();
        assert!(start.step(0) <= s.epsilon * (1.0 + 1e-12));
        for i in 0..start.intervals() {
            let (x, h) = (start.nodes[i], start.step(i));
            let pole = s.epsilon.max(q * (x - s.epsilon));
            assert!(h <= 1.0000001 * pole, "start interval {i} at {x}: {h}");
        }
        // Too many nodes: refused before they are laid.
        assert!(equidistribute(&mesh, &local, 4, 1e-30, &floors, 1000).is_err_and(|n| n > 1000));
    }
}
