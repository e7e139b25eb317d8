//! Growth as one coupled DAE (docs/MODEL.md §3, §5–6): the growth state and the
//! elastic state advance together, so a time step costs one Newton iteration of the whole
//! system instead of a nested elastic solve per right-hand side.
//!
//! Unknowns y = [P | W | d]:
//! - P: (ρ, γ_s) at every growth point (`GrowthPoints`), 2 per point;
//! - W: per node i, (κ, r, θ, q_s, t_s, z): the elastic unknowns and z, so that the retina
//!   at a point reads only its neighbours' unknowns (z was a quadrature over the shell);
//! - d: the blue depth where the retina crosses φ_max, read by every point beyond it
//!   (docs/MODEL.md §6), as one unknown with its own equation instead of a dense coupling.
//!
//! Residual rows, in the same order:
//! - P: ρ' − η [r − ρ]⁺ and γ_s' − η γ_s [α_s − 1]⁺ (differential);
//! - W: the three pole conditions, per interval the five scheme rows and
//!   z_{i+1} − z_i − Δz_i (the scheme's own quadrature of dz/dΣ = −γ α_s sin θ), then the
//!   cornea's r, θ and z (algebraic);
//! - d: d − [the interpolated depth at φ_max] (algebraic; d = 0 when no point reaches it).
//!
//! This is the semi-discretisation CVODE integrates (`system.rs`), with the elastic
//! equations held as constraints: at a consistent state the two agree exactly.
//!
//! The Jacobian ∂F/∂y + c ∂F/∂y' is assembled analytically into a [`Csr`] whose every row
//! touches one interval's unknowns (and d): the elastic Jacobian the solver already has,
//! the elastic rows' derivatives in the material data (`equations::data_partials`), and
//! the rates' derivatives through the retina and the stimulus
//! (`Surface::depth_gradient`). The [·]⁺ kinks take the derivative of the branch the value
//! took.
//!
//! The rooms: this file, the unknowns' layout (pattern, solvers, the state at the start)
//! and what IDA asks for; `residual.rs`, the rates and F; `jacobian.rs`, the Newton matrix;
//! `sensitivities.rs`, [`SensParam`] and ∂F/∂p.

mod jacobian;
mod residual;
mod sensitivities;

pub use sensitivities::{SensParam, SensitivityError};

use super::crossing::Crossing;
mod border;
use border::{Border, Term};

use super::points::NP;
use super::settings::DaeLinear;
use super::system::{GrowthSystem, RhsError};
use super::ThicknessLaw;
use crate::bvp::discretisation::{Discretisation, EvalFailure, Evaluations, NY, POLE_ROWS};
use crate::bvp::equations::{
    constant_partials, data_partials, ConstantPartials, Mat5, MaterialPoint, Part, PointError,
    PointEval, ShellConstant, Vec5, KAPPA, R, THETA, TS,
};
use crate::bvp::settings::Scheme;
use crate::model::growth_law::positive_smooth;
use crate::model::params::Params;
use eyeshell_linalg::{
    Csr, DirectSolver, Fallback, InterleavedBand, LinalgError, Reduced, SchurSolver,
};
use eyeshell_sundials::{KluSolver, MatrixSink};

/// W unknowns per node: the five elastic unknowns and z.
pub const NW: usize = 6;
/// Index of z among a node's W unknowns.
pub const Z: usize = 5;

/// Where a growth point reads its local state (r, θ, z, α_s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Site {
    /// Node i as the left end of interval i (its evaluation `left(i)`).
    Left(usize),
    /// Node i + 1 as the right end of interval i (`right(i)`).
    Right(usize),
    /// The Hermite–Simpson midpoint of interval i.
    Mid(usize),
}

impl Site {
    fn interval(self) -> usize {
        match self {
            Site::Left(i) | Site::Right(i) | Site::Mid(i) => i,
        }
    }
}

/// A scalar's derivatives with respect to one interval's unknowns: W columns 6i..6i+12
/// (y_i, z_i, y_{i+1}, z_{i+1}) and the data (ρ, γ_s) of its points L = above[i],
/// R = below[i+1], M = mid[i].
#[derive(Clone, Copy, Debug, Default)]
struct Grad {
    w: [f64; 2 * NW],
    p: [[f64; 2]; 3],
}

const L: usize = 0;
const RT: usize = 1;
const M: usize = 2;

impl Grad {
    fn axpy(&mut self, a: f64, x: &Grad) {
        for (s, v) in self.w.iter_mut().zip(&x.w) {
            *s += a * v;
        }
        for (s, v) in self.p.iter_mut().zip(&x.p) {
            s[0] += a * v[0];
            s[1] += a * v[1];
        }
    }
}

/// −Σ_q coef_q x_q, summed in q order from 0 (as `Grad::axpy` sums the four local
/// derivatives, so that the entries are the same to the bit).
#[inline]
fn neg_combination(coef: &[f64; 6], x: [f64; 4]) -> f64 {
    let mut v = 0.0;
    for q in 0..4 {
        v += -coef[q] * x[q];
    }
    v
}

/// The four local derivatives of a point as arrays of one entry each.
trait EachLocal {
    fn each(&self, entry: impl Fn(&Grad) -> f64) -> [f64; 4];
}

impl EachLocal for [Grad; 4] {
    #[inline]
    fn each(&self, entry: impl Fn(&Grad) -> f64) -> [f64; 4] {
        [
            entry(&self[0]),
            entry(&self[1]),
            entry(&self[2]),
            entry(&self[3]),
        ]
    }
}

/// A node point's local derivatives, which are a few numbers: r, θ, z are the node's own
/// unknowns (unit derivatives in its half `off` of the window), and α_s moves with r, t_s
/// and the point's own data (slot `slot`).
struct NodeGrads {
    slot: usize,
    off: usize,
    alpha_s_r: f64,
    alpha_s_ts: f64,
    alpha_s_data: [f64; 2],
}

impl NodeGrads {
    /// The four derivatives (r, θ, z, α_s) in window column c, zeros and ones included.
    #[inline]
    fn w(&self, c: usize) -> [f64; 4] {
        let unit = |at: usize| if c == self.off + at { 1.0 } else { 0.0 };
        let alpha = if c == self.off + R {
            self.alpha_s_r
        } else if c == self.off + TS {
            self.alpha_s_ts
        } else {
            0.0
        };
        [unit(R), unit(THETA), unit(Z), alpha]
    }
}

/// gᵀ ∂y_m/∂(window) for a row vector g over interval i's Hermite–Simpson midpoint,
/// y_m = (y_i + y_{i+1})/2 + h/8 (f_L − f_R): the two 5×5 factors are made once per
/// interval for its four uses (the midpoint's r, θ, α_s and the midpoint slope).
struct MidMap<'a> {
    h: f64,
    /// (I/2 + h/8 J_L)ᵀ and (I/2 − h/8 J_R)ᵀ.
    dlt: Mat5,
    drt: Mat5,
    /// The end points' data derivatives (f_L, f_R move with their data).
    fl: &'a DataDeriv,
    fr: &'a DataDeriv,
}

impl MidMap<'_> {
    /// gᵀ ∂y_m/∂(window) into `out`, every entry written (M's data: zero), in place: a
    /// `Grad` returned by value was a 144-byte copy per use.
    fn apply(&self, g: &Vec5, out: &mut Grad) {
        let h = self.h;
        let gl = self.dlt * g;
        let gr = self.drt * g;
        *out = Grad::default();
        for c in 0..NY {
            out.w[c] = gl[c];
            out.w[NW + c] = gr[c];
        }
        for q in 0..2 {
            out.p[L][q] = (h / 8.0) * g.dot(&self.fl.f[q]);
            out.p[RT][q] = -(h / 8.0) * g.dot(&self.fr.f[q]);
        }
    }
}

/// What the rates saw at one point, with the derivatives the Jacobian needs.
#[derive(Clone, Copy, Debug, Default)]
struct Local {
    r: f64,
    z: f64,
    alpha_s: f64,
    sin_theta: f64,
    cos_theta: f64,
}

/// The derivatives of a point's data in the window: ∂f/∂(ρ, γ_s) (5×2, through ζ too) and
/// ∂α_s/∂(ρ, γ_s).
#[derive(Clone, Copy, Debug)]
struct DataDeriv {
    f: [Vec5; 2],
    alpha_s: [f64; 2],
}

/// ∂ζ/∂(ρ, γ_s) under the thickness law (mass: ζ ∝ 1/(γ_s ρ)).
fn zeta_partials(law: ThicknessLaw, rho: f64, zeta: f64, gamma: f64) -> [f64; 2] {
    match law {
        ThicknessLaw::None => [0.0, 0.0],
        ThicknessLaw::Mass => [-zeta / rho, -zeta / gamma],
    }
}

fn data_deriv(law: ThicknessLaw, mp: &MaterialPoint, y: &Vec5, e: &PointEval) -> DataDeriv {
    let d = data_partials(mp, y, e);
    let [zr, zg] = zeta_partials(law, mp.rho, mp.zeta, mp.gamma);
    DataDeriv {
        f: [d.f_rho + zr * d.f_zeta, d.f_gamma + zg * d.f_zeta],
        alpha_s: [d.alpha_s_rho + zr * d.alpha_s_zeta, zg * d.alpha_s_zeta],
    }
}

/// The rates at one point and, on request, their derivatives in the point's local state.
#[derive(Clone, Copy, Debug, Default)]
struct PointRates {
    rho: f64,
    gamma: f64,
    /// The rule's drive at the point's own view (mm).
    drive: f64,
    angle: f64,
    g_v: f64,
    eta: f64,
    beyond: bool,
    /// ∂(rate_ρ, rate_γ)/∂g_c: the rates are linear in the growth capacity.
    per_capacity: [f64; 2],
}

/// Derivatives of (rate_ρ, rate_γ, drive, angle) in (r, θ, z, α_s, ρ, γ_s) and d.
#[derive(Clone, Copy, Debug, Default)]
struct RateDeriv {
    rate: [[f64; 6]; 2],
    rate_d: [f64; 2],
    /// ∂(z_ret, r_ret).
    retina: [[f64; 6]; 2],
    drive: [f64; 6],
    angle: [f64; 6],
}

/// Whether every value is finite: a value's exponent bits all set is ±∞ or NaN. One OR per
/// value and no branch, so that the check of ~26 000 rate derivatives per assembly runs at
/// the memory's pace.
fn all_finite(v: &[f64]) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    v.iter().fold(0u64, |acc, x| {
        acc | u64::from(x.to_bits() & EXPONENT == EXPONENT)
    }) == 0
}

/// The per-point buffers of an evaluation (local states, rates, their derivatives), kept
/// between calls so that a residual or an assembly allocates nothing (N = 501: ~0.5 MB a
/// call). The outputs are bit-identical; the smallest on-CPU time of a run did not move.
#[derive(Default)]
struct PointScratch {
    local: Vec<Local>,
    rates: Vec<PointRates>,
    rd: Vec<RateDeriv>,
    /// What each point sees, the rule's drive there, and ∂(z_ret, r_ret)/∂(local state).
    seen: Vec<crate::model::rule::Seen>,
    /// Each point's Σ and retina (z, r).
    places: Vec<(f64, (f64, f64))>,
    drives: Vec<crate::model::rule::Drive>,
    retina_d: Vec<[[f64; 6]; 2]>,
}

/// The layout of y and the fixed data of the coupled system.
pub struct CoupledDae {
    pub sys: GrowthSystem,
    m: usize,
    n_p: usize,
    n_w: usize,
    sites: Vec<Site>,
    hermite_simpson: bool,
    jac: Csr,
    linear: Box<dyn DirectSolver>,
    /// Scratch: the elastic unknowns, and the elastic residual.
    u: Vec<f64>,
    f: Vec<f64>,
    dz: Vec<f64>,
    /// Scratch of the Jacobian: each interval's midpoint's local state's derivatives
    /// (Hermite–Simpson; a node point's are a few numbers, [`CoupledDae::node_grads`]), and
    /// each point's derivatives of its elastic right side in its data (computed once per
    /// assembly).
    grads: Vec<[Grad; 4]>,
    derivs: Vec<DataDeriv>,
    scratch: PointScratch,
    /// The (p, u) the discretisation's data and evaluations were last set for.
    at_p: Vec<f64>,
    pub counters: DaeCounters,
    /// Forward sensitivities: the parameters, and F_y and each ∂F/∂p_j at the y they were
    /// last computed for (IDAS's staggered corrector asks for them repeatedly at one y).
    sens_params: Vec<SensParam>,
    sens_jac: Csr,
    sens_fp: Vec<Vec<f64>>,
    sens_at: Vec<f64>,
}

/// Work done by the coupled system's callbacks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DaeCounters {
    pub residuals: usize,
    pub jacobians: usize,
    pub solves: usize,
    pub jacobian_seconds: f64,
    pub factor_seconds: f64,
    pub solve_seconds: f64,
    pub residual_seconds: f64,
    /// Factorisations a Schur path handed to its pivoting fallback.
    pub fallbacks: usize,
    /// Forward sensitivities: [`CoupledDae::sensitivity_residual`]'s calls, its
    /// assemblies of F_y (one per new y), and its seconds in them, in ∂F/∂p and in the
    /// products F_y s.
    pub sensitivity_residuals: usize,
    pub sensitivity_jacobians: usize,
    pub sensitivity_jacobian_seconds: f64,
    pub sensitivity_parameter_seconds: f64,
    pub sensitivity_product_seconds: f64,
}

/// Why the coupled system could not be evaluated or solved.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DaeError {
    #[error(transparent)]
    Rhs(#[from] RhsError),
    #[error("the Newton matrix of the coupled system: {0}")]
    Linear(#[from] LinalgError),
}

impl CoupledDae {
    /// The coupled system of a growth system whose elastic state has been solved at t = 0,
    /// before its linear solver is chosen ([`CoupledDae::set_linear`]).
    pub fn new(sys: GrowthSystem) -> Self {
        let disc = sys.elastic.discretisation();
        let m = disc.mesh.len();
        let hermite_simpson = disc.scheme == Scheme::HermiteSimpson;
        let pts = &sys.points;
        let n_p = NP * pts.len();
        let n_w = NW * m;
        let mut sites = vec![Site::Left(0); pts.len()];
        for i in 0..m {
            if i > 0 {
                sites[pts.below[i]] = Site::Right(i - 1);
            }
            if i < m - 1 {
                sites[pts.above[i]] = Site::Left(i);
            }
        }
        for (i, &k) in pts.mid.iter().enumerate() {
            sites[k] = Site::Mid(i);
        }
        let mut dae = CoupledDae {
            m,
            n_p,
            n_w,
            sites,
            hermite_simpson,
            jac: Csr::from_rows(vec![]),
            linear: Box::new(NoSolver),
            u: vec![0.0; NY * m],
            f: vec![0.0; NY * m],
            dz: vec![0.0; m - 1],
            grads: vec![],
            derivs: vec![],
            scratch: PointScratch::default(),
            at_p: vec![],
            counters: DaeCounters::default(),
            sens_params: vec![],
            sens_jac: Csr::from_rows(vec![]),
            sens_fp: vec![],
            sens_at: vec![],
            sys,
        };
        dae.jac = Csr::from_rows(dae.pattern());
        dae.sens_jac = dae.jac.clone();
        dae
    }

    /// Choose the linear solver of the Newton matrix.
    pub fn set_linear(&mut self, kind: DaeLinear) -> Result<(), DaeError> {
        self.linear = self.make_solver(kind)?;
        Ok(())
    }

    /// The number of unknowns.
    pub fn len(&self) -> usize {
        self.n_p + self.n_w + 1
    }

    pub fn is_empty(&self) -> bool {
        false
    }

    /// Index of the border unknown d.
    fn d(&self) -> usize {
        self.n_p + self.n_w
    }

    /// Global column of W unknown c at node i.
    fn wcol(&self, i: usize, c: usize) -> usize {
        self.n_p + NW * i + c
    }

    /// The interval window's points (L, R, M); M absent for the trapezoidal scheme.
    fn window_points(&self, i: usize) -> [Option<usize>; 3] {
        let pts = &self.sys.points;
        [
            Some(pts.above[i]),
            Some(pts.below[i + 1]),
            self.hermite_simpson.then(|| pts.mid[i]),
        ]
    }

    /// The growth-row index of interval i's W row `a` (0..5 scheme rows, 5 the z row).
    fn interval_row(&self, i: usize, a: usize) -> usize {
        self.n_p + POLE_ROWS + NW * i + a
    }

    fn pattern(&self) -> Vec<Vec<usize>> {
        let n = self.len();
        let d = self.d();
        let mut rows: Vec<Vec<usize>> = vec![vec![]; n];
        let window = |i: usize| -> Vec<usize> {
            let mut cols: Vec<usize> = (0..2 * NW).map(|c| self.n_p + NW * i + c).collect();
            for k in self.window_points(i).into_iter().flatten() {
                cols.extend([NP * k, NP * k + 1]);
            }
            cols
        };
        for (k, &site) in self.sites.iter().enumerate() {
            let mut cols = vec![NP * k, NP * k + 1, d];
            match site {
                Site::Left(i) => cols.extend((0..NW).map(|c| self.wcol(i, c))),
                Site::Right(i) => cols.extend((0..NW).map(|c| self.wcol(i + 1, c))),
                Site::Mid(i) => cols.extend(window(i)),
            }
            rows[NP * k] = cols.clone();
            rows[NP * k + 1] = cols;
        }
        let pole: Vec<usize> = (0..NW)
            .map(|c| self.wcol(0, c))
            .chain([
                NP * self.sys.points.above[0],
                NP * self.sys.points.above[0] + 1,
            ])
            .collect();
        for row in &mut rows[self.n_p..self.n_p + POLE_ROWS] {
            *row = pole.clone();
        }
        for i in 0..self.m - 1 {
            let cols = window(i);
            for a in 0..NW {
                rows[self.interval_row(i, a)] = cols.clone();
            }
        }
        let last: Vec<usize> = (0..NW).map(|c| self.wcol(self.m - 1, c)).collect();
        for row in &mut rows[d - 3..d] {
            *row = last.clone();
        }
        rows[d] = (0..n).collect();
        rows
    }

    fn make_solver(&self, kind: DaeLinear) -> Result<Box<dyn DirectSolver>, LinalgError> {
        let schur = |how| -> Result<Box<dyn DirectSolver>, LinalgError> {
            let fast = SchurSolver::new(&self.jac, self.n_p, true, how)?;
            Ok(Box::new(Fallback::new(
                Box::new(fast),
                self.pivoting_solver(),
            )))
        };
        Ok(match kind {
            DaeLinear::SchurBlock => schur(Reduced::Block)?,
            DaeLinear::Schur => schur(Reduced::Band)?,
            DaeLinear::SchurKlu => schur(KluSolver::REDUCED)?,
            DaeLinear::Band => Box::new(InterleavedBand::new(
                &self.jac,
                self.interleaving(),
                Some(self.d()),
            )?),
            DaeLinear::Klu => Box::new(KluSolver::new(&self.jac)?),
        })
    }

    /// The Schur paths' fallback for a matrix whose growth block cannot be eliminated
    /// without pivoting (huge steps where a point's rates barely depend on its own state):
    /// KLU on the whole matrix where KLU was built in, else the pivoted interleaved band.
    fn pivoting_solver(&self) -> eyeshell_linalg::MakeSolver {
        let pattern = self.jac.clone();
        let (perm, border) = (self.interleaving(), self.d());
        Box::new(move || -> Result<Box<dyn DirectSolver>, LinalgError> {
            Ok(if eyeshell_sundials::klu_available() {
                Box::new(KluSolver::new(&pattern)?)
            } else {
                Box::new(InterleavedBand::new(&pattern, perm.clone(), Some(border))?)
            })
        })
    }

    /// Node by node: the node's growth points, its W unknowns, then its interval's midpoint.
    fn interleaving(&self) -> Vec<usize> {
        let pts = &self.sys.points;
        let mut perm = vec![0; self.len()];
        let mut next = 0;
        let mut place = |perm: &mut Vec<usize>, cols: &mut dyn Iterator<Item = usize>| {
            for c in cols {
                perm[c] = next;
                next += 1;
            }
        };
        for i in 0..self.m {
            let mut node_points = vec![pts.below[i], pts.above[i]];
            node_points.dedup();
            for k in node_points {
                place(&mut perm, &mut (NP * k..NP * k + NP));
            }
            place(&mut perm, &mut (self.wcol(i, 0)..self.wcol(i, NW)));
            if self.hermite_simpson && i < self.m - 1 {
                let k = pts.mid[i];
                place(&mut perm, &mut (NP * k..NP * k + NP));
            }
        }
        perm
    }

    /// Set the discretisation's data to p and its evaluations to the elastic unknowns of y:
    /// their values, or with [`Part::Full`] their derivatives too.
    fn load(&mut self, y: &[f64], part: Part) -> Result<(), RhsError> {
        let p = &y[..self.n_p];
        for i in 0..self.m {
            let w = &y[self.n_p + NW * i..self.n_p + NW * i + NY];
            self.u[NY * i..NY * i + NY].copy_from_slice(w);
        }
        if self.at_p.as_slice() != p {
            self.sys.load_data(p);
            self.at_p.clear();
            self.at_p.extend_from_slice(p);
        }
        let disc = self.sys.elastic.discretisation_mut();
        match part {
            Part::Values => disc.evaluate_values_at(&self.u),
            _ => disc.evaluate_at(&self.u),
        }
        .map_err(RhsError::Evaluation)
    }

    /// The consistent state at t = 0 from the elastic solution the system holds: y with z
    /// from the quadrature and d from the stimulus. y' comes from [`CoupledDae::derivative`].
    pub fn initial_state(&mut self) -> Result<Vec<f64>, DaeError> {
        let p0 = self.sys.points.initial_state();
        let u0 = self.sys.elastic.u.clone();
        let data = self.sys.points.material_data(&p0);
        let disc = self.sys.elastic.discretisation_mut();
        disc.set_data(data);
        let quad = disc.quadratures(&u0).map_err(RhsError::Evaluation)?;
        let mut y = vec![0.0; self.len()];
        y[..self.n_p].copy_from_slice(&p0);
        for i in 0..self.m {
            let w = self.n_p + NW * i;
            y[w..w + NY].copy_from_slice(&u0[NY * i..NY * i + NY]);
            y[w + Z] = quad.z[i];
        }
        self.at_p.clear();
        self.load(&y, Part::Values)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(&y, &mut s.local);
        let crossing = self.point_rates(&y, &mut s, false);
        self.scratch = s;
        let crossing = crossing?;
        let d = self.d();
        y[d] = crossing.map_or(0.0, |c| c.value());
        Ok(y)
    }

    /// y' at a consistent y: the rates for P, and for W and d the derivative of the
    /// constraints, [A a; cᵀ s] w' = −[C; cᵀ] p' (one band solve of the algebraic block).
    pub fn derivative(&mut self, y: &[f64]) -> Result<Vec<f64>, DaeError> {
        let mut yp = vec![0.0; self.len()];
        let mut r = vec![0.0; self.len()];
        self.residual(y, &yp.clone(), &mut r)?;
        for k in 0..self.n_p {
            yp[k] = -r[k];
        }
        self.assemble(0.0, y)?;
        let mut schur = SchurSolver::new(&self.jac, self.n_p, true, Reduced::Band)?;
        schur.factor_algebraic(&self.jac)?;
        let n_p = self.n_p;
        let (p_dot, w_dot) = yp.split_at_mut(n_p);
        schur.solve_algebraic(p_dot, w_dot)?;
        Ok(yp)
    }

    /// Assemble at (c, y) and factorise.
    pub fn setup(&mut self, c: f64, y: &[f64]) -> Result<(), DaeError> {
        let start = std::time::Instant::now();
        self.counters.jacobians += 1;
        self.assemble(c, y)?;
        let mid = std::time::Instant::now();
        self.counters.jacobian_seconds += (mid - start).as_secs_f64();
        let factored = self.linear.factor(&self.jac);
        self.counters.fallbacks = self.linear.fallbacks();
        factored?;
        self.counters.factor_seconds += mid.elapsed().as_secs_f64();
        Ok(())
    }

    /// x = M⁻¹ b with the last factorisation.
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), DaeError> {
        let start = std::time::Instant::now();
        self.counters.solves += 1;
        self.linear.solve(b, x)?;
        self.counters.solve_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The assembled matrix of the last [`CoupledDae::assemble`] (for tests).
    pub fn matrix(&self) -> &Csr {
        &self.jac
    }

    /// Hand the state y to the growth system (for output at an interpolated time): its
    /// data become p and its elastic unknowns y's, without a re-solve.
    pub fn adopt(&mut self, y: &[f64]) {
        let p = &y[..self.n_p];
        let mut u = Vec::with_capacity(NY * self.m);
        for i in 0..self.m {
            u.extend_from_slice(&y[self.wcol(i, 0)..self.wcol(i, NY)]);
        }
        self.sys.adopt(p, &u);
        self.at_p.clear();
    }

    /// The number of growth unknowns (the differential part of y).
    pub fn differential_len(&self) -> usize {
        self.n_p
    }

    /// 1 for the differential unknowns, 0 for the algebraic ones (IDASetId).
    pub fn id(&self) -> Vec<f64> {
        (0..self.len())
            .map(|k| if k < self.n_p { 1.0 } else { 0.0 })
            .collect()
    }

    /// The local error test's mask when the sensitivities take part in it: every unknown
    /// but the border d (IDAS reads its id only for the suppressed error test and for
    /// IDACalcIC, which this system does not use: its consistent values come from the
    /// elastic solve). d is the blue surface's depth where the retina crosses φ_max,
    /// interpolated between the two points that bracket the crossing (docs/MODEL.md §6):
    /// continuous, but ∂d/∂y jumps whenever the bracketing pair changes, so its sensitivity
    /// s_d jumps there, and an error test on s_d asks for steps no h resolves (measured:
    /// const, N = 101, rtol 1e-8: h cut to 1e-314 at t = 0.053). d is algebraic, determined by
    /// the unknowns that stay in the test.
    pub fn sensitivity_error_mask(&self) -> Vec<f64> {
        let mut mask = vec![1.0; self.len()];
        mask[self.d()] = 0.0;
        mask
    }

    /// Absolute tolerances. The growth state and d take `atol` (mm for ρ and d, 1 for γ_s),
    /// as CVODE's growth state does. Each elastic unknown takes the error `rtol` allows on
    /// its typical size (κ ~ 1/R0, r and z ~ R0, θ ~ 1, q_s and t_s ~ the Laplace tension,
    /// as KINSOL's scaling has them) plus `atol` in proportion: q_s is near zero over much
    /// of the shell, and an error test relative to its own size there asked for 1e-9 of the
    /// tension it balances (measured: the q_s rows limited nearly every step).
    pub fn abs_tolerances(&self, rtol: f64, atol: f64, r0: f64) -> Vec<f64> {
        let typ = self.sys.elastic.discretisation().typical(r0);
        let typical = [typ[0], typ[1], typ[2], typ[3], typ[4], r0];
        let mut v = vec![atol; self.len()];
        for i in 0..self.m {
            for (c, t) in typical.iter().enumerate() {
                v[self.wcol(i, c)] = (rtol + atol / r0) * t;
            }
        }
        v
    }
}

/// The placeholder before the real solver is made.
struct NoSolver;

impl DirectSolver for NoSolver {
    fn factor(&mut self, _: &Csr) -> Result<(), LinalgError> {
        Err(LinalgError::Singular("no solver".into()))
    }
    fn solve(&mut self, _: &[f64], _: &mut [f64]) -> Result<(), LinalgError> {
        Err(LinalgError::Singular("no solver".into()))
    }
}

/// The state of the kinks at y, for the measurement of stopping IDA at them (`ida.rs`'s
/// tests): the first point of the crossing's stencil (it moves when the crossing passes to
/// the next pair), and per point whether [d]⁺, [r − ρ]⁺ and [α_s − 1]⁺ are on.
#[cfg(test)]
impl CoupledDae {
    pub(crate) fn kink_state(
        &mut self,
        y: &[f64],
    ) -> Result<(Option<usize>, Vec<[bool; 3]>), RhsError> {
        self.load(y, Part::Values)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let crossing = match self.point_rates(y, &mut s, false) {
            Ok(c) => c,
            Err(e) => {
                self.scratch = s;
                return Err(e);
            }
        };
        let d = y[self.d()];
        let on = s
            .rates
            .iter()
            .zip(&s.local)
            .enumerate()
            .map(|(k, (pr, l))| {
                let drive = if pr.beyond { d } else { pr.drive };
                [drive > 0.0, l.r - y[NP * k] > 0.0, l.alpha_s > 1.0]
            })
            .collect();
        self.scratch = s;
        let first = match crossing {
            Some(Border::Crossing(c)) => Some(c.points()[0].0),
            _ => None,
        };
        Ok((first, on))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::settings::SolverSettings;
    use crate::growth::GrowthParams;
    use crate::model::params::Params;

    /// The const and fibre scenes (the fibre scene: non-uniform thickness, D = 200, so
    /// jump nodes and two growth points at them) under both schemes, N = 31, rounded kinks.
    fn sensitivity_cases() -> Vec<(String, Params, SolverSettings, GrowthParams)> {
        use crate::model::params::Thickness;
        let mut out = vec![];
        for (thickness, d) in [(Thickness::Uniform, 0.0), (Thickness::NonUniform, 200.0)] {
            for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
                let p = Params {
                    thickness,
                    d,
                    ..Params::default()
                };
                let s = SolverSettings {
                    nodes: 31,
                    scheme,
                    newton_tol: 1e-13,
                    ..SolverSettings::default()
                };
                let g = GrowthParams {
                    kink_width: 0.01,
                    ..GrowthParams::default()
                };
                out.push((format!("D = {d}, {scheme:?}"), p, s, g));
            }
        }
        out
    }

    /// The derivative of a vector function at v by Richardson extrapolation of central
    /// differences: (4 D(h) − D(2h))/3, whose error is O(h⁴).
    fn richardson_derivative(f: impl Fn(f64) -> Vec<f64>, v: f64, h: f64) -> Vec<f64> {
        let central = |h: f64| -> Vec<f64> {
            let (up, down) = (f(v + h), f(v - h));
            up.iter()
                .zip(&down)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let (d1, d2) = (central(h), central(2.0 * h));
        d1.iter()
            .zip(&d2)
            .map(|(a, b)| (4.0 * a - b) / 3.0)
            .collect()
    }

    /// The coupled system of the model with `param` set to `v`, and its consistent y(0).
    fn dae_with(
        p: &Params,
        s: &SolverSettings,
        g: &GrowthParams,
        param: SensParam,
        v: f64,
    ) -> (CoupledDae, Vec<f64>) {
        let (mut p, mut g) = (*p, g.clone());
        param.set(&mut p, &mut g, v);
        let mut dae = CoupledDae::new(GrowthSystem::new(&p, s, &g).unwrap());
        let y = dae.initial_state().unwrap();
        (dae, y)
    }

    /// The model's parameters a scene of `p` takes sensitivities to.
    fn model_params(p: &Params) -> Vec<SensParam> {
        SensParam::ALL
            .into_iter()
            .filter(|q| !q.is_growth() && q.check(p).is_ok())
            .collect()
    }

    /// ∂F/∂p for C, D, E_b, ΔP and z_B against central differences of the residual itself
    /// (the model rebuilt at p ± h, evaluated at the same y and y' = 0): every row, the
    /// elastic, z, cornea, growth and border rows, both schemes, with and without fibres and
    /// jumps, to 1e-7 of the column's largest entry (beside the differences' round-off);
    /// and each column moves some row besides the growth rows, and the growth rows exactly
    /// where the parameter reaches the rates (so that the check cannot pass on zeros).
    #[test]
    fn model_parameter_residuals_match_differences_of_the_residual() {
        for (what, p, s, g) in sensitivity_cases() {
            let mut dae = CoupledDae::new(GrowthSystem::new(&p, &s, &g).unwrap());
            let y = dae.initial_state().unwrap();
            let n = dae.len();
            let yp = vec![0.0; n];
            let y_max = y.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            for param in model_params(&p) {
                let mut fp = vec![0.0; n];
                dae.parameter_residual(&y, param, &mut fp).unwrap();
                let v = param.value(&p, &g);
                let h = 1e-3 * v.abs().max(1.0);
                let residual_at = |v: f64| {
                    let (mut other, _) = dae_with(&p, &s, &g, param, v);
                    let mut r = vec![0.0; n];
                    other.residual(&y, &yp, &mut r).unwrap();
                    r
                };
                // O(h⁴) = 1e-12 relative.
                let fd = richardson_derivative(residual_at, v, h);
                let scale = fd.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                let at = residual_at(v);
                for (i, (a, b)) in fp.iter().zip(&fd).enumerate() {
                    // The difference's round-off: ulps of the row's terms (the unknowns, or
                    // the rates ~ η0 at y' = 0) over h; the α_s solves agree to an ulp or
                    // two whatever their seed, and γ_s' ∝ [α_s − 1]⁺ amplifies that by
                    // 1/(α_s − 1) ~ 30.
                    let noise = 100.0 * f64::EPSILON * at[i].abs().max(y_max) / h;
                    assert!(
                        (a - b).abs() <= 1e-7 * scale + noise,
                        "{what}, {}: row {i}: {a} vs {b} (largest {scale:e})",
                        param.key()
                    );
                }
                let moved = |rows: std::ops::Range<usize>| rows.into_iter().any(|i| fp[i] != 0.0);
                // At fixed y, E_b and ΔP do not reach the rates: they move f_κ and f_{q_s},
                // and so y_m's κ and q_s, which no local state (r, θ, z, α_s) reads.
                let reaches_rates = !matches!(param, SensParam::Bending | SensParam::Pressure);
                assert_eq!(
                    moved(0..dae.n_p),
                    reaches_rates,
                    "{what}, {}: growth rows",
                    param.key()
                );
                assert!(moved(dae.n_p..n), "{what}, {}: no other row", param.key());
            }
        }
    }

    /// s(0) against central differences of the t = 0 equilibrium (KINSOL to 1e-13, the
    /// model rebuilt at p ± 1e-4 relative): every unknown to 1e-6 of the column's largest,
    /// for all eight parameters (η0, Γ, δ: exactly zero), both schemes, with and without
    /// fibres.
    #[test]
    fn initial_sensitivities_match_differences_of_the_elastic_solve() {
        for (what, p, s, g) in sensitivity_cases() {
            let params: Vec<SensParam> = SensParam::ALL
                .into_iter()
                .filter(|q| q.check(&p).is_ok())
                .collect();
            let mut dae = CoupledDae::new(GrowthSystem::new(&p, &s, &g).unwrap());
            dae.set_linear(DaeLinear::SchurBlock).unwrap();
            dae.set_sensitivities(&params);
            let y = dae.initial_state().unwrap();
            let yp = dae.derivative(&y).unwrap();
            let (s0, sp0) = dae.initial_sensitivities(&y, &yp).unwrap();
            assert_eq!((s0.len(), sp0.len()), (params.len(), params.len()));
            for (j, &param) in params.iter().enumerate() {
                let v = param.value(&p, &g);
                let h = 1e-2 * v.abs().max(1.0);
                // O(h⁴) = 1e-8 relative.
                let fd = richardson_derivative(|x| dae_with(&p, &s, &g, param, x).1, v, h);
                let scale = fd.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                if param.is_growth() {
                    assert!(
                        s0[j].iter().chain(&fd).all(|&x| x == 0.0),
                        "{what}, {}",
                        param.key()
                    );
                    continue;
                }
                assert!(
                    scale > 0.0,
                    "{what}, {}: the equilibrium does not move",
                    param.key()
                );
                let mut worst = 0.0_f64;
                for (i, (a, b)) in s0[j].iter().zip(&fd).enumerate() {
                    // The equilibria's own error (KINSOL at 1e-13, measured ~2e-13 of an
                    // unknown's size) over the steps, as Richardson's sum amplifies it.
                    let noise = 1.5 * 2e-13 * y[i].abs().max(1.0) / h;
                    worst = worst.max((a - b).abs() / scale);
                    assert!(
                        (a - b).abs() <= 1e-6 * scale + noise,
                        "{what}, {}: unknown {i}: {a} vs {b} (largest {scale:e})",
                        param.key()
                    );
                }
                println!(
                    "{what}, {}: s(0) within {worst:.1e} of the largest",
                    param.key()
                );
            }
        }
    }

    /// s'(0) = ∂y'(0)/∂p: against central differences of the consistent start's y'(0)
    /// (the model rebuilt at p ± h), every unknown but the border d (outside the error test,
    /// its derivative jumps), for the model's parameters, both schemes, with and without
    /// fibres, with the kinks rounded as in the sensitivity tests and as wide as 0.05 (the
    /// case whose first step failed with the sensitivities in the error test while the
    /// algebraic s'(0) left out the second-order terms).
    #[test]
    fn initial_sensitivity_derivatives_match_differences_of_the_start() {
        let mut worst_linearised = 0.0_f64;
        for (what, p, s, g) in sensitivity_cases() {
            for kink_width in [0.01, 0.05] {
                let g = GrowthParams {
                    kink_width,
                    ..g.clone()
                };
                let params = model_params(&p);
                let mut dae = CoupledDae::new(GrowthSystem::new(&p, &s, &g).unwrap());
                dae.set_linear(DaeLinear::SchurBlock).unwrap();
                dae.set_sensitivities(&params);
                let y = dae.initial_state().unwrap();
                let yp = dae.derivative(&y).unwrap();
                let (_, sp0) = dae.initial_sensitivities(&y, &yp).unwrap();
                let (_, linearised) = dae.linearised_sensitivities(&y).unwrap();
                let d = dae.d();
                for (j, &param) in params.iter().enumerate() {
                    let v = param.value(&p, &g);
                    let h = 1e-2 * v.abs().max(1.0);
                    let fd = richardson_derivative(
                        |x| {
                            let (mut dae, y) = dae_with(&p, &s, &g, param, x);
                            dae.set_linear(DaeLinear::SchurBlock).unwrap();
                            dae.derivative(&y).unwrap()
                        },
                        v,
                        h,
                    );
                    let scale = fd
                        .iter()
                        .enumerate()
                        .filter(|&(i, _)| i != d)
                        .fold(0.0_f64, |m, (_, x)| m.max(x.abs()));
                    let mut worst = 0.0_f64;
                    for i in (0..fd.len()).filter(|&i| i != d) {
                        let (a, b) = (sp0[j][i], fd[i]);
                        // The starts' own error (KINSOL at 1e-13 of an unknown's size,
                        // through y') over the steps, as Richardson's sum amplifies it.
                        let noise = 1.5 * 2e-13 * yp[i].abs().max(1.0) / h;
                        worst = worst.max((a - b).abs() / scale);
                        worst_linearised =
                            worst_linearised.max((linearised[j][i] - b).abs() / scale);
                        assert!(
                            (a - b).abs() <= 1e-5 * scale + noise,
                            "{what}, kink {kink_width}, {}: unknown {i}: {a} vs {b} (largest {scale:e})",
                            param.key()
                        );
                    }
                    println!(
                        "{what}, kink {kink_width}, {}: s'(0) within {worst:.1e} of the largest",
                        param.key()
                    );
                }
            }
        }
        // The linearised algebraic s' misses ∂y'(0)/∂p by far more than that.
        println!("linearised: within {worst_linearised:.1e}");
        assert!(worst_linearised > 1e-3, "{worst_linearised:.1e}");
    }

    /// The structure the docs state: the Schur complement leaves the elastic band (lower 8,
    /// upper 8, with z in it) while the interleaved whole system has lower 14, upper 12,
    /// and the pattern of the const scene at N = 501 holds 87 939 entries.
    #[test]
    fn reduced_and_interleaved_bandwidths() {
        let s = SolverSettings {
            nodes: 501,
            ..SolverSettings::default()
        };
        let sys = GrowthSystem::new(&Params::default(), &s, &GrowthParams::default()).unwrap();
        let dae = CoupledDae::new(sys);
        let schur = SchurSolver::new(&dae.jac, dae.n_p, true, Reduced::Band).unwrap();
        let band = InterleavedBand::new(&dae.jac, dae.interleaving(), Some(dae.d())).unwrap();
        assert_eq!(
            (dae.len(), dae.n_p, dae.n_w, dae.jac.nnz()),
            (5059, 2022, 3036, 87939)
        );
        assert_eq!(schur.widths(), (8, 8));
        assert_eq!(band.widths(), (14, 12));
        // The same pattern fits the block structure (its check refuses any other).
        SchurSolver::new(&dae.jac, dae.n_p, true, Reduced::Block).unwrap();
    }

    /// The reduced solvers on real Newton matrices of every shape the schemes produce:
    /// the const scene (uniform) and the fibre scene (non-uniform thickness, D = 200:
    /// breakpoints and graded pole and cornea nodes, two growth points at each breakpoint),
    /// trapezoid and Hermite–Simpson (midpoint growth points), at the consistent start with
    /// c = 500. Block and band paths against nalgebra's dense LU of the whole matrix:
    /// relative residual ≤ 1e-13, and block and band agree to 1e-12.
    #[test]
    fn block_reduced_solver_matches_dense_lu_on_real_newton_matrices() {
        use crate::model::params::Thickness;
        use nalgebra::{DMatrix, DVector};
        for (thickness, d) in [(Thickness::Uniform, 0.0), (Thickness::NonUniform, 200.0)] {
            for scheme in [Scheme::Trapezoid, Scheme::HermiteSimpson] {
                let s = SolverSettings {
                    nodes: 31,
                    scheme,
                    ..SolverSettings::default()
                };
                let p = Params {
                    thickness,
                    d,
                    ..Params::default()
                };
                let what = format!("{thickness:?}, D = {d}, {scheme:?}");
                let sys = GrowthSystem::new(&p, &s, &GrowthParams::default()).unwrap();
                let mut dae = CoupledDae::new(sys);
                let y = dae.initial_state().unwrap();
                dae.assemble(500.0, &y).unwrap();
                let a = dae.jac.clone();
                let n = a.n();
                let mut dense = DMatrix::zeros(n, n);
                for i in 0..n {
                    let (cols, vals) = a.row(i);
                    for (&j, &v) in cols.iter().zip(vals) {
                        dense[(i, j)] = v;
                    }
                }
                let b: Vec<f64> = (0..n).map(|k| (0.37 * k as f64).sin()).collect();
                let mut xs = vec![];
                for how in [Reduced::Block, Reduced::Band] {
                    let mut schur = SchurSolver::new(&a, dae.n_p, true, how).unwrap();
                    schur.factor(&a).unwrap();
                    let mut x = vec![0.0; n];
                    schur.solve(&b, &mut x).unwrap();
                    let (xv, bv) = (
                        DVector::from_column_slice(&x),
                        DVector::from_column_slice(&b),
                    );
                    let res = (&dense * &xv - &bv).amax() / (dense.amax() * xv.amax() + bv.amax());
                    assert!(res <= 1e-13, "{what}, {how:?}: residual {res:e}");
                    xs.push(x);
                }
                let expect = dense.lu().solve(&DVector::from_column_slice(&b)).unwrap();
                let scale = expect.amax();
                for (i, e) in expect.iter().enumerate() {
                    let (blk, band) = (xs[0][i], xs[1][i]);
                    assert!(
                        (blk - band).abs() <= 1e-12 * scale,
                        "{what} {i}: {blk} vs {band}"
                    );
                    assert!(
                        (blk - e).abs() <= 1e-10 * scale,
                        "{what} {i}: {blk} vs dense {e}"
                    );
                }
            }
        }
    }
}
