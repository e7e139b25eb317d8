//! The growth system dp/dt = G(p) (docs/MODEL.md §5–6): p holds (ρ, γ_s) at the growth points;
//! each evaluation solves the elastic problem for the shell p describes (warm-started from
//! the last solution) and turns its state into growth rates through the visual stimulus.
//!
//! Jacobian products by the implicit-function theorem. With F(u; p) = 0 the elastic
//! equations and g(u, p) the rates, G(p) = g(u*(p), p) and
//!     J v = g_p v + g_u w,   w = −F_u⁻¹ F_p v.
//! F_u is assembled and factored once per Jacobian set-up at the converged u*, so a
//! product costs one residual evaluation (F_p v, by a directional difference at fixed u*),
//! one back-substitution, and one evaluation of the rates at (u* + δw, p + δv), which gives
//! g_p v + g_u w as a single directional difference. No elastic re-solve per column.

use super::points::{GrowthPoints, NP};
use super::{GrowthParams, GrowthRow, SeriesRow};
use crate::bvp::discretisation::{EvalFailure, NY};
use crate::bvp::equations::{R, THETA};
use crate::bvp::settings::SolverSettings;
use crate::bvp::solve::{linear_spec, ElasticSolver, Solution};
use crate::bvp::BvpError;
use crate::deadline::OutOfTime;
use crate::model::growth_law;
use crate::model::params::Params;
use crate::model::rule::Vergence;
use crate::model::stimulus::{self, EyeMeasure, Focal};
use eyeshell_optics::PolarSpline;
use eyeshell_sundials::{CallbackError, Context, LinearSolver, Matrix, NVector, SundialsError};
use std::rc::Rc;

/// Newton iterations between refactorisations of the elastic Jacobian during growth.
const REFACTOR_EVERY: usize = 3;

/// What the rates saw at one point: the retina and the stimulus there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointStimulus {
    pub z_retina: f64,
    pub r_retina: f64,
    /// Depth of the blue surface behind the retina (docs/MODEL.md §6).
    pub depth_blue: f64,
    pub angle: f64,
    /// The defocus (D) there, when the rule reads it (else NaN).
    pub defocus: f64,
    /// The rule's drive (mm) at the point's own view; g_v is its positive part, beyond
    /// φ_max the drive at the crossing's.
    pub drive: f64,
    pub g_v: f64,
    pub eta: f64,
}

/// Counters of the work behind the right-hand side.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    pub rhs_evaluations: usize,
    pub bvp_solves: usize,
    pub jacobian_products: usize,
    pub jacobian_setups: usize,
}

/// Why a right-hand side could not be evaluated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RhsError {
    #[error("the elastic solve failed: {0}")]
    Elastic(BvpError),
    #[error("the growth rates cannot be evaluated at node {} (Σ = {}): {}", .0.node, crate::text::decimals6(.0.sigma_ref), .0.why)]
    Evaluation(EvalFailure),
    #[error(transparent)]
    Sundials(#[from] SundialsError),
    /// `solver.max_seconds` stopped the run (in an elastic solve or in a callback).
    #[error(transparent)]
    OutOfTime(#[from] OutOfTime),
    /// The stimulus's surfaces cannot be computed from the scene's optics keys.
    #[error("{0}")]
    Optics(crate::model::optics::OpticsKeyError),
    /// The stimulus's surfaces at a time cannot be blended from the traced ones.
    #[error(transparent)]
    Blend(#[from] crate::model::optics::BlendError),
    /// The integrated region reaches beyond where the stimulus surface is defined.
    #[error("the integrated stimulus's region reaches {}° from the pole, beyond where the stimulus surface is defined (φ_max = {}°): make it at most that", crate::text::decimals6(.max_angle.to_degrees()), crate::text::decimals6(.phi_max.to_degrees()))]
    RegionBeyondSurface { max_angle: f64, phi_max: f64 },
    /// A growth rule from outside eyeshell failed.
    #[error(transparent)]
    Rule(#[from] crate::model::rule::RuleError),
}

impl From<BvpError> for RhsError {
    fn from(e: BvpError) -> Self {
        match e {
            BvpError::OutOfTime(o) => RhsError::OutOfTime(o),
            e => RhsError::Elastic(e),
        }
    }
}

impl RhsError {
    /// How an integrator's callback reports this failure: `solver.max_seconds` stops the
    /// integrator (fatal); anything else makes it cut the step and try again (recoverable).
    pub fn to_callback(&self) -> CallbackError {
        match self {
            RhsError::OutOfTime(_) => CallbackError::Fatal(self.to_string()),
            _ => CallbackError::Recoverable(self.to_string()),
        }
    }
}

/// F_u factored at the converged state of one p, for Jacobian products.
struct Factored {
    matrix: Matrix,
    solver: LinearSolver,
    /// F(u*; p) as evaluated (≈ 0), the base of the directional difference F_p v.
    residual: Vec<f64>,
    /// The p it was factored for.
    at: Vec<f64>,
    rhs: NVector,
    x: NVector,
}

pub struct GrowthSystem {
    pub elastic: ElasticSolver,
    pub points: GrowthPoints,
    growth: GrowthParams,
    linear: crate::bvp::settings::LinearSolverKind,
    /// The last state the elastic problem was solved for, and its converged unknowns.
    solved_at: Vec<f64>,
    /// Whether `elastic.u` solves the elastic problem at `solved_at` to Newton's tolerance
    /// (false after [`GrowthSystem::adopt`]: an integrator's state, accurate to its own
    /// tolerance).
    exact: bool,
    last_good_u: Vec<f64>,
    ctx: Rc<Context>,
    factored: Option<Factored>,
    pub work: Work,
    /// What stopped the run when `solver.max_seconds` did: the integrator's own error says
    /// only that a callback failed.
    out_of_time: Option<OutOfTime>,
    /// The blue and red surfaces at the time of the last [`GrowthSystem::set_time`], when the
    /// eye's optics change with time (`None`: the surfaces of t = 0, or fixed optics), with
    /// the (real) time they were blended at.
    now: Option<(f64, PolarSpline, PolarSpline)>,
    /// The dioptre conversion of the rule's defocus (None when the rule reads none).
    vergence: Option<Vergence>,
    /// The time of the last [`GrowthSystem::set_time`]: what a rule reads as t.
    t: f64,
    /// On a schedule's clock with optics that change with age, the real time of each clock
    /// time, which the surfaces are read at ([`GrowthSystem::set_real_time`]); None: the
    /// surfaces are read at the time the integrator gives. With the last (τ, t) it gave.
    real_time: Option<(super::real_time::RealTime, (f64, f64))>,
}

/// The blue (or red) surface the stimulus reads: at the current time when the optics
/// change with it, else the growth model's own.
fn focal<'a>(
    growth: &'a GrowthParams,
    now: &'a Option<(f64, PolarSpline, PolarSpline)>,
    blue: bool,
) -> Focal<'a> {
    match (now, blue) {
        (Some((_, b, _)), true) => Focal::Computed(b),
        (Some((_, _, r)), false) => Focal::Computed(r),
        (None, true) => growth.blue_focal(),
        (None, false) => growth.red_focal(),
    }
}

impl GrowthSystem {
    pub fn new(
        params: &Params,
        solver: &SolverSettings,
        growth: &GrowthParams,
    ) -> Result<Self, RhsError> {
        Self::with_elastic(ElasticSolver::new(params, solver)?, solver, growth)
    }

    /// The growth system on a given material mesh (it must hold the scene's breakpoints), as
    /// `solver.tol` chooses it ([`super::tolerance`]).
    pub fn on_mesh(
        params: &Params,
        solver: &SolverSettings,
        growth: &GrowthParams,
        mesh: crate::mesh::Mesh,
    ) -> Result<Self, RhsError> {
        let elastic = ElasticSolver::on_mesh(params, solver, mesh)?;
        Self::with_elastic(elastic, solver, growth)
    }

    fn with_elastic(
        mut elastic: ElasticSolver,
        solver: &SolverSettings,
        growth: &GrowthParams,
    ) -> Result<Self, RhsError> {
        // Computed surfaces are traced here at most once (a resolved copy is kept as it is).
        let growth = growth.resolved().map_err(RhsError::Optics)?.into_owned();
        let growth = &growth;
        let vergence = growth.vergence().map_err(RhsError::Optics)?;
        let stimulus = &growth.stimulus;
        let phi_max = growth.blue_focal().phi_max();
        if stimulus.region == crate::model::rule::Region::Integrated
            && !(stimulus.max_angle() > 0.0 && stimulus.max_angle() <= phi_max)
        {
            return Err(RhsError::RegionBeyondSurface {
                max_angle: stimulus.max_angle(),
                phi_max,
            });
        }
        let params = elastic.params();
        elastic.solve_cold()?;
        // Successive right sides change the shell a little: modified Newton from the last
        // factorisation, refactored every 3 iterations (measured on the const scene, N = 501:
        // 0.77 → 0.63 s; refactoring every 10 iterations is slower again).
        elastic.set_jacobian_reuse(Some(REFACTOR_EVERY))?;
        let disc = elastic.discretisation();
        let points = GrowthPoints::new(&params, growth, &disc.mesh, disc.scheme);
        let last_good_u = elastic.u.clone();
        Ok(GrowthSystem {
            elastic,
            points,
            growth: growth.clone(),
            linear: solver.linear,
            solved_at: vec![],
            exact: false,
            last_good_u,
            ctx: Context::new()?,
            factored: None,
            work: Work::default(),
            out_of_time: None,
            now: None,
            vergence,
            t: 0.0,
            real_time: None,
        })
    }

    /// The growth time the next right sides are evaluated at: the stimulus's surfaces are
    /// blended for it when the eye's optics change with time (once per time; nothing to do
    /// for fixed optics, whose right side does not depend on t). On a schedule's clock
    /// ([`GrowthSystem::set_real_time`]) `t` is the clock's τ: the rule reads τ, the
    /// surfaces are those of the real time S⁻¹(τ).
    pub fn set_time(&mut self, t: f64) -> Result<(), RhsError> {
        self.t = t;
        let Some(timed) = self.growth.computed.as_ref().and_then(|c| c.timed.as_ref()) else {
            return Ok(());
        };
        let real = match self.real_time.as_mut() {
            None => t,
            Some((rt, last)) => {
                if last.0 != t {
                    *last = (t, rt.at(t));
                }
                last.1
            }
        };
        if self.now.as_ref().is_some_and(|(at, _, _)| *at == real) {
            return Ok(());
        }
        let (blue, red) = timed.at(real)?;
        self.now = Some((real, blue, red));
        Ok(())
    }

    /// Run the growth on a schedule's clock τ whose optics change with age: the surfaces
    /// become those of t = S⁻¹(τ) for the current τ, and every later
    /// [`GrowthSystem::set_time`] reads them there (None: at the time given, as without a
    /// schedule). Nothing changes for fixed optics, whose surfaces read no time.
    ///
    /// # Errors
    /// [`RhsError::Blend`] if the surfaces at S⁻¹(τ) cannot be blended.
    pub fn set_real_time(
        &mut self,
        real_time: Option<super::real_time::RealTime>,
    ) -> Result<(), RhsError> {
        let Some(rt) = real_time else {
            self.real_time = None;
            return Ok(());
        };
        self.real_time = Some((rt, (f64::NAN, f64::NAN)));
        self.set_time(self.t)
    }

    /// `f` on the growth system with its surfaces read at the times given, not through the
    /// schedule's clock: a scheduled run's outputs are recorded at the real t (what the
    /// output's surfaces, refraction and rows read), its integration runs on τ. Afterwards
    /// the surfaces are again those of the clock's τ, which the integrator's next
    /// evaluations (a consistent start's among them) read without setting it again.
    ///
    /// # Errors
    /// `f`'s, and [`RhsError::Blend`] if the surfaces at τ cannot be blended again.
    pub fn on_real_clock<R>(
        &mut self,
        f: impl FnOnce(&mut Self) -> Result<R, super::ObserverError>,
    ) -> Result<R, super::ObserverError> {
        let Some(real_time) = self.real_time.take() else {
            return f(self);
        };
        let tau = self.t;
        let out = f(self);
        self.real_time = Some(real_time);
        self.set_time(tau)?;
        out
    }

    /// The number of growth unknowns.
    pub fn len(&self) -> usize {
        NP * self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Solve the elastic problem for the shell in state `p` (nothing to do if it was the last;
    /// from the adopted unknowns if `p` was adopted).
    pub fn solve_elastic(&mut self, p: &[f64]) -> Result<(), RhsError> {
        let same = self.solved_at.as_slice() == p;
        if same && self.exact {
            return Ok(());
        }
        if !same {
            self.load_data(p);
        }
        self.solved_at.clear();
        self.work.bvp_solves += 1;
        // An adopted state is accurate to the integrator's tolerance, and the factorisation
        // kept for modified Newton may be from long ago: polish it by exact Newton.
        let polishing = same;
        if polishing {
            self.elastic.set_jacobian_reuse(None)?;
        }
        let solved = self.elastic.newton();
        if polishing {
            self.elastic.set_jacobian_reuse(Some(REFACTOR_EVERY))?;
        }
        if let Err(e) = solved {
            // Start the next attempt (a shorter step) from the last converged state.
            self.elastic.u.clone_from(&self.last_good_u);
            return Err(self.note(e.into()));
        }
        self.last_good_u.clone_from(&self.elastic.u);
        self.solved_at.extend_from_slice(p);
        self.exact = true;
        Ok(())
    }

    /// Check the run's `solver.max_seconds` (one deadline, set when the system was made),
    /// reached `place` if it has passed.
    pub fn check_deadline(&mut self, place: impl FnOnce() -> String) -> Result<(), RhsError> {
        let checked = self.elastic.deadline().check(place);
        checked.map_err(|o| self.note(o.into()))
    }

    /// Remember `e` if it is the deadline's, for [`Self::take_out_of_time`].
    fn note(&mut self, e: RhsError) -> RhsError {
        if let RhsError::OutOfTime(o) = &e {
            self.out_of_time.get_or_insert_with(|| o.clone());
        }
        e
    }

    /// Where `solver.max_seconds` stopped the run, if it did (once).
    pub fn take_out_of_time(&mut self) -> Option<OutOfTime> {
        self.out_of_time.take()
    }

    /// G(p): solve the elastic problem, then the growth rates.
    pub fn rhs(&mut self, p: &[f64], out: &mut [f64]) -> Result<(), RhsError> {
        self.work.rhs_evaluations += 1;
        self.solve_elastic(p)?;
        let u = std::mem::take(&mut self.elastic.u);
        let r = self.rates(&u, p, out, None);
        self.elastic.u = u;
        r
    }

    /// Rates g(u, p) with the discretisation's data already set to p. With `detail`, also
    /// what the stimulus saw at each point.
    fn rates(
        &mut self,
        u: &[f64],
        p: &[f64],
        out: &mut [f64],
        detail: Option<&mut Vec<PointStimulus>>,
    ) -> Result<(), RhsError> {
        let disc = self.elastic.discretisation_mut();
        let quad = disc.quadratures(u).map_err(RhsError::Evaluation)?;
        let (m, pts) = (disc.mesh.len(), &self.points);
        let ev = disc.evaluations();
        let n_pts = pts.len();
        // r, θ, z, α_s at every point (a point shared by two slots takes either: equal).
        let mut local = vec![(0.0, 0.0, 0.0, 0.0); n_pts];
        for i in 0..m {
            let (r, th, z) = (u[NY * i + R], u[NY * i + THETA], quad.z[i]);
            if i < m - 1 {
                local[pts.above[i]] = (r, th, z, ev.left(i).alpha_s);
            }
            if i > 0 {
                local[pts.below[i]] = (r, th, z, ev.right(i - 1).alpha_s);
            }
        }
        if !pts.mid.is_empty() {
            for i in 0..m - 1 {
                let ym = ev.y_mid(i);
                local[pts.mid[i]] = (
                    ym[R],
                    ym[THETA],
                    quad.z_mid(i, disc.mesh.step(i)),
                    ev.mid(i).alpha_s,
                );
            }
        }
        // The retina (inner face), what it sees, and the rule's drive there.
        let viewer = self.viewer();
        let t = self.t;
        let places: Vec<(f64, (f64, f64))> = (0..n_pts)
            .map(|k| {
                let (r, th, z, a) = local[k];
                let rho = p[NP * k];
                let h = pts.zeta(k, p) / (a * r / rho);
                (pts.sigma_ref[k], stimulus::retina(z, r, h, th))
            })
            .collect();
        let (mut seen, mut drives) = (Vec::new(), Vec::new());
        viewer
            .drives(
                self.growth.stimulus.rule().as_ref(),
                places.into_iter(),
                t,
                false,
                &mut seen,
                &mut drives,
            )
            .map_err(RhsError::Rule)?;
        let mut stim: Vec<PointStimulus> = seen
            .iter()
            .zip(&drives)
            .map(|(s, d)| PointStimulus {
                z_retina: s.z,
                r_retina: s.r,
                depth_blue: s.depth,
                angle: s.angle,
                defocus: s.defocus,
                drive: d.value,
                ..Default::default()
            })
            .collect();
        let phi_max = viewer.blue.phi_max();
        let integrated = integrated_drive(&self.growth.stimulus, pts, &stim);
        let drive_at_max = drive_at_angle(pts, &stim, phi_max);
        for (k, s) in stim.iter_mut().enumerate() {
            let d = if let Some(total) = integrated {
                total
            } else if s.angle < phi_max {
                s.drive
            } else {
                drive_at_max.unwrap_or(s.drive)
            };
            let w = self.growth.kink_width;
            s.g_v = growth_law::positive_smooth(d, w).0;
            s.eta = pts.capacity[k] * s.g_v;
            let (r, _, _, a) = local[k];
            out[NP * k] = growth_law::rho_rate(s.eta, r, p[NP * k], w);
            out[NP * k + 1] = growth_law::gamma_rate(s.eta, p[NP * k + 1], a, w);
        }
        if let Some(d) = detail {
            *d = stim;
        }
        Ok(())
    }
}

impl GrowthSystem {
    /// Assemble and factor F_u at the converged elastic state for `p` (a Jacobian set-up).
    pub fn jac_setup(&mut self, p: &[f64]) -> Result<(), RhsError> {
        self.solve_elastic(p)?;
        self.work.jacobian_setups += 1;
        let n = self.elastic.discretisation().len();
        if self.factored.is_none() {
            let spec = linear_spec(self.elastic.discretisation(), self.linear);
            let (matrix, solver) = LinearSolver::for_spec(&self.ctx, n, &spec)?;
            let (rhs, x) = (NVector::new(&self.ctx, n)?, NVector::new(&self.ctx, n)?);
            self.factored = Some(Factored {
                matrix,
                solver,
                residual: vec![0.0; n],
                at: vec![],
                rhs,
                x,
            });
        }
        let f = self.factored.as_mut().expect("made above");
        let u = self.elastic.u.clone();
        let disc = self.elastic.discretisation_mut();
        f.matrix.zero();
        disc.jacobian(&u, &mut f.matrix.view_mut())
            .map_err(RhsError::Evaluation)?;
        f.solver.setup(&mut f.matrix)?;
        disc.residual(&u, &mut f.residual)
            .map_err(RhsError::Evaluation)?;
        f.at.clear();
        f.at.extend_from_slice(p);
        Ok(())
    }

    /// J v = dG/dp · v at `p`, where `fy` = G(p), through the implicit-function theorem.
    pub fn jac_times(
        &mut self,
        p: &[f64],
        fy: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) -> Result<(), RhsError> {
        if self.factored.as_ref().is_none_or(|f| f.at.as_slice() != p) {
            self.jac_setup(p)?;
        }
        self.work.jacobian_products += 1;
        let v_max = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        if v_max == 0.0 {
            out.fill(0.0);
            return Ok(());
        }
        let p_max = p.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        let delta = f64::EPSILON.sqrt() * p_max / v_max;
        let pv: Vec<f64> = p.iter().zip(v).map(|(a, b)| a + delta * b).collect();
        // δ F_p v at fixed u*, then δ w = −F_u⁻¹ (δ F_p v).
        self.load_data(&pv);
        let u = self.elastic.u.clone();
        let f = self.factored.as_mut().expect("set up above");
        {
            let rhs = f.rhs.as_mut_slice();
            let disc = self.elastic.discretisation_mut();
            disc.residual(&u, rhs).map_err(RhsError::Evaluation)?;
            for (r, r0) in rhs.iter_mut().zip(&f.residual) {
                *r -= r0;
            }
        }
        f.solver.solve(&mut f.matrix, &mut f.x, &f.rhs)?;
        let u1: Vec<f64> = u.iter().zip(f.x.as_slice()).map(|(a, dx)| a - dx).collect();
        // g(u* + δw, p + δv) − g(u*, p) = δ (g_u w + g_p v).
        let result = self.rates(&u1, &pv, out, None);
        self.load_data(p);
        result?;
        for (o, g0) in out.iter_mut().zip(fy) {
            *o = (*o - g0) / delta;
        }
        Ok(())
    }

    /// Every field of the shell in state `p` at time `t`, for output.
    pub fn snapshot(&mut self, t: f64, p: &[f64]) -> Result<super::Snapshot, RhsError> {
        self.set_time(t)?;
        self.solve_elastic(p)?;
        let sol: Solution = self.elastic.solution()?;
        let stim = self.stimulus(p)?;
        let pts = &self.points;
        let growth: Vec<GrowthRow> = (0..sol.rows.len())
            .map(|i| {
                let k = pts.node_point(i);
                let s = &stim[k];
                GrowthRow {
                    rho: p[NP * k],
                    zeta: pts.zeta(k, p),
                    eta: s.eta,
                    g_v: s.g_v,
                    z_retina: s.z_retina,
                    r_retina: s.r_retina,
                    drive: s.drive,
                    defocus_d: s.defocus,
                }
            })
            .collect();
        let retina: Vec<(f64, f64)> = growth.iter().map(|g| (g.z_retina, g.r_retina)).collect();
        let series = self.series_row(t, &retina)?;
        let peripheral = self.growth.peripheral(t, &retina);
        let through = self.growth.through_lenses(t, &retina);
        Ok(super::Snapshot {
            t,
            fields: sol.rows,
            growth,
            series,
            peripheral,
            through,
        })
    }

    /// The series row alone (axial length, refraction, ...) of the shell in state `p` at
    /// time `t`: what a history point needs, without the fields of a snapshot. An adopted
    /// state is used as it is (its error is the integrator's).
    pub fn series(&mut self, t: f64, p: &[f64]) -> Result<SeriesRow, RhsError> {
        self.set_time(t)?;
        if self.solved_at.as_slice() != p {
            self.solve_elastic(p)?;
        }
        let u = std::mem::take(&mut self.elastic.u);
        let retina = self.retina_at_nodes(&u, p);
        self.elastic.u = u;
        self.series_row(t, &retina?.0)
    }

    /// The series row and the mid-surface (r, z) at every node, of the shell in state `p`
    /// at time `t` polished as [`Self::snapshot`] polishes it: the numbers of a snapshot
    /// that an error estimate compares, without the fields, the stimulus and the peripheral
    /// refraction a snapshot also writes.
    pub fn outline(&mut self, t: f64, p: &[f64]) -> Result<(SeriesRow, Vec<(f64, f64)>), RhsError> {
        self.set_time(t)?;
        self.solve_elastic(p)?;
        let u = std::mem::take(&mut self.elastic.u);
        let outline = self.retina_at_nodes(&u, p).map(|(retina, z)| {
            let shell = z
                .iter()
                .enumerate()
                .map(|(i, &z)| (u[NY * i + R], z))
                .collect();
            (retina, shell)
        });
        self.elastic.u = u;
        let (retina, shell) = outline?;
        Ok((self.series_row(t, &retina)?, shell))
    }

    /// The retina (z, r) at every node of the shell with unknowns `u` in state `p`: what a
    /// series row reads, the same numbers as [`Self::stimulus`] gives at the nodes' points,
    /// without what the rates need besides (every point's depth and angle behind the blue
    /// surface, the midpoints, the crossing of φ_max): a history point costs the point
    /// evaluations and the quadrature of z alone. The mid-surface's z at every node comes
    /// with it.
    #[allow(clippy::type_complexity)] // (the retina's (z, r), the mid-surface's z) per node
    fn retina_at_nodes(
        &mut self,
        u: &[f64],
        p: &[f64],
    ) -> Result<(Vec<(f64, f64)>, Vec<f64>), RhsError> {
        let disc = self.elastic.discretisation_mut();
        let quad = disc.quadratures(u).map_err(RhsError::Evaluation)?;
        let (ev, pts) = (disc.evaluations(), &self.points);
        let retina = (0..disc.mesh.len())
            .map(|i| {
                // The slot `rates` reads a node's point from: node 0 from above, every
                // other node from below.
                let a = match i {
                    0 => ev.left(0).alpha_s,
                    _ => ev.right(i - 1).alpha_s,
                };
                let (r, th, z) = (u[NY * i + R], u[NY * i + THETA], quad.z[i]);
                let k = pts.node_point(i);
                let h = pts.zeta(k, p) / (a * r / p[NP * k]);
                stimulus::retina(z, r, h, th)
            })
            .collect();
        Ok((retina, quad.z))
    }

    /// What the stimulus sees at every point of the solved shell in state `p`.
    fn stimulus(&mut self, p: &[f64]) -> Result<Vec<PointStimulus>, RhsError> {
        let u = std::mem::take(&mut self.elastic.u);
        let mut stim = vec![];
        let mut rates = vec![0.0; p.len()];
        let r = self.rates(&u, p, &mut rates, Some(&mut stim));
        self.elastic.u = u;
        r.map(|_| stim)
    }

    /// The series row from the retina (z, r) at every node: at the posterior pole (node 0),
    /// and the largest retina radius through the nodes
    /// ([`crate::model::stimulus::largest_radius`]).
    fn series_row(&self, t: f64, retina: &[(f64, f64)]) -> Result<SeriesRow, RhsError> {
        let eye = EyeMeasure::new(
            retina[0],
            retina.iter().copied(),
            focal(&self.growth, &self.now, true),
            focal(&self.growth, &self.now, false),
        );
        let mut row = SeriesRow::new(t, self.growth.measure(t, eye));
        // The rule's drive at the pole, as the rates read it there (the pole is never
        // beyond φ_max); over an integrated region, the average over the nodes' retina.
        let viewer = self.viewer();
        let stimulus = &self.growth.stimulus;
        let rule = stimulus.rule();
        if stimulus.region == crate::model::rule::Region::Integrated {
            let nodes = &self.elastic.discretisation().mesh.nodes;
            let (mut seen, mut drives) = (Vec::new(), Vec::new());
            let places = retina.iter().zip(nodes).map(|(&p, &sigma)| (sigma, p));
            viewer.drives(rule.as_ref(), places, self.t, false, &mut seen, &mut drives)?;
            let order: Vec<usize> = (0..seen.len()).collect();
            let points = seen
                .iter()
                .zip(&drives)
                .map(|(v, d)| (v.z, v.r, v.angle, d.value));
            row.drive = retina_average(stimulus, &order, points);
            row.defocus_d = seen[0].defocus;
            return Ok(row);
        }
        let (mut seen, mut drive) = (Vec::new(), Vec::new());
        let pole = std::iter::once((0.0, retina[0]));
        viewer.drives(rule.as_ref(), pole, self.t, false, &mut seen, &mut drive)?;
        (row.drive, row.defocus_d) = (drive[0].value, seen[0].defocus);
        Ok(row)
    }

    /// Take (p, u) as the current state (the coupled DAE's state at an output time): the
    /// data become p's, the elastic unknowns u. A history point reads it as it is; a
    /// snapshot first polishes u into the exact elastic state of p (a warm Newton solve), so
    /// that its fields carry only the growth state's error, as CVODE's do.
    pub fn adopt(&mut self, p: &[f64], u: &[f64]) {
        self.load_data(p);
        self.elastic.u.clear();
        self.elastic.u.extend_from_slice(u);
        self.solved_at.clear();
        self.solved_at.extend_from_slice(p);
        self.exact = false;
    }

    /// The discretisation's data become those of state `p`, written over its buffers.
    pub(crate) fn load_data(&mut self, p: &[f64]) {
        let disc = self.elastic.discretisation_mut();
        let mut data = disc.take_data();
        self.points.material_data_into(p, &mut data);
        self.elastic.discretisation_mut().set_data(data);
    }

    /// The thickness law of the growth points.
    pub fn points_law(&self) -> crate::model::growth_law::ThicknessLaw {
        self.points.law()
    }

    /// The growth model this system runs.
    pub fn growth_params(&self) -> &super::GrowthParams {
        &self.growth
    }

    /// The blue best-focus surface the stimulus reads.
    pub fn blue(&self) -> Focal<'_> {
        focal(&self.growth, &self.now, true)
    }

    /// Move the blue surface's polar centre to `z_b` (forward sensitivities measure the eye
    /// at a shifted surface: `CoupledDae::set_measured_parameter`).
    pub(crate) fn set_blue_centre(&mut self, z_b: f64) {
        self.growth.blue.z_b = z_b;
    }

    /// What the rule reads at each retinal point: the surfaces of now and the dioptre
    /// conversion.
    pub fn viewer(&self) -> crate::growth::view::Viewer<'_> {
        crate::growth::view::Viewer {
            blue: focal(&self.growth, &self.now, true),
            red: focal(&self.growth, &self.now, false),
            vergence: self.vergence.as_ref(),
            reads: self.growth.stimulus.rule().reads(),
            images: self.images(),
            main: self.growth.computed.as_ref().map_or(0, |c| c.main_image()),
        }
    }

    /// The lens's simultaneous images the rule reads: none unless the lens forms several
    /// and the rule reads every image.
    fn images(&self) -> &[crate::model::optics::ComputedImage] {
        match (&self.growth.source, &self.growth.computed) {
            (crate::model::optics::Source::Optics, Some(c))
                if c.images.len() > 1 && self.growth.stimulus.rule().reads_every_image() =>
            {
                &c.images
            }
            _ => &[],
        }
    }

    /// The growth time of the last [`GrowthSystem::set_time`].
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The width the growth laws' kinks are rounded over (0: exact).
    pub fn kink_width(&self) -> f64 {
        self.growth.kink_width
    }
}

/// With `stimulus.region = "integrated"`, the drive averaged over the retina out to the
/// region's edge ([`retina_average`]); None for a local rule.
fn integrated_drive(
    stimulus: &crate::model::rule::Stimulus,
    pts: &GrowthPoints,
    stim: &[PointStimulus],
) -> Option<f64> {
    if stimulus.region != crate::model::rule::Region::Integrated {
        return None;
    }
    let points = stim
        .iter()
        .map(|s| (s.z_retina, s.r_retina, s.angle, s.drive));
    Some(retina_average(stimulus, &pts.by_sigma, points))
}

/// The drive averaged over the retina points `points` ((z, r, φ, drive), taken in the
/// order `order`, pole first) out to the integrated region's edge ([`super::integral`]):
/// what the right side feeds every node and series.csv reports. NaN when no area lies
/// inside, which fails the evaluation.
fn retina_average(
    stimulus: &crate::model::rule::Stimulus,
    order: &[usize],
    points: impl Iterator<Item = (f64, f64, f64, f64)>,
) -> f64 {
    let points: Vec<super::integral::RetinaPoint> = points
        .map(|(z, r, angle, drive)| super::integral::RetinaPoint { z, r, angle, drive })
        .collect();
    super::integral::integrate(order, &points, stimulus.max_angle(), false)
        .map_or(f64::NAN, |i| i.value)
}

/// The rule's drive where the retina crosses the polar angle φ_max ([`super::crossing`]);
/// None if the retina never reaches φ_max.
fn drive_at_angle(pts: &GrowthPoints, stim: &[PointStimulus], phi_max: f64) -> Option<f64> {
    super::crossing::crossing(&pts.by_sigma, |k| stim[k].angle, |k| stim[k].drive, phi_max)
        .map(|c| c.value)
}
