//! The Newton matrix ∂F/∂y + c ∂F/∂y' of the coupled DAE, assembled analytically into a
//! CSR: the elastic Jacobian, its data columns, the z rows, the growth rows and the border.

#[allow(unused_imports)]
use super::*;

impl CoupledDae {
    /// Assemble ∂F/∂y + c ∂F/∂y' at y into the CSR matrix.
    pub fn assemble(&mut self, c: f64, y: &[f64]) -> Result<(), DaeError> {
        self.load(y, Part::Full)?;
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
        let finite = self
            .point_rates(y, &mut s, true)
            .and_then(|c| self.check_finite(&s.rates, Some(&s.rd)).map(|_| c));
        if let Ok(crossing) = &finite {
            self.assemble_growth_rows(c, &grads, &s.rd, &s.rates);
            self.assemble_border(&grads, &s.rd, crossing.as_ref());
        }
        (self.grads, self.scratch) = (grads, s);
        finite.map(|_| ())?;
        match self.jac.take_outside() {
            0 => Ok(()),
            k => Err(DaeError::Linear(LinalgError::OutsidePattern(k))),
        }
    }

    /// Add a window gradient `g` of interval i to row `row`; `half` restricts the W part
    /// to the nodes the row's pattern holds (0: node i, 1: node i+1, None: both).
    pub(super) fn add_grad(&mut self, row: usize, i: usize, g: &Grad, half: Option<usize>) {
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
    pub(super) fn data_derivs(&self, out: &mut Vec<DataDeriv>) {
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
    pub(super) fn assemble_data_columns(&mut self) {
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
    pub(super) fn interval_data_columns(&self, i: usize) -> [Option<(usize, [Vec5; 2])>; 3] {
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
    pub(super) fn assemble_z_rows(&mut self, grads: &mut [[Grad; 4]]) {
        for i in 0..self.m - 1 {
            let mid = self.hermite_simpson.then(|| &mut grads[i]);
            let g = self.z_row(i, mid);
            self.add_grad(self.interval_row(i, Z), i, &g, None);
        }
    }

    /// Interval i's z row's gradient in its window; with `mid`, its midpoint's derivatives.
    pub(super) fn z_row(&self, i: usize, mid: Option<&mut [Grad; 4]>) -> Grad {
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
    pub(super) fn assemble_growth_rows(
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

    /// The border row: d − D*(y), D* the drive interpolated at φ_max or averaged over the
    /// integrated region ([`Border::terms`]).
    pub(super) fn assemble_border(
        &mut self,
        grads: &[[Grad; 4]],
        rd: &[RateDeriv],
        border: Option<&Border>,
    ) {
        let Some(border) = border else {
            return;
        };
        let d = self.d();
        for (k, c) in border.terms() {
            let v = rd[k].border_row(&c);
            let mut g = Grad::default();
            let own = match self.sites[k] {
                Site::Left(_) => L,
                Site::Right(_) => RT,
                Site::Mid(_) => M,
            };
            let gk = self.point_grads(k, grads);
            for q in 0..4 {
                g.axpy(-v[q], &gk[q]);
            }
            for (s, q) in [(0usize, 4usize), (1, 5)] {
                g.p[own][s] -= v[q];
            }
            let i = self.sites[k].interval();
            self.add_grad(d, i, &g, None);
        }
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
