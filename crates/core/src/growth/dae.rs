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

use super::crossing::Crossing;
use super::points::NP;
use super::settings::DaeLinear;
use super::system::{GrowthSystem, RhsError};
use super::ThicknessLaw;
use crate::bvp::discretisation::{Discretisation, EvalFailure, Evaluations, NY, POLE_ROWS};
use crate::bvp::equations::{
    constant_partials, data_partials, ConstantPartials, Mat5, MaterialPoint, PointError, PointEval,
    ShellConstant, Vec5, KAPPA, R, THETA, TS,
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
    depth: f64,
    angle: f64,
    g_v: f64,
    eta: f64,
    beyond: bool,
    /// ∂(rate_ρ, rate_γ)/∂g_c: the rates are linear in the growth capacity.
    per_capacity: [f64; 2],
}

/// Derivatives of (rate_ρ, rate_γ, depth, angle) in (r, θ, z, α_s, ρ, γ_s) and d.
#[derive(Clone, Copy, Debug, Default)]
struct RateDeriv {
    rate: [[f64; 6]; 2],
    rate_d: [f64; 2],
    depth: [f64; 6],
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

/// A parameter the growth run's forward sensitivities are taken with respect to (docs/MODEL.md §10).
/// η0, Γ, δ enter only the growth rates, through the capacity g_c(Σ) = η0/2 (1 + tanh((Γ −
/// Σ)/δ)) (docs/MODEL.md §5), linearly. C, D, E_b and ΔP enter the elastic equations
/// (docs/MODEL.md §2–3; ΔP the cornea's edge too, §3) and through α_s the z rows, the
/// retina and the rates; z_B moves the blue surface the retina is compared with (§6). Every
/// ∂F/∂p is analytic ([`CoupledDae::parameter_residual`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensParam {
    /// growth.eta0.
    Eta0,
    /// growth.Gamma.
    Gamma,
    /// growth.delta.
    Delta,
    /// fibres.D (only in a scene with fibres).
    FibreStiffness,
    /// material.C.
    Modulus,
    /// material.bending.
    Bending,
    /// pressure.dP.
    Pressure,
    /// stimulus.blue.z_B: the blue best-focus surface's polar centre, which moves the
    /// surface along the axis.
    BlueCentre,
    /// growth.schedule_tau, growth.schedule_centre, growth.schedule_width: the named
    /// schedules' parameters. They never reach the DAE: the schedule is a change of the
    /// run's clock, and their sensitivities follow from η0's ([`super::schedule`]).
    ScheduleTau,
    ScheduleCentre,
    ScheduleWidth,
    /// geometry.R0: the eye's radius at the start. It moves the material mesh itself (the
    /// shell's length is π·fraction·R0), so its sensitivity is a directional difference of
    /// two runs, not an IDAS sensitivity (docs/MODEL.md §11).
    Radius,
}

impl SensParam {
    pub const ALL: [SensParam; 8] = [
        SensParam::Eta0,
        SensParam::Gamma,
        SensParam::Delta,
        SensParam::FibreStiffness,
        SensParam::Modulus,
        SensParam::Bending,
        SensParam::Pressure,
        SensParam::BlueCentre,
    ];

    /// The parameters the run handles outside the DAE: the schedule's and R0.
    pub const OUTSIDE: [SensParam; 4] = [
        SensParam::ScheduleTau,
        SensParam::ScheduleCentre,
        SensParam::ScheduleWidth,
        SensParam::Radius,
    ];

    /// The scene keys sensitivities can be taken to, for messages and help.
    pub const SUPPORTED: &'static str = "growth.eta0, growth.Gamma, growth.delta, fibres.D, material.C, material.bending, pressure.dP, stimulus.blue.z_B, growth.schedule_tau, growth.schedule_centre, growth.schedule_width, geometry.R0";

    /// The schedule's parameter this is, if it is one.
    pub fn schedule_param(self) -> Option<super::schedule::ScheduleParam> {
        use super::schedule::ScheduleParam;
        match self {
            SensParam::ScheduleTau => Some(ScheduleParam::Tau),
            SensParam::ScheduleCentre => Some(ScheduleParam::Centre),
            SensParam::ScheduleWidth => Some(ScheduleParam::Width),
            _ => None,
        }
    }

    /// True for the parameters IDAS integrates sensitivities to (the DAE's).
    pub fn in_dae(self) -> bool {
        !Self::OUTSIDE.contains(&self)
    }

    /// The scene key.
    pub fn key(self) -> &'static str {
        match self {
            SensParam::Eta0 => "growth.eta0",
            SensParam::Gamma => "growth.Gamma",
            SensParam::Delta => "growth.delta",
            SensParam::FibreStiffness => "fibres.D",
            SensParam::Modulus => "material.C",
            SensParam::Bending => "material.bending",
            SensParam::Pressure => "pressure.dP",
            SensParam::BlueCentre => "stimulus.blue.z_B",
            SensParam::ScheduleTau => "growth.schedule_tau",
            SensParam::ScheduleCentre => "growth.schedule_centre",
            SensParam::ScheduleWidth => "growth.schedule_width",
            SensParam::Radius => "geometry.R0",
        }
    }

    /// Why the parameter cannot be taken in a model of `params`, if it cannot: fibres.D in
    /// a scene without fibres (D = 0 leaves the fibres out of the model, docs/MODEL.md §2).
    pub fn check(self, params: &Params) -> Result<(), String> {
        match self {
            SensParam::FibreStiffness if !params.has_fibres() => Err(format!(
                "{} = 0: the scene has no fibres, so there is no sensitivity to their stiffness",
                self.key()
            )),
            _ => Ok(()),
        }
    }

    /// True for η0, Γ, δ: the parameters that enter the growth rates alone.
    pub fn is_growth(self) -> bool {
        matches!(self, SensParam::Eta0 | SensParam::Gamma | SensParam::Delta)
    }

    /// The shell constant this is, for C, D, E_b and ΔP.
    pub fn shell_constant(self) -> Option<ShellConstant> {
        match self {
            SensParam::FibreStiffness => Some(ShellConstant::FibreStiffness),
            SensParam::Modulus => Some(ShellConstant::Modulus),
            SensParam::Bending => Some(ShellConstant::Bending),
            SensParam::Pressure => Some(ShellConstant::Pressure),
            _ => None,
        }
    }

    /// Its value in the model (`params`, `g`).
    pub fn value(self, params: &Params, g: &super::GrowthParams) -> f64 {
        match self {
            SensParam::Eta0 => g.eta0,
            SensParam::Gamma => g.gamma,
            SensParam::Delta => g.delta,
            SensParam::FibreStiffness => params.d,
            SensParam::Modulus => params.c,
            SensParam::Bending => params.e_b,
            SensParam::Pressure => params.dp,
            SensParam::BlueCentre => g.blue.z_b,
            SensParam::ScheduleTau => g.schedule.tau,
            SensParam::ScheduleCentre => g.schedule.centre,
            SensParam::ScheduleWidth => g.schedule.width,
            SensParam::Radius => params.r0,
        }
    }

    /// The scale |p̄| IDAS weighs its sensitivity by (tolerances atol/|p̄|): the value's
    /// size, or where the value is 0 (η0 = 0, ΔP = 0, Γ or z_B at 0) the size of its
    /// default (docs/MODEL.md §8), else 1 in the key's units. A scale of 0 would make every
    /// weight of s zero, so that the sensitivity's Newton iteration passed its test with
    /// s uncorrected (ΔP = 0 gave ∂L/∂ΔP ≈ −1e7).
    pub fn scale(self, params: &Params, g: &super::GrowthParams) -> f64 {
        let defaults = (Params::default(), super::GrowthParams::default());
        [self.value(params, g), self.value(&defaults.0, &defaults.1)]
            .into_iter()
            .map(f64::abs)
            .find(|v| *v > 0.0 && v.is_finite())
            .unwrap_or(1.0)
    }

    /// Set its value in the model to `v` (the scene's own key does the same, with the red
    /// surface following the blue one where the scene says so: `Scene::set`).
    pub fn set(self, params: &mut Params, g: &mut super::GrowthParams, v: f64) {
        match self {
            SensParam::Eta0 => g.eta0 = v,
            SensParam::Gamma => g.gamma = v,
            SensParam::Delta => g.delta = v,
            SensParam::FibreStiffness => params.d = v,
            SensParam::Modulus => params.c = v,
            SensParam::Bending => params.e_b = v,
            SensParam::Pressure => params.dp = v,
            SensParam::BlueCentre => g.blue.z_b = v,
            SensParam::ScheduleTau => g.schedule.tau = v,
            SensParam::ScheduleCentre => g.schedule.centre = v,
            SensParam::ScheduleWidth => g.schedule.width = v,
            SensParam::Radius => params.r0 = v,
        }
    }

    /// ∂g_c/∂p at Σ = `sigma` (docs/MODEL.md §5); zero for the parameters g_c does not hold.
    pub fn capacity_partial(self, g: &super::GrowthParams, sigma: f64) -> f64 {
        let u = (g.gamma - sigma) / g.delta;
        let (th, sech2) = (u.tanh(), 1.0 - u.tanh() * u.tanh());
        match self {
            SensParam::Eta0 => 0.5 * (1.0 + th),
            SensParam::Gamma => 0.5 * g.eta0 * sech2 / g.delta,
            SensParam::Delta => -0.5 * g.eta0 * sech2 * u / g.delta,
            _ => 0.0,
        }
    }
}

/// (s_j(0), s_j'(0)) for every parameter j, from [`CoupledDae::initial_sensitivities`].
pub type InitialSensitivities = (Vec<Vec<f64>>, Vec<Vec<f64>>);

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

    /// Set the discretisation's data to p and its evaluations to the elastic unknowns of y.
    fn load(&mut self, y: &[f64]) -> Result<(), RhsError> {
        let p = &y[..self.n_p];
        for i in 0..self.m {
            let w = &y[self.n_p + NW * i..self.n_p + NW * i + NY];
            self.u[NY * i..NY * i + NY].copy_from_slice(w);
        }
        if self.at_p.as_slice() != p {
            let data = self.sys.points.material_data(p);
            self.sys.elastic.discretisation_mut().set_data(data);
            self.at_p.clear();
            self.at_p.extend_from_slice(p);
        }
        self.sys
            .elastic
            .discretisation_mut()
            .evaluate_at(&self.u)
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
        self.load(&y)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(&y, &mut s.local);
        let crossing = self.point_rates(&y, &s.local, None, &mut s.rates);
        self.scratch = s;
        let d = self.d();
        y[d] = crossing.map_or(0.0, |c| c.value);
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

    /// Take forward sensitivities with respect to `params`.
    pub fn set_sensitivities(&mut self, params: &[SensParam]) {
        self.sens_params = params.to_vec();
        self.sens_at.clear();
    }

    /// The parameters of the forward sensitivities.
    pub fn sensitivity_params(&self) -> &[SensParam] {
        &self.sens_params
    }

    /// ∂F/∂p at y for parameter `param` (at fixed y and y'): for η0, Γ, δ only the growth
    /// rows, −(∂rates/∂g_c) ∂g_c/∂p; for the others every row that holds the parameter
    /// ([`CoupledDae::model_parameter_residual`]).
    pub fn parameter_residual(
        &mut self,
        y: &[f64],
        param: SensParam,
        out: &mut [f64],
    ) -> Result<(), RhsError> {
        self.parameter_residuals(y, &[param], &mut [out])
    }

    /// [`CoupledDae::parameter_residual`] for several parameters from one evaluation of
    /// the rates.
    fn parameter_residuals(
        &mut self,
        y: &[f64],
        params: &[SensParam],
        out: &mut [&mut [f64]],
    ) -> Result<(), RhsError> {
        self.load(y)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let model = params.iter().any(|p| !p.is_growth());
        let crossing = self.point_rates(y, &s.local, model.then_some(&mut s.rd), &mut s.rates);
        let finite = self.check_finite(&s.rates, model.then_some(s.rd.as_slice()));
        if finite.is_ok() {
            let g = self.sys.growth_params();
            for (&param, out) in params.iter().zip(out.iter_mut()) {
                out.fill(0.0);
                if !param.is_growth() {
                    self.model_parameter_residual(param, &s.rd, crossing, out);
                    continue;
                }
                for (k, pr) in s.rates.iter().enumerate() {
                    let dc = param.capacity_partial(g, self.sys.points.sigma_ref[k]);
                    out[NP * k] = -pr.per_capacity[0] * dc;
                    out[NP * k + 1] = -pr.per_capacity[1] * dc;
                }
            }
        }
        self.scratch = s;
        finite
    }

    /// Each point's ∂f/∂c and ∂α_s/∂c in the shell constant c at fixed y, from the
    /// evaluation at its site (as [`CoupledDae::data_derivs`]).
    fn constant_derivs(&self, c: ShellConstant) -> Vec<ConstantPartials> {
        let disc = self.sys.elastic.discretisation();
        let (ev, data, shell) = (disc.evaluations(), &disc.data, &disc.shell);
        let y = |j: usize| Vec5::from_column_slice(&self.u[NY * j..NY * j + NY]);
        self.sites
            .iter()
            .map(|&site| match site {
                Site::Left(i) => constant_partials(shell, c, &data.above[i], &y(i), ev.left(i)),
                Site::Right(i) => {
                    constant_partials(shell, c, &data.below[i + 1], &y(i + 1), ev.right(i))
                }
                Site::Mid(i) => constant_partials(shell, c, &data.mid[i], ev.y_mid(i), ev.mid(i)),
            })
            .collect()
    }

    /// ∂F/∂p for a parameter of the model (C, D, E_b, ΔP, z_B) at the y last loaded, with
    /// the rates' derivatives `rd` and the crossing there, by the chain rule:
    /// - the elastic rows through f (and α_s at the pole), with the Hermite–Simpson midpoint
    ///   y_m = (y_i + y_{i+1})/2 + h/8 (f_i − f_{i+1}) moving with f_i, f_{i+1}:
    ///   ∂f_m/∂p = f_m,p + J_m h/8 (f_i,p − f_{i+1,p}); ΔP in the pole's first integral and
    ///   the cornea's edge (r*, z* ∝ the cornea's stretch α, dα/dΔP from its law);
    /// - the z rows through the slopes −γ α_s sin θ;
    /// - each point's local state (r, θ, z, α_s): at a node only α_s moves; at a midpoint
    ///   y_m, α_s there and z_m (through the end slopes) too; the growth rows and the border
    ///   follow through the rates' and the crossing's derivatives in the local state;
    /// - z_B: the stimulus reads the retina's z − z_B only, so moving z_B is moving every
    ///   point's z the other way: the local state's derivative is (0, 0, −1, 0).
    fn model_parameter_residual(
        &self,
        param: SensParam,
        rd: &[RateDeriv],
        crossing: Option<Crossing>,
        out: &mut [f64],
    ) {
        let disc = self.sys.elastic.discretisation();
        let (ev, data) = (disc.evaluations(), &disc.data);
        let pd = match param.shell_constant() {
            Some(c) => self.constant_derivs(c),
            None => vec![ConstantPartials::default(); self.sites.len()],
        };
        let n_p = self.n_p;
        // ∂(r, θ, z, α_s)/∂p of every point.
        let mut dlocal: Vec<[f64; 4]> = pd.iter().map(|c| [0.0, 0.0, 0.0, c.alpha_s]).collect();
        // The pole: r − σ_ε α_s, θ − σ_ε α_s κ, and the first integral's −r ΔP / 2.
        let k0 = self.sys.points.above[0];
        let se = data.above[0].sigma;
        out[n_p] = -se * pd[k0].alpha_s;
        out[n_p + 1] = -se * pd[k0].alpha_s * self.u[KAPPA];
        if param == SensParam::Pressure {
            out[n_p + 2] = -0.5 * self.u[R];
        }
        for i in 0..self.m - 1 {
            let h = disc.mesh.step(i);
            let [pl, pr, pm] = self.window_points(i);
            let (pl, pr) = (
                pl.expect("every interval has ends"),
                pr.expect("every interval has ends"),
            );
            let (fl, fr) = (pd[pl].f, pd[pr].f);
            // The z slopes w = −γ α_s sin θ at the ends, at fixed y.
            let wl = -data.above[i].gamma * ev.left(i).sin_theta * pd[pl].alpha_s;
            let wr = -data.below[i + 1].gamma * ev.right(i).sin_theta * pd[pr].alpha_s;
            let (rows, zrow) = match pm {
                None => (-(0.5 * h) * (fl + fr), -(0.5 * h) * (wl + wr)),
                Some(pm) => {
                    let ym = (h / 8.0) * (fl - fr);
                    let em = ev.mid(i);
                    let fm = pd[pm].f + em.jac * ym;
                    let am = pd[pm].alpha_s + em.alpha_s_r * ym[R] + em.alpha_s_ts * ym[TS];
                    let wm = -data.mid[i].gamma
                        * (em.sin_theta * am + em.alpha_s * em.cos_theta * ym[THETA]);
                    dlocal[pm] = [ym[R], ym[THETA], (h / 8.0) * (wl - wr), am];
                    (
                        -(h / 6.0) * (fl + 4.0 * fm + fr),
                        -(h / 6.0) * (wl + 4.0 * wm + wr),
                    )
                }
            };
            for a in 0..NY {
                out[self.interval_row(i, a)] = rows[a];
            }
            out[self.interval_row(i, Z)] = zrow;
        }
        let d = self.d();
        if param == SensParam::Pressure {
            // r* = α R_c sin(L/R_c), z* = α R_c (1 + cos(L/R_c)): both ∝ α.
            let cornea = self.sys.elastic.params().cornea;
            let edge = &disc.edge;
            let da = crate::model::cornea::stretch_per_pressure(&cornea, edge.alpha);
            out[d - 3] = -edge.r / edge.alpha * da;
            out[d - 1] = -edge.z / edge.alpha * da;
        }
        if param == SensParam::BlueCentre {
            dlocal.fill([0.0, 0.0, -1.0, 0.0]);
        }
        let dot = |v: &[f64; 6], dl: &[f64; 4]| (0..4).map(|q| v[q] * dl[q]).sum::<f64>();
        for (k, dl) in dlocal.iter().enumerate() {
            out[NP * k] = -dot(&rd[k].rate[0], dl);
            out[NP * k + 1] = -dot(&rd[k].rate[1], dl);
        }
        // The border d − D*: ∂D* = Σ L_k (∂depth_k − p'(φ_k) ∂φ_k), as in the Jacobian.
        if let Some(cr) = crossing {
            for &(k, wgt, slope) in cr.points() {
                out[d] -=
                    wgt * (dot(&rd[k].depth, &dlocal[k]) - slope * dot(&rd[k].angle, &dlocal[k]));
            }
        }
    }

    /// Whether the measurement of the eye (`GrowthSystem::series`) reads `param` itself, at
    /// fixed y: C and D through α_s (the retina's loaded thickness), ΔP through the cornea's
    /// edge (the measurement integrates z from z* = α R_c (1 + cos(L/R_c)) anew), z_B
    /// through the blue surface. E_b and the growth parameters reach it only through y.
    pub fn measurement_reads(&self, param: SensParam) -> bool {
        !param.is_growth() && param != SensParam::Bending
    }

    /// Set the value of `param` where the measurement reads it (see
    /// [`CoupledDae::measurement_reads`]; nothing for the others), for the directional
    /// difference of the measurement. The caller restores the value; the next
    /// [`CoupledDae::adopt`] drops the evaluations made with the other.
    pub fn set_measured_parameter(&mut self, param: SensParam, v: f64) {
        let params = self.sys.elastic.params();
        let disc = self.sys.elastic.discretisation_mut();
        match param {
            SensParam::Modulus => disc.shell.law.c = v,
            SensParam::FibreStiffness => disc.shell.law.d = Some(v),
            SensParam::Pressure => {
                disc.shell.dp = v;
                // ΔP within the cornea's limit: the caller's shifts are 1e-6 of it.
                if let Ok(edge) = crate::model::cornea::edge(&params.cornea, v, params.length()) {
                    disc.edge = edge;
                }
            }
            SensParam::BlueCentre => self.sys.set_blue_centre(v),
            _ => {}
        }
        self.at_p.clear();
    }

    /// The sensitivity residuals rs_j = F_y ys_j + F_y' yps_j + ∂F/∂p_j at y (F_y' is the
    /// identity on the growth rows and zero elsewhere). F_y is the Newton matrix's own
    /// analytic assembly at c = 0, in a matrix of its own (the Newton matrix stays factored).
    pub fn sensitivity_residual(
        &mut self,
        y: &[f64],
        ys: &[&[f64]],
        yps: &[&[f64]],
        rs: &mut [&mut [f64]],
    ) -> Result<(), DaeError> {
        self.counters.sensitivity_residuals += 1;
        if self.sens_at.as_slice() != y {
            let start = std::time::Instant::now();
            self.counters.sensitivity_jacobians += 1;
            self.sens_at.clear();
            std::mem::swap(&mut self.jac, &mut self.sens_jac);
            let assembled = self.assemble(0.0, y);
            std::mem::swap(&mut self.jac, &mut self.sens_jac);
            assembled?;
            let mid = std::time::Instant::now();
            self.counters.sensitivity_jacobian_seconds += (mid - start).as_secs_f64();
            let n = self.len();
            let mut fp = std::mem::take(&mut self.sens_fp);
            fp.resize(self.sens_params.len(), vec![0.0; n]);
            let params = self.sens_params.clone();
            let mut outs: Vec<&mut [f64]> = fp.iter_mut().map(|v| v.as_mut_slice()).collect();
            let done = self.parameter_residuals(y, &params, &mut outs);
            self.sens_fp = fp;
            done?;
            self.sens_at.extend_from_slice(y);
            self.counters.sensitivity_parameter_seconds += mid.elapsed().as_secs_f64();
        }
        let start = std::time::Instant::now();
        self.sens_jac.mul_many(ys, rs);
        for j in 0..rs.len() {
            let r = &mut *rs[j];
            for k in 0..self.n_p {
                r[k] += yps[j][k];
            }
            for (a, b) in r.iter_mut().zip(&self.sens_fp[j]) {
                *a += b;
            }
        }
        self.counters.sensitivity_product_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// The consistent initial sensitivities (s(0), s'(0)) at the consistent y(0) = `y`,
    /// y'(0) = `yp`:
    /// - s(0): the initial growth state does not hold any parameter, so s_P(0) = 0; the
    ///   algebraic part (the elastic unknowns, z and d) moves with the t = 0 equilibrium:
    ///   s_W(0) = −A⁻¹ F_p,W, A the algebraic block of F_y (one back-substitution per
    ///   parameter with the factored block; zero for η0, Γ, δ, which no algebraic row holds);
    /// - s'(0): on the growth rows s'_P = −(F_y s + F_p)_P; on the algebraic rows the
    ///   derivative in time of s_W(t) = −A(y(t))⁻¹ (F_p,W(y(t)) + C(y(t)) s_P(t)), the
    ///   algebraic sensitivities along the start of the run. For η0, Γ, δ (F_p,W = 0,
    ///   s_W(0) = 0) that is the linearised A s'_W = −C s'_P, as in
    ///   [`CoupledDae::derivative`]. For the model's parameters it also holds the
    ///   second-order terms (∂F_y/∂t) s and ∂F_p/∂t, taken by the one-sided difference
    ///   (−3 s_W(0) + 4 s_W(δ) − s_W(2δ)) / 2δ along y(t) = y + t y', s_P(t) = t s'_P
    ///   (second order: the t² terms those lines leave out cancel in it). IDAS's residual
    ///   holds no s'_W, but its first predictor does: with the sensitivities in the error
    ///   test, the linearised s'_W (which left those terms out) failed the first step's test
    ///   down to h = 1e-13 for material.C at rtol 1e-10 (docs/MODEL.md §10). The border d
    ///   keeps the linearised value: its derivative jumps where the bracketing pair changes,
    ///   and it is outside the error test.
    pub fn initial_sensitivities(
        &mut self,
        y: &[f64],
        yp: &[f64],
    ) -> Result<InitialSensitivities, DaeError> {
        let n_p = self.n_p;
        let params = self.sens_params.clone();
        if params.iter().all(|p| p.is_growth()) {
            return self.linearised_sensitivities(y);
        }
        // δ moves no unknown by more than 1e-5 of the largest's size: the difference's
        // truncation (δ²) and round-off (ε/δ) errors both near 1e-10 relative.
        let size = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let speed = yp.iter().fold(0.0_f64, |m, v| m.max(v.abs())) / size;
        if !(speed.is_finite() && speed > 0.0) {
            return self.linearised_sensitivities(y);
        }
        let delta = 1e-5 / speed;
        let (s0, mut sp0) = self.linearised_sensitivities(y)?;
        let sp_p: Vec<Vec<f64>> = sp0.iter().map(|v| v[..n_p].to_vec()).collect();
        let later: Vec<Vec<Vec<f64>>> = [1.0, 2.0]
            .into_iter()
            .map(|k| self.algebraic_sensitivities(y, yp, &sp_p, k * delta))
            .collect::<Result<_, _>>()?;
        // Leave the system as the caller had it: assembled at y (with its parameter rows).
        self.linearised_sensitivities(y)?;
        let d = self.d();
        for (j, param) in params.iter().enumerate() {
            if param.is_growth() {
                continue;
            }
            for i in n_p..self.len() {
                if i == d {
                    continue;
                }
                let (a, b, c) = (s0[j][i], later[0][j][i - n_p], later[1][j][i - n_p]);
                sp0[j][i] = (-3.0 * a + 4.0 * b - c) / (2.0 * delta);
            }
        }
        Ok((s0, sp0))
    }

    /// s_W at time `t` of the start: at y + t y', with s_P = t s'_P (`sp_p`, one per
    /// parameter), the algebraic rows' sensitivities −A⁻¹ (F_p,W + C s_P) there.
    fn algebraic_sensitivities(
        &mut self,
        y: &[f64],
        yp: &[f64],
        sp_p: &[Vec<f64>],
        t: f64,
    ) -> Result<Vec<Vec<f64>>, DaeError> {
        let (n, n_p) = (self.len(), self.n_p);
        let params = self.sens_params.clone();
        let y_t: Vec<f64> = y.iter().zip(yp).map(|(a, b)| a + t * b).collect();
        self.assemble(0.0, &y_t)?;
        let mut schur = SchurSolver::new(&self.jac, n_p, true, Reduced::Band)?;
        schur.factor_algebraic(&self.jac)?;
        let mut fp = vec![vec![0.0; n]; params.len()];
        {
            let mut outs: Vec<&mut [f64]> = fp.iter_mut().map(|v| v.as_mut_slice()).collect();
            self.parameter_residuals(&y_t, &params, &mut outs)?;
        }
        let mut out = Vec::with_capacity(params.len());
        for (fpj, spj) in fp.iter().zip(sp_p) {
            let s_p: Vec<f64> = spj.iter().map(|v| t * v).collect();
            let mut w = vec![0.0; n - n_p];
            schur.solve_algebraic_with(&s_p, &fpj[n_p..], &mut w)?;
            out.push(w);
        }
        Ok(out)
    }

    /// s(0) and s'(0) with the algebraic s' from the linearised constraints A s'_W = −C s'_P
    /// ([`CoupledDae::initial_sensitivities`]), the system left assembled at `y`.
    fn linearised_sensitivities(&mut self, y: &[f64]) -> Result<InitialSensitivities, DaeError> {
        let (n, n_p) = (self.len(), self.n_p);
        let params = self.sens_params.clone();
        self.assemble(0.0, y)?;
        let mut schur = SchurSolver::new(&self.jac, n_p, true, Reduced::Band)?;
        schur.factor_algebraic(&self.jac)?;
        let mut fp = vec![vec![0.0; n]; params.len()];
        {
            let mut outs: Vec<&mut [f64]> = fp.iter_mut().map(|v| v.as_mut_slice()).collect();
            self.parameter_residuals(y, &params, &mut outs)?;
        }
        let (mut s0, mut sp0) = (Vec::with_capacity(params.len()), Vec::new());
        let zero_p = vec![0.0; n_p];
        let mut js = vec![0.0; n];
        for fpj in &fp {
            let mut s = vec![0.0; n];
            if fpj[n_p..].iter().any(|&v| v != 0.0) {
                schur.solve_algebraic_with(&zero_p, &fpj[n_p..], &mut s[n_p..])?;
            }
            self.jac.mul(&s, &mut js);
            let mut sp = vec![0.0; n];
            for k in 0..n_p {
                sp[k] = -(js[k] + fpj[k]);
            }
            let (p_dot, w_dot) = sp.split_at_mut(n_p);
            schur.solve_algebraic(p_dot, w_dot)?;
            s0.push(s);
            sp0.push(sp);
        }
        Ok((s0, sp0))
    }

    /// The local state (r, θ, z, α_s) of every point. Their derivatives in the windows come
    /// from [`CoupledDae::node_grads`] (nodes) and [`CoupledDae::assemble_z_rows`]
    /// (midpoints, which share the slopes' derivatives with the z rows).
    fn locals(&self, y: &[f64], local: &mut Vec<Local>) {
        let disc = self.sys.elastic.discretisation();
        let ev = disc.evaluations();
        let at = |e: &PointEval, r: f64, z: f64| Local {
            r,
            z,
            alpha_s: e.alpha_s,
            sin_theta: e.sin_theta,
            cos_theta: e.cos_theta,
        };
        let at_node = |e: &PointEval, node: usize| {
            let w = self.n_p + NW * node;
            at(e, y[w + R], y[w + Z])
        };
        local.clear();
        local.extend(self.sites.iter().map(|&site| match site {
            Site::Left(i) => at_node(ev.left(i), i),
            Site::Right(i) => at_node(ev.right(i), i + 1),
            Site::Mid(i) => at(ev.mid(i), ev.y_mid(i)[R], self.z_mid_value(y, disc, ev, i)),
        }));
    }

    /// The derivatives of node point k's (r, θ, z, α_s) in its window: r, θ, z are its
    /// node's own unknowns, α_s moves with r, t_s and the point's data. The growth rows use
    /// the few numbers directly ([`NodeGrads`]); this full form is the border row's.
    fn node_grads(&self, k: usize) -> [Grad; 4] {
        let n = self.node_grad(k);
        let mut g = [Grad::default(); 4];
        g[0].w[n.off + R] = 1.0;
        g[1].w[n.off + THETA] = 1.0;
        g[2].w[n.off + Z] = 1.0;
        g[3].w[n.off + R] = n.alpha_s_r;
        g[3].w[n.off + TS] = n.alpha_s_ts;
        g[3].p[n.slot] = n.alpha_s_data;
        g
    }

    /// Node point k's [`NodeGrads`]; panics at a midpoint.
    fn node_grad(&self, k: usize) -> NodeGrads {
        let ev = self.sys.elastic.discretisation().evaluations();
        let (slot, e, off) = match self.sites[k] {
            Site::Left(i) => (L, ev.left(i), 0),
            Site::Right(i) => (RT, ev.right(i), NW),
            Site::Mid(_) => unreachable!("a midpoint's derivatives are stored"),
        };
        NodeGrads {
            slot,
            off,
            alpha_s_r: e.alpha_s_r,
            alpha_s_ts: e.alpha_s_ts,
            alpha_s_data: self.derivs[k].alpha_s,
        }
    }

    /// The derivatives of point k's local state in its window (a midpoint's from `mids`).
    fn point_grads(&self, k: usize, mids: &[[Grad; 4]]) -> [Grad; 4] {
        match self.sites[k] {
            Site::Mid(i) => mids[i],
            _ => self.node_grads(k),
        }
    }

    /// z at interval i's midpoint, from the cubic Hermite through its ends (the slopes
    /// −γ α_s sin θ from inside the interval).
    fn z_mid_value(&self, y: &[f64], disc: &Discretisation, ev: &Evaluations, i: usize) -> f64 {
        let h = disc.mesh.step(i);
        let (el, er) = (ev.left(i), ev.right(i));
        let wl = -disc.data.above[i].gamma * el.alpha_s * el.sin_theta;
        let wr = -disc.data.below[i + 1].gamma * er.alpha_s * er.sin_theta;
        0.5 * (y[self.wcol(i, Z)] + y[self.wcol(i + 1, Z)]) + h / 8.0 * (wl - wr)
    }

    /// The derivatives of dz/dΣ = −γ α_s sin θ in the window at interval i's end `slot` (L
    /// or RT) or midpoint (M, through y_m: `mid` is the interval's [`MidMap`]).
    fn slope(&self, disc: &Discretisation, i: usize, slot: usize, mid: Option<&MidMap>) -> Grad {
        let ev = disc.evaluations();
        let (e, mp, off) = match slot {
            L => (ev.left(i), &disc.data.above[i], Some(0)),
            RT => (ev.right(i), &disc.data.below[i + 1], Some(NW)),
            _ => (ev.mid(i), &disc.data.mid[i], None),
        };
        let (sn, cs) = (e.sin_theta, e.cos_theta);
        let (g, a) = (mp.gamma, e.alpha_s);
        // ∂w/∂y at the point, and ∂w/∂(ρ, γ_s) of its own data.
        let mut dy = Vec5::zeros();
        dy[R] = -g * e.alpha_s_r * sn;
        dy[THETA] = -g * a * cs;
        dy[TS] = -g * e.alpha_s_ts * sn;
        let dd = self.derivs[self.window_points(i)[slot].expect("the slot's point exists")];
        let dp = [-g * sn * dd.alpha_s[0], -sn * (a + g * dd.alpha_s[1])];
        let mut grad = Grad::default();
        match off {
            Some(o) => {
                for c in 0..NY {
                    grad.w[o + c] = dy[c];
                }
                grad.p[slot] = dp;
            }
            None => {
                let map = mid.expect("a midpoint's slope goes through y_m");
                map.apply(&dy, &mut grad);
                grad.p[M] = dp;
            }
        }
        grad
    }

    /// Interval i's [`MidMap`] (Hermite–Simpson).
    fn mid_map(&self, i: usize) -> MidMap<'_> {
        let disc = self.sys.elastic.discretisation();
        let ev = disc.evaluations();
        let h = disc.mesh.step(i);
        let id = Mat5::identity();
        let dl = 0.5 * id + (h / 8.0) * ev.left(i).jac;
        let dr = 0.5 * id - (h / 8.0) * ev.right(i).jac;
        let pts = &self.sys.points;
        MidMap {
            h,
            dlt: dl.transpose(),
            drt: dr.transpose(),
            fl: &self.derivs[pts.above[i]],
            fr: &self.derivs[pts.below[i + 1]],
        }
    }

    /// The derivatives of interval i's midpoint's r, θ and α_s in its window (z's, out[2], are
    /// the caller's).
    fn mid_grads(&self, i: usize, map: &MidMap, out: &mut [Grad; 4]) {
        let e = self.sys.elastic.discretisation().evaluations().mid(i);
        let unit = |c: usize| {
            let mut v = Vec5::zeros();
            v[c] = 1.0;
            v
        };
        map.apply(&unit(R), &mut out[0]);
        map.apply(&unit(THETA), &mut out[1]);
        let mut ga_y = Vec5::zeros();
        ga_y[R] = e.alpha_s_r;
        ga_y[TS] = e.alpha_s_ts;
        map.apply(&ga_y, &mut out[3]);
        out[3].p[M] = self.derivs[self.sys.points.mid[i]].alpha_s;
    }

    /// The retina, the stimulus and the rates at every point, and the crossing of φ_max
    /// they read beyond it; with `deriv`, their derivatives in each point's
    /// (r, θ, z, α_s, ρ, γ_s) and d.
    fn point_rates(
        &self,
        y: &[f64],
        local: &[Local],
        mut deriv: Option<&mut Vec<RateDeriv>>,
        out: &mut Vec<PointRates>,
    ) -> Option<Crossing> {
        let pts = &self.sys.points;
        let law = self.sys.points_law();
        let blue = self.sys.blue();
        let w = self.sys.kink_width();
        let d_unknown = y[self.d()];
        out.clear();
        if let Some(dv) = deriv.as_deref_mut() {
            dv.clear();
        }
        for (k, s) in local.iter().enumerate() {
            let (rho, gam) = (y[NP * k], y[NP * k + 1]);
            let zeta = pts.zeta(k, &y[..self.n_p]);
            let ht = zeta * rho / (s.alpha_s * s.r);
            let (sn, cs) = (s.sin_theta, s.cos_theta);
            let (zr, rr) = (s.z - 0.5 * ht * cs, s.r - 0.5 * ht * sn);
            let g = blue.depth_gradient(zr, rr);
            out.push(PointRates {
                depth: g.depth,
                angle: g.angle,
                ..Default::default()
            });
            if let Some(dv) = deriv.as_deref_mut() {
                // h_t = ζ ρ / (α_s r), ζ = ζ(ρ, γ_s): ∂h_t/∂(r, θ, z, α_s, ρ, γ_s).
                let [z_rho, z_gam] = zeta_partials(law, rho, zeta, gam);
                let dht = [
                    -ht / s.r,
                    0.0,
                    0.0,
                    -ht / s.alpha_s,
                    ht / rho + ht / zeta * z_rho,
                    ht / zeta * z_gam,
                ];
                let mut dz_ret = dht.map(|v| -0.5 * cs * v);
                let mut dr_ret = dht.map(|v| -0.5 * sn * v);
                dz_ret[2] += 1.0;
                dz_ret[1] += 0.5 * ht * sn;
                dr_ret[0] += 1.0;
                dr_ret[1] -= 0.5 * ht * cs;
                let mut rd = RateDeriv::default();
                for q in 0..6 {
                    rd.depth[q] = g.depth_z * dz_ret[q] + g.depth_r * dr_ret[q];
                    rd.angle[q] = g.angle_z * dz_ret[q] + g.angle_r * dr_ret[q];
                }
                dv.push(rd);
            }
        }
        // Beyond φ_max the depth is the unknown d (docs/MODEL.md §6).
        let crossing = self.crossing_depth(out);
        let has_crossing = crossing.is_some();
        for (k, pr) in out.iter_mut().enumerate() {
            let s = &local[k];
            let (rho, gam) = (y[NP * k], y[NP * k + 1]);
            pr.beyond = has_crossing && pr.angle >= blue.phi_max();
            let depth = if pr.beyond { d_unknown } else { pr.depth };
            let (dr, da) = (s.r - rho, s.alpha_s - 1.0);
            let ((gv, gv_slope), (pr_, pr_slope), (pa, pa_slope)) = (
                positive_smooth(depth, w),
                positive_smooth(dr, w),
                positive_smooth(da, w),
            );
            pr.g_v = gv;
            let cap = pts.capacity[k];
            pr.eta = cap * pr.g_v;
            pr.rho = pr.eta * pr_;
            pr.gamma = pr.eta * gam * pa;
            pr.per_capacity = [pr.g_v * pr_, pr.g_v * gam * pa];
            if let Some(dv) = deriv.as_deref_mut() {
                let rd = &mut dv[k];
                // ∂g_v/∂(local) and ∂g_v/∂d: the slope of the branch the value took.
                let gv_local: [f64; 6] = if pr.beyond {
                    [0.0; 6]
                } else {
                    rd.depth.map(|v| gv_slope * v)
                };
                let gv_d = if pr.beyond { gv_slope } else { 0.0 };
                for q in 0..6 {
                    rd.rate[0][q] = cap * gv_local[q] * pr_;
                    rd.rate[1][q] = cap * gv_local[q] * gam * pa;
                }
                rd.rate[0][0] += pr.eta * pr_slope;
                rd.rate[0][4] -= pr.eta * pr_slope;
                rd.rate[1][3] += pr.eta * gam * pa_slope;
                rd.rate[1][5] += pr.eta * pa;
                rd.rate_d = [cap * gv_d * pr_, cap * gv_d * gam * pa];
            }
        }
        crossing
    }

    /// Rates (and, with `deriv`, their derivatives) that are not finite fail the evaluation
    /// at their point, as an elastic evaluation does, so that IDA cuts the step or the run
    /// says where; they would otherwise spread NaN through the Newton matrix.
    fn check_finite(
        &self,
        rates: &[PointRates],
        deriv: Option<&[RateDeriv]>,
    ) -> Result<(), RhsError> {
        // No allocation and no branch per value: this runs at every residual and assembly.
        let bad = |k: usize| {
            let pr = &rates[k];
            let own = all_finite(&[pr.rho, pr.gamma, pr.depth]);
            let derivatives = deriv.is_none_or(|rd| {
                let d = &rd[k];
                all_finite(d.rate.as_flattened())
                    & all_finite(&d.rate_d)
                    & all_finite(&d.depth)
                    & all_finite(&d.angle)
            });
            !(own && derivatives)
        };
        match (0..rates.len()).find(|&k| bad(k)) {
            None => Ok(()),
            Some(k) => {
                let node = match self.sites[k] {
                    Site::Left(i) | Site::Mid(i) => i,
                    Site::Right(i) => i + 1,
                };
                Err(RhsError::Evaluation(EvalFailure {
                    node,
                    sigma_ref: self.sys.points.sigma_ref[k],
                    why: PointError::NotFinite,
                }))
            }
        }
    }

    /// The depth of the blue surface where the retina crosses φ_max ([`super::crossing`]);
    /// None if no point reaches it.
    fn crossing_depth(&self, rates: &[PointRates]) -> Option<Crossing> {
        super::crossing::crossing(
            &self.sys.points.by_sigma,
            |k| rates[k].angle,
            |k| rates[k].depth,
            self.sys.blue().phi_max(),
        )
    }

    /// F(t, y, y') into r.
    pub fn residual(&mut self, y: &[f64], yp: &[f64], r: &mut [f64]) -> Result<(), RhsError> {
        let start = std::time::Instant::now();
        self.counters.residuals += 1;
        self.load(y)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let crossing = self.point_rates(y, &s.local, None, &mut s.rates);
        let finite = self.check_finite(&s.rates, None);
        for (k, pr) in s.rates.iter().enumerate() {
            r[NP * k] = yp[NP * k] - pr.rho;
            r[NP * k + 1] = yp[NP * k + 1] - pr.gamma;
        }
        self.scratch = s;
        finite?;
        let (n_p, m) = (self.n_p, self.m);
        let (mut f, mut dz) = (std::mem::take(&mut self.f), std::mem::take(&mut self.dz));
        let disc = self.sys.elastic.discretisation_mut();
        let res = disc
            .residual(&self.u, &mut f)
            .and_then(|_| disc.z_steps(&self.u, &mut dz));
        if let Err(e) = res {
            (self.f, self.dz) = (f, dz);
            return Err(RhsError::Evaluation(e));
        }
        let z_star = disc.edge.z;
        r[n_p..n_p + POLE_ROWS].copy_from_slice(&f[..POLE_ROWS]);
        for i in 0..m - 1 {
            let row = n_p + POLE_ROWS + NW * i;
            r[row..row + NY].copy_from_slice(&f[POLE_ROWS + NY * i..POLE_ROWS + NY * i + NY]);
            r[row + Z] = y[self.wcol(i + 1, Z)] - y[self.wcol(i, Z)] - dz[i];
        }
        let d = self.d();
        let nf = f.len();
        r[d - 3] = f[nf - 2];
        r[d - 2] = f[nf - 1];
        r[d - 1] = y[self.wcol(m - 1, Z)] - z_star;
        r[d] = y[d] - crossing.map_or(0.0, |c| c.value);
        (self.f, self.dz) = (f, dz);
        self.counters.residual_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// Assemble ∂F/∂y + c ∂F/∂y' at y into the CSR matrix.
    pub fn assemble(&mut self, c: f64, y: &[f64]) -> Result<(), DaeError> {
        self.load(y)?;
        let mut derivs = std::mem::take(&mut self.derivs);
        self.data_derivs(&mut derivs);
        self.derivs = derivs;
        self.jac.zero();
        let n_p = self.n_p;
        // The elastic rows in the elastic unknowns: the discretisation's own Jacobian.
        {
            let disc = self.sys.elastic.discretisation_mut();
            let mut sink = WSink {
                csr: &mut self.jac,
                n_p,
                m: self.m,
            };
            disc.jacobian(&self.u, &mut sink)
                .map_err(RhsError::Evaluation)?;
        }

        // The cornea's z and the border's own entry.
        let d = self.d();
        self.jac.add(d - 1, self.wcol(self.m - 1, Z), 1.0);
        self.jac.add(d, d, 1.0);
        self.assemble_data_columns();
        let mut grads = std::mem::take(&mut self.grads);
        let mids = if self.hermite_simpson { self.m - 1 } else { 0 };
        grads.resize(mids, [Grad::default(); 4]);
        self.assemble_z_rows(&mut grads);
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let crossing = self.point_rates(y, &s.local, Some(&mut s.rd), &mut s.rates);
        let finite = self.check_finite(&s.rates, Some(&s.rd));
        if finite.is_ok() {
            self.assemble_growth_rows(c, &grads, &s.rd, &s.rates);
            self.assemble_border(&grads, &s.rd, crossing);
        }
        (self.grads, self.scratch) = (grads, s);
        finite?;
        match self.jac.take_outside() {
            0 => Ok(()),
            k => Err(DaeError::Linear(LinalgError::OutsidePattern(k))),
        }
    }

    /// Add a window gradient `g` of interval i to row `row`; `half` restricts the W part
    /// to the nodes the row's pattern holds (0: node i, 1: node i+1, None: both).
    fn add_grad(&mut self, row: usize, i: usize, g: &Grad, half: Option<usize>) {
        let w0 = self.wcol(i, 0);
        match half {
            None => self.jac.add_span(row, w0, &g.w),
            Some(h) => self
                .jac
                .add_span(row, w0 + NW * h, &g.w[NW * h..NW * h + NW]),
        }
        // Every column the row's pattern holds gets its addition, zero or not: the matrix
        // replays the last assembly's positions in call order (`Csr`'s trail), and an
        // addition skipped because a value happened to vanish (a growth point switching off
        // at a kink) would shift every later one into a search (measured: 7 000 of 21 700).
        // A half row holds its own point's columns only.
        for (slot, k) in self.window_points(i).into_iter().enumerate() {
            if let Some(k) = k.filter(|_| half.is_none_or(|h| h == slot)) {
                self.jac.add_span(row, NP * k, &g.p[slot]);
            }
        }
    }

    /// Each point's ∂f/∂(ρ, γ_s) and ∂α_s/∂(ρ, γ_s), from the evaluation at its site (the
    /// interval end or midpoint it belongs to; a node shared by two intervals has one).
    fn data_derivs(&self, out: &mut Vec<DataDeriv>) {
        let disc = self.sys.elastic.discretisation();
        let (ev, data, law) = (disc.evaluations(), &disc.data, self.sys.points_law());
        let y = |j: usize| Vec5::from_column_slice(&self.u[NY * j..NY * j + NY]);
        out.clear();
        out.extend(self.sites.iter().map(|&site| match site {
            Site::Left(i) => data_deriv(law, &data.above[i], &y(i), ev.left(i)),
            Site::Right(i) => data_deriv(law, &data.below[i + 1], &y(i + 1), ev.right(i)),
            Site::Mid(i) => data_deriv(law, &data.mid[i], ev.y_mid(i), ev.mid(i)),
        }));
    }

    /// The elastic rows' derivatives in the growth data: the pole rows in above[0]'s data
    /// (σ_ε = ε γ_s and α_s there), each interval's rows in its points' data. Added as they
    /// are computed (no list per call), in the order the trail replays.
    fn assemble_data_columns(&mut self) {
        let n_p = self.n_p;
        // Pole: f0 = r − σ_ε α_s, f1 = θ − σ_ε α_s κ, σ_ε = ε γ_s.
        let k0 = self.sys.points.above[0];
        let d_f0 = {
            let disc = self.sys.elastic.discretisation();
            let (mp0, e0, dd0) = (
                &disc.data.above[0],
                disc.evaluations().left(0),
                &self.derivs[k0],
            );
            let (eps, se) = (disc.mesh.nodes[0], mp0.sigma);
            [
                -se * dd0.alpha_s[0],
                -eps * e0.alpha_s - se * dd0.alpha_s[1],
            ]
        };
        let y0 = self.u[0];
        self.jac.add_span(n_p, NP * k0, &d_f0);
        self.jac
            .add_span(n_p + 1, NP * k0, &[d_f0[0] * y0, d_f0[1] * y0]);
        for i in 0..self.m - 1 {
            for (k, dv) in self.interval_data_columns(i).into_iter().flatten() {
                for a in 0..NY {
                    self.jac
                        .add_span(self.interval_row(i, a), NP * k, &[dv[0][a], dv[1][a]]);
                }
            }
        }
    }

    /// Interval i's rows' derivatives in the data (ρ, γ_s) of each of its points (ends, and
    /// a midpoint): the scheme's weights on ∂f/∂(ρ, γ_s), through y_m for Hermite–Simpson.
    fn interval_data_columns(&self, i: usize) -> [Option<(usize, [Vec5; 2])>; 3] {
        let disc = self.sys.elastic.discretisation();
        let h = disc.mesh.step(i);
        let [pl, pr, pm] = self.window_points(i);
        let (pl, pr) = (
            pl.expect("every interval has ends"),
            pr.expect("every interval has ends"),
        );
        let (fl, fr) = (&self.derivs[pl], &self.derivs[pr]);
        let mut cols: [Option<(usize, [Vec5; 2])>; 3] = [None; 3];
        match self.hermite_simpson {
            false => {
                cols[0] = Some((pl, fl.f.map(|v| -0.5 * h * v)));
                cols[1] = Some((pr, fr.f.map(|v| -0.5 * h * v)));
            }
            true => {
                let jm = &disc.evaluations().mid(i).jac;
                let pm = pm.expect("Hermite–Simpson has midpoints");
                let fm = &self.derivs[pm];
                cols[0] = Some((pl, fl.f.map(|v| -(h / 6.0) * v - (h * h / 12.0) * (jm * v))));
                cols[1] = Some((pr, fr.f.map(|v| -(h / 6.0) * v + (h * h / 12.0) * (jm * v))));
                cols[2] = Some((pm, fm.f.map(|v| -(2.0 * h / 3.0) * v)));
            }
        }
        cols
    }

    /// The z rows: z_{i+1} − z_i − Δz_i with Δz_i the scheme's quadrature of the slopes;
    /// and, from the same slopes, each midpoint's derivatives into `grads` (its z is the
    /// cubic Hermite through the interval's ends).
    fn assemble_z_rows(&mut self, grads: &mut [[Grad; 4]]) {
        for i in 0..self.m - 1 {
            let mid = self.hermite_simpson.then(|| &mut grads[i]);
            let g = self.z_row(i, mid);
            self.add_grad(self.interval_row(i, Z), i, &g, None);
        }
    }

    /// Interval i's z row's gradient in its window; with `mid`, its midpoint's derivatives.
    fn z_row(&self, i: usize, mid: Option<&mut [Grad; 4]>) -> Grad {
        let disc = self.sys.elastic.discretisation();
        let h = disc.mesh.step(i);
        let map = self.hermite_simpson.then(|| self.mid_map(i));
        let gl = self.slope(disc, i, L, None);
        let gr = self.slope(disc, i, RT, None);
        let mut g = Grad::default();
        g.w[Z] = -1.0;
        g.w[NW + Z] = 1.0;
        if let Some(map) = &map {
            let gm = self.slope(disc, i, M, Some(map));
            g.axpy(-h / 6.0, &gl);
            g.axpy(-4.0 * h / 6.0, &gm);
            g.axpy(-h / 6.0, &gr);
        } else {
            g.axpy(-0.5 * h, &gl);
            g.axpy(-0.5 * h, &gr);
        }
        if let (Some(map), Some(out)) = (&map, mid) {
            // z_m = (z_i + z_{i+1})/2 + h/8 (w_L − w_R).
            let gz = &mut out[2];
            *gz = Grad::default();
            gz.w[Z] = 0.5;
            gz.w[NW + Z] = 0.5;
            gz.axpy(h / 8.0, &gl);
            gz.axpy(-h / 8.0, &gr);
            self.mid_grads(i, map, out);
        }
        g
    }

    /// The growth rows: c I − ∂rates/∂y, through each point's local state.
    fn assemble_growth_rows(
        &mut self,
        c: f64,
        grads: &[[Grad; 4]],
        rd: &[RateDeriv],
        _rates: &[PointRates],
    ) {
        let d = self.d();
        for k in 0..self.sites.len() {
            let site = self.sites[k];
            let i = site.interval();
            let (half, own) = match site {
                Site::Left(_) => (Some(0), L),
                Site::Right(_) => (Some(1), RT),
                Site::Mid(_) => (None, M),
            };
            let rdk = &rd[k];
            let node = half.map(|_| self.node_grad(k));
            for a in 0..2 {
                let row = NP * k + a;
                let dr = &rdk.rate[a];
                // −Σ_q dr_q ∂local_q, summed in q order, over the part of the window the
                // row's pattern holds (a node's half and its own point, or all of it).
                let cols = match half {
                    Some(h) => NW * h..NW * h + NW,
                    None => 0..2 * NW,
                };
                let mut g = Grad::default();
                match &node {
                    Some(n) => {
                        for c in cols {
                            g.w[c] = neg_combination(dr, n.w(c));
                        }
                        for e in 0..2 {
                            g.p[own][e] = neg_combination(dr, [0.0, 0.0, 0.0, n.alpha_s_data[e]]);
                        }
                    }
                    None => {
                        let gk = &grads[site.interval()];
                        for c in cols {
                            g.w[c] = neg_combination(dr, gk.each(|x| x.w[c]));
                        }
                        for slot in [L, RT, M] {
                            for e in 0..2 {
                                g.p[slot][e] = neg_combination(dr, gk.each(|x| x.p[slot][e]));
                            }
                        }
                    }
                }
                g.p[own][0] -= dr[4];
                g.p[own][1] -= dr[5];
                g.p[own][a] += c;
                self.add_grad(row, i, &g, half);
                // Zero or not (see add_grad): d is in every growth row's pattern.
                self.jac.add(row, d, -rdk.rate_d[a]);
            }
        }
    }

    /// The border row: d − D*(y), D* the depth interpolated at φ_max.
    fn assemble_border(
        &mut self,
        grads: &[[Grad; 4]],
        rd: &[RateDeriv],
        crossing: Option<Crossing>,
    ) {
        let Some(cr) = crossing else {
            return;
        };
        let d = self.d();
        // ∂D* = Σ_i L_i (∂d_i − p'(φ_i) ∂φ_i) over the interpolant's points.
        for &(k, wgt, slope) in cr.points() {
            let mut g = Grad::default();
            let own = match self.sites[k] {
                Site::Left(_) => L,
                Site::Right(_) => RT,
                Site::Mid(_) => M,
            };
            let gk = self.point_grads(k, grads);
            for q in 0..4 {
                g.axpy(-wgt * (rd[k].depth[q] - slope * rd[k].angle[q]), &gk[q]);
            }
            for (s, q) in [(0usize, 4usize), (1, 5)] {
                g.p[own][s] -= wgt * (rd[k].depth[q] - slope * rd[k].angle[q]);
            }
            let i = self.sites[k].interval();
            self.add_grad(d, i, &g, None);
        }
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
        let u: Vec<f64> = (0..self.m)
            .flat_map(|i| y[self.wcol(i, 0)..self.wcol(i, NY)].to_vec())
            .collect();
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

/// Writes the discretisation's Jacobian (rows and columns of the 5-per-node elastic
/// system) into the coupled matrix's W block (6 per node).
struct WSink<'a> {
    csr: &'a mut Csr,
    n_p: usize,
    m: usize,
}

impl MatrixSink for WSink<'_> {
    fn nrows(&self) -> usize {
        NY * self.m
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        let (row, col) = (self.row(i), Self::col(j));
        self.csr.add(self.n_p + row, self.n_p + col, v);
    }

    /// A block row's columns of one node (NY of them) are consecutive in W too: one span
    /// each, instead of an addition per entry.
    fn set_block(&mut self, row0: usize, col0: usize, ncols: usize, values: &[f64]) {
        for (a, vals) in values.chunks_exact(ncols).enumerate() {
            let row = self.n_p + self.row(row0 + a);
            let mut b = 0;
            while b < ncols {
                let j = col0 + b;
                let len = (NY - j % NY).min(ncols - b);
                self.csr
                    .add_span(row, self.n_p + Self::col(j), &vals[b..b + len]);
                b += len;
            }
        }
    }
}

impl WSink<'_> {
    /// The W row of elastic row i.
    fn row(&self, i: usize) -> usize {
        let n = NY * self.m;
        if i < POLE_ROWS {
            i
        } else if i >= n - 2 {
            NW * self.m - 3 + (i + 2 - n)
        } else {
            let k = i - POLE_ROWS;
            POLE_ROWS + NW * (k / NY) + k % NY
        }
    }

    /// The W column of elastic column j.
    fn col(j: usize) -> usize {
        NW * (j / NY) + j % NY
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
