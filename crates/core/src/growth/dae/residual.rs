//! The residual of the coupled DAE: the local state of every point, the growth rates and
//! their derivatives, the depth where the retina crosses φ_max, and F(t, y, y').

#[allow(unused_imports)]
use super::*;
use crate::growth::integral::{integrate, Integral, RetinaPoint};
use crate::model::rule::Region;

/// The rule a growth system runs.
fn viewer_rule(sys: &GrowthSystem) -> &dyn crate::model::rule::GrowthRule {
    sys.growth_params().stimulus.rule().as_ref()
}

impl CoupledDae {
    /// The local state (r, θ, z, α_s) of every point. Their derivatives in the windows come
    /// from [`CoupledDae::node_grads`] (nodes) and [`CoupledDae::assemble_z_rows`]
    /// (midpoints, which share the slopes' derivatives with the z rows).
    pub(super) fn locals(&self, y: &[f64], local: &mut Vec<Local>) {
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
    pub(super) fn node_grads(&self, k: usize) -> [Grad; 4] {
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
    pub(super) fn node_grad(&self, k: usize) -> NodeGrads {
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
    pub(super) fn point_grads(&self, k: usize, mids: &[[Grad; 4]]) -> [Grad; 4] {
        match self.sites[k] {
            Site::Mid(i) => mids[i],
            _ => self.node_grads(k),
        }
    }

    /// z at interval i's midpoint, from the cubic Hermite through its ends (the slopes
    /// −γ α_s sin θ from inside the interval).
    pub(super) fn z_mid_value(
        &self,
        y: &[f64],
        disc: &Discretisation,
        ev: &Evaluations,
        i: usize,
    ) -> f64 {
        let h = disc.mesh.step(i);
        let (el, er) = (ev.left(i), ev.right(i));
        let wl = -disc.data.above[i].gamma * el.alpha_s * el.sin_theta;
        let wr = -disc.data.below[i + 1].gamma * er.alpha_s * er.sin_theta;
        0.5 * (y[self.wcol(i, Z)] + y[self.wcol(i + 1, Z)]) + h / 8.0 * (wl - wr)
    }

    /// The derivatives of dz/dΣ = −γ α_s sin θ in the window at interval i's end `slot` (L
    /// or RT) or midpoint (M, through y_m: `mid` is the interval's [`MidMap`]).
    pub(super) fn slope(
        &self,
        disc: &Discretisation,
        i: usize,
        slot: usize,
        mid: Option<&MidMap>,
    ) -> Grad {
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
    pub(super) fn mid_map(&self, i: usize) -> MidMap<'_> {
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
    pub(super) fn mid_grads(&self, i: usize, map: &MidMap, out: &mut [Grad; 4]) {
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

    /// The retina, what it sees, the rule's drive and the rates at every point, and the
    /// crossing of φ_max whose drive they read beyond it; with `deriv`, their derivatives in
    /// each point's (r, θ, z, α_s, ρ, γ_s) and d.
    pub(super) fn point_rates(
        &self,
        y: &[f64],
        s: &mut PointScratch,
        deriv: bool,
    ) -> Result<Option<Border>, RhsError> {
        let pts = &self.sys.points;
        let law = self.sys.points_law();
        let viewer = self.sys.viewer();
        let t = self.sys.time();
        let w = self.sys.kink_width();
        let d_unknown = y[self.d()];
        s.rates.clear();
        s.rd.clear();
        s.places.clear();
        s.retina_d.clear();
        for (k, l) in s.local.iter().enumerate() {
            let (rho, gam) = (y[NP * k], y[NP * k + 1]);
            let zeta = pts.zeta(k, &y[..self.n_p]);
            let ht = zeta * rho / (l.alpha_s * l.r);
            let (sn, cs) = (l.sin_theta, l.cos_theta);
            let (zr, rr) = (l.z - 0.5 * ht * cs, l.r - 0.5 * ht * sn);
            s.places.push((pts.sigma_ref[k], (zr, rr)));
            if deriv {
                // h_t = ζ ρ / (α_s r), ζ = ζ(ρ, γ_s): ∂h_t/∂(r, θ, z, α_s, ρ, γ_s).
                let [z_rho, z_gam] = zeta_partials(law, rho, zeta, gam);
                let dht = [
                    -ht / l.r,
                    0.0,
                    0.0,
                    -ht / l.alpha_s,
                    ht / rho + ht / zeta * z_rho,
                    ht / zeta * z_gam,
                ];
                let mut dz_ret = dht.map(|v| -0.5 * cs * v);
                let mut dr_ret = dht.map(|v| -0.5 * sn * v);
                dz_ret[2] += 1.0;
                dz_ret[1] += 0.5 * ht * sn;
                dr_ret[0] += 1.0;
                dr_ret[1] -= 0.5 * ht * cs;
                s.retina_d.push([dz_ret, dr_ret]);
            }
        }
        viewer
            .drives(
                viewer_rule(&self.sys),
                s.places.iter().copied(),
                t,
                deriv,
                &mut s.seen,
                &mut s.drives,
            )
            .map_err(RhsError::Rule)?;
        for (k, (seen, drive)) in s.seen.iter().zip(&s.drives).enumerate() {
            s.rates.push(PointRates {
                drive: drive.value,
                angle: seen.angle,
                ..Default::default()
            });
            if deriv {
                let [dz_ret, dr_ret] = s.retina_d[k];
                let [gz, gr] = drive.gradient(seen);
                let mut rd = RateDeriv {
                    retina: [dz_ret, dr_ret],
                    ..RateDeriv::default()
                };
                for q in 0..6 {
                    rd.drive[q] = gz * dz_ret[q] + gr * dr_ret[q];
                    rd.angle[q] = seen.angle_grad[0] * dz_ret[q] + seen.angle_grad[1] * dr_ret[q];
                }
                s.rd.push(rd);
            }
        }
        // Beyond φ_max the drive is the unknown d (docs/MODEL.md §6); over an integrated
        // region d is the average, and every point reads it.
        let integrated = self.sys.growth_params().stimulus.region == Region::Integrated;
        let border = if integrated {
            let points: Vec<RetinaPoint> = s
                .seen
                .iter()
                .zip(&s.rates)
                .map(|(v, pr)| RetinaPoint {
                    z: v.z,
                    r: v.r,
                    angle: v.angle,
                    drive: pr.drive,
                })
                .collect();
            let max_angle = self.sys.growth_params().stimulus.max_angle();
            let integral = integrate(&self.sys.points.by_sigma, &points, max_angle, deriv);
            Some(Border::Integral(integral.unwrap_or(Integral {
                value: f64::NAN,
                ..Integral::default()
            })))
        } else {
            self.crossing_drive(&s.rates).map(Border::Crossing)
        };
        let has_crossing = border.is_some();
        for (k, pr) in s.rates.iter_mut().enumerate() {
            let l = &s.local[k];
            let (rho, gam) = (y[NP * k], y[NP * k + 1]);
            pr.beyond = integrated || (has_crossing && pr.angle >= viewer.blue.phi_max());
            let drive = if pr.beyond { d_unknown } else { pr.drive };
            let (dr, da) = (l.r - rho, l.alpha_s - 1.0);
            let ((gv, gv_slope), (pr_, pr_slope), (pa, pa_slope)) = (
                positive_smooth(drive, w),
                positive_smooth(dr, w),
                positive_smooth(da, w),
            );
            pr.g_v = gv;
            let cap = pts.capacity[k];
            pr.eta = cap * pr.g_v;
            pr.rho = pr.eta * pr_;
            pr.gamma = pr.eta * gam * pa;
            pr.per_capacity = [pr.g_v * pr_, pr.g_v * gam * pa];
            if deriv {
                let rd = &mut s.rd[k];
                // ∂g_v/∂(local) and ∂g_v/∂d: the slope of the branch the value took.
                let gv_local: [f64; 6] = if pr.beyond {
                    [0.0; 6]
                } else {
                    rd.drive.map(|v| gv_slope * v)
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
        Ok(border)
    }

    /// Rates (and, with `deriv`, their derivatives) that are not finite fail the evaluation
    /// at their point, as an elastic evaluation does, so that IDA cuts the step or the run
    /// says where; they would otherwise spread NaN through the Newton matrix.
    pub(super) fn check_finite(
        &self,
        rates: &[PointRates],
        deriv: Option<&[RateDeriv]>,
    ) -> Result<(), RhsError> {
        // No allocation and no branch per value: this runs at every residual and assembly.
        let bad = |k: usize| {
            let pr = &rates[k];
            let own = all_finite(&[pr.rho, pr.gamma, pr.drive]);
            let derivatives = deriv.is_none_or(|rd| {
                let d = &rd[k];
                all_finite(d.rate.as_flattened())
                    & all_finite(&d.rate_d)
                    & all_finite(&d.drive)
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

    /// The rule's drive where the retina crosses φ_max ([`crate::growth::crossing`]); None
    /// if no point reaches it.
    pub(super) fn crossing_drive(&self, rates: &[PointRates]) -> Option<Crossing> {
        crate::growth::crossing::crossing(
            &self.sys.points.by_sigma,
            |k| rates[k].angle,
            |k| rates[k].drive,
            self.sys.blue().phi_max(),
        )
    }

    /// F(t, y, y') into r.
    pub fn residual(&mut self, y: &[f64], yp: &[f64], r: &mut [f64]) -> Result<(), RhsError> {
        let start = std::time::Instant::now();
        self.counters.residuals += 1;
        self.load(y, Part::Values)?;
        let mut s = std::mem::take(&mut self.scratch);
        self.locals(y, &mut s.local);
        let crossing = self.point_rates(y, &mut s, false);
        let crossing = match crossing {
            Ok(c) => c,
            Err(e) => {
                self.scratch = s;
                return Err(e);
            }
        };
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
        r[d] = y[d] - crossing.as_ref().map_or(0.0, |c| c.value());
        (self.f, self.dz) = (f, dz);
        self.counters.residual_seconds += start.elapsed().as_secs_f64();
        Ok(())
    }
}
