//! The forward sensitivities of the coupled DAE: the parameters they are taken with respect
//! to ([`SensParam`]), ∂F/∂p analytically, and their consistent start (docs/MODEL.md §10).

#[allow(unused_imports)]
use super::*;
use crate::names::Quantity;

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
    /// run's clock, and their sensitivities follow from η0's ([`crate::growth::schedule`]).
    ScheduleTau,
    ScheduleCentre,
    ScheduleWidth,
    /// geometry.R0: the eye's radius at the start. It moves the material mesh itself (the
    /// shell's length is π·fraction·R0), so its sensitivity is a directional difference of
    /// two runs, not an IDAS sensitivity (docs/MODEL.md §11).
    Radius,
}

/// Why a sensitivity cannot be taken in a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SensitivityError {
    /// The fibres' stiffness in a scene without fibres.
    #[error("{} = 0: the scene has no fibres, so there is no sensitivity to their stiffness", .param.quantity())]
    NoFibres { param: SensParam },
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

    /// The schedule's parameter this is, if it is one.
    pub fn schedule_param(self) -> Option<crate::growth::schedule::ScheduleParam> {
        use crate::growth::schedule::ScheduleParam;
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

    /// The quantity it is: what messages and sensitivity rows name it by
    /// ([`crate::names`]; the scene layer maps it to its key).
    pub fn quantity(self) -> Quantity {
        match self {
            SensParam::Eta0 => Quantity::GrowthRate,
            SensParam::Gamma => Quantity::CapacityFall,
            SensParam::Delta => Quantity::CapacityWidth,
            SensParam::FibreStiffness => Quantity::FibreStiffness,
            SensParam::Modulus => Quantity::Modulus,
            SensParam::Bending => Quantity::Bending,
            SensParam::Pressure => Quantity::Pressure,
            SensParam::BlueCentre => Quantity::BlueCentre,
            SensParam::ScheduleTau => Quantity::ScheduleTau,
            SensParam::ScheduleCentre => Quantity::ScheduleCentre,
            SensParam::ScheduleWidth => Quantity::ScheduleWidth,
            SensParam::Radius => Quantity::Radius,
        }
    }

    /// Its name in messages and in the rows' `parameter`: the front end's word for its
    /// quantity (the scene key under the `eyeshell` crate), else the model's symbol.
    pub fn key(self) -> &'static str {
        self.quantity().name()
    }

    /// Whether the parameter can be taken in a model of `params`.
    ///
    /// # Errors
    /// [`SensitivityError::NoFibres`] for the fibres' stiffness in a scene without fibres
    /// (D = 0 leaves the fibres out of the model, docs/MODEL.md §2).
    pub fn check(self, params: &Params) -> Result<(), SensitivityError> {
        match self {
            SensParam::FibreStiffness if !params.has_fibres() => {
                Err(SensitivityError::NoFibres { param: self })
            }
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
    pub fn value(self, params: &Params, g: &crate::growth::GrowthParams) -> f64 {
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
    pub fn scale(self, params: &Params, g: &crate::growth::GrowthParams) -> f64 {
        let defaults = (Params::default(), crate::growth::GrowthParams::default());
        [self.value(params, g), self.value(&defaults.0, &defaults.1)]
            .into_iter()
            .map(f64::abs)
            .find(|v| *v > 0.0 && v.is_finite())
            .unwrap_or(1.0)
    }

    /// Set its value in the model to `v` (the scene's own key does the same, with the red
    /// surface following the blue one where the scene says so: `Scene::set`).
    pub fn set(self, params: &mut Params, g: &mut crate::growth::GrowthParams, v: f64) {
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
            SensParam::Radius => params.set_radius(v),
        }
    }

    /// ∂g_c/∂p at Σ = `sigma` (docs/MODEL.md §5); zero for the parameters g_c does not hold.
    pub fn capacity_partial(self, g: &crate::growth::GrowthParams, sigma: f64) -> f64 {
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

impl CoupledDae {
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
    pub(super) fn parameter_residuals(
        &mut self,
        y: &[f64],
        params: &[SensParam],
        out: &mut [&mut [f64]],
    ) -> Result<(), RhsError> {
        self.load(y, Part::Full)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let model = params.iter().any(|p| !p.is_growth());
        let crossing = match self.point_rates(y, &mut s, model) {
            Ok(c) => c,
            Err(e) => {
                self.scratch = s;
                return Err(e);
            }
        };
        let finite = self.check_finite(&s.rates, model.then_some(s.rd.as_slice()));
        if finite.is_ok() {
            let g = self.sys.growth_params();
            for (&param, out) in params.iter().zip(out.iter_mut()) {
                out.fill(0.0);
                if !param.is_growth() {
                    self.model_parameter_residual(param, &s.rd, crossing.as_ref(), out);
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
    pub(super) fn constant_derivs(&self, c: ShellConstant) -> Vec<ConstantPartials> {
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
    pub(super) fn model_parameter_residual(
        &self,
        param: SensParam,
        rd: &[RateDeriv],
        crossing: Option<&Border>,
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
        // The border d − D*, as in the Jacobian.
        if let Some(border) = crossing {
            for (k, term) in border.terms() {
                out[d] -= match term {
                    Term::Crossing { weight, slope } => {
                        weight
                            * (dot(&rd[k].drive, &dlocal[k])
                                - slope * dot(&rd[k].angle, &dlocal[k]))
                    }
                    Term::Integral(_) => dot(&rd[k].border_row(&term), &dlocal[k]),
                };
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
    pub(super) fn algebraic_sensitivities(
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
    pub(super) fn linearised_sensitivities(
        &mut self,
        y: &[f64],
    ) -> Result<InitialSensitivities, DaeError> {
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
}
