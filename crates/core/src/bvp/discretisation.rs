//! The discrete equations on the material nodes (docs/MODEL.md §3): trapezoidal (order 2) or
//! Hermite–Simpson = 3-stage Lobatto IIIA (order 4, bvp4c's scheme), the truncated pole
//! conditions at Σ = ε and the cornea conditions at Σ = L, with the analytic Jacobian.
//!
//! Unknowns are interleaved by node, u = [y_0, y_1, …, y_{M−1}], y = (κ, r, θ, q_s, t_s).
//! Rows: the three pole conditions (on y_0), then five rows per interval (on y_i, y_{i+1}),
//! then the two cornea conditions (on y_{M−1}). Every row's columns lie within 7 below and
//! 6 above the diagonal, so the Jacobian is a band matrix with ml = 7, mu = 6; node by node
//! it is almost block diagonal (5×10 interval blocks, 3 rows before and 2 after), the
//! structure `linalg::AbdLu` factors (`solver.linear = "block"`).
//!
//! At a material breakpoint each interval evaluates f with the data from its own side, so
//! α_s may jump there while t_s, κ, r, θ, Q stay continuous (docs/MODEL.md §4).
//!
//! The residual and the Jacobian are built from the scene's components
//! (`model::components`): each pass over the points resolves the membrane component once
//! and runs a loop monomorphised for it (`Equations<NoFibres>` or `Equations<Fibres>`),
//! so a fibre-free scene's assembly holds no fibre code. A uniform thickness has no jump
//! node and so no second evaluation at πR0/2; no component adds thickness derivatives.

use super::equations::{
    self, Equations, Mat5, MaterialPoint, Part, PointError, PointEval, Shell, Vec5, KAPPA, QS, R,
    THETA, TS,
};
use crate::bvp::settings::Scheme;
use crate::mesh::Mesh;
use crate::model::components::Membrane;
use crate::model::constitutive::Reinforcement;
use crate::model::cornea::CorneaEdge;
use eyeshell_sundials::MatrixSink;

/// Unknowns per node.
pub const NY: usize = 5;
/// Band widths of the Jacobian (below, above the diagonal).
pub const LOWER: usize = 7;
pub const UPPER: usize = 6;
/// Rows at the pole before the first interval's rows.
pub const POLE_ROWS: usize = 3;

/// Where the discrete equations could not be evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalFailure {
    pub node: usize,
    pub sigma_ref: f64,
    pub why: PointError,
}

/// The shell's material data on the mesh: at each node from either side, and at the
/// interval midpoints (used by Hermite–Simpson).
#[derive(Clone, Debug, Default)]
pub struct MaterialData {
    /// Node i seen from interval i (the limit from above). Length M.
    pub above: Vec<MaterialPoint>,
    /// Node i seen from interval i−1 (the limit from below). Length M.
    pub below: Vec<MaterialPoint>,
    /// Midpoint of interval i. Length M−1.
    pub mid: Vec<MaterialPoint>,
}

impl MaterialData {
    fn jumps(&self, i: usize) -> bool {
        self.above[i] != self.below[i]
    }
}

/// Point evaluations at the current state, shared by the residual and the Jacobian. The
/// buffers live as long as the discretisation: a Newton iteration allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct Evaluations {
    /// u at which they were taken (empty: none yet).
    u: Vec<f64>,
    /// Node i from above (interval i's left end); the last node from below.
    node: Vec<PointEval>,
    /// Nodes where the data jump, seen from below (interval i−1's right end): (i, eval).
    below: Vec<(usize, PointEval)>,
    /// Hermite–Simpson midpoint of interval i, and y there.
    mid: Vec<PointEval>,
    y_mid: Vec<Vec5>,
    /// Whether ∂f/∂y and ∂α_s/∂(r, t_s) are those at `u` too ([`Part::Full`]), or only
    /// the values ([`Part::Values`]).
    full: bool,
}

impl Evaluations {
    /// f and ∂f/∂y at interval i's left end.
    #[inline]
    pub fn left(&self, i: usize) -> &PointEval {
        &self.node[i]
    }

    /// f and ∂f/∂y at interval i's right end, from inside the interval.
    #[inline]
    pub fn right(&self, i: usize) -> &PointEval {
        match self.below.iter().find(|(k, _)| *k == i + 1) {
            Some((_, e)) => e,
            None => &self.node[i + 1],
        }
    }

    /// At interval i's Hermite–Simpson midpoint (empty for the trapezoidal scheme).
    #[inline]
    pub fn mid(&self, i: usize) -> &PointEval {
        &self.mid[i]
    }

    /// y at interval i's Hermite–Simpson midpoint.
    #[inline]
    pub fn y_mid(&self, i: usize) -> &Vec5 {
        &self.y_mid[i]
    }
}

/// The quadratures s(Σ), z(Σ) at the nodes, with their slopes (ds/dΣ, dz/dΣ) at each
/// interval's ends from inside the interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadratures {
    pub s: Vec<f64>,
    pub z: Vec<f64>,
    pub slope_left: Vec<[f64; 2]>,
    pub slope_right: Vec<[f64; 2]>,
    /// z(Σ_{i+1}) − z(Σ_i) by the scheme's quadrature, interval by interval.
    pub dz: Vec<f64>,
}

impl Quadratures {
    /// z at the middle of interval i, from the cubic Hermite through its ends.
    pub fn z_mid(&self, i: usize, h: f64) -> f64 {
        0.5 * (self.z[i] + self.z[i + 1])
            + h / 8.0 * (self.slope_left[i][1] - self.slope_right[i][1])
    }
}

/// The discrete boundary value problem F(u) = 0.
#[derive(Clone, Debug)]
pub struct Discretisation {
    pub shell: Shell,
    pub scheme: Scheme,
    pub mesh: Mesh,
    pub data: MaterialData,
    pub edge: CorneaEdge,
    evals: Evaluations,
    /// Nodes whose data jump (a material breakpoint of H).
    jump_nodes: Vec<usize>,
}

#[inline]
fn y_at(u: &[f64], i: usize) -> Vec5 {
    Vec5::from_column_slice(&u[NY * i..NY * i + NY])
}

impl Discretisation {
    pub fn new(
        shell: Shell,
        scheme: Scheme,
        mesh: Mesh,
        data: MaterialData,
        edge: CorneaEdge,
    ) -> Self {
        let m = mesh.len();
        assert!(data.above.len() == m && data.below.len() == m && data.mid.len() == m - 1);
        let jump_nodes = (1..m - 1).filter(|&i| data.jumps(i)).collect();
        Discretisation {
            shell,
            scheme,
            mesh,
            data,
            edge,
            evals: Evaluations::default(),
            jump_nodes,
        }
    }

    /// Replace the unloaded shell's data (after growth); evaluations at the old data are dropped.
    /// The data, handed out to be written over ([`Self::set_data`] gives them back): no
    /// point evaluation holds until then.
    pub fn take_data(&mut self) -> MaterialData {
        self.evals.u.clear();
        std::mem::take(&mut self.data)
    }

    pub fn set_data(&mut self, data: MaterialData) {
        let m = self.mesh.len();
        assert!(data.above.len() == m && data.below.len() == m && data.mid.len() == m - 1);
        self.jump_nodes = (1..m - 1).filter(|&i| data.jumps(i)).collect();
        self.data = data;
        self.evals.u.clear();
    }

    /// s and z along the shell by the scheme's own quadrature (Simpson with the
    /// Hermite–Simpson midpoints, else trapezoidal): ds/dΣ = γ α_s from s(ε) = σ_ε α_s,
    /// dz/dΣ = −γ α_s sin θ from the cornea's z(L) = z*.
    pub fn quadratures(&mut self, u: &[f64]) -> Result<Quadratures, EvalFailure> {
        self.evaluate(u, Part::Values)?;
        let (m, ev, data) = (self.mesh.len(), &self.evals, &self.data);
        let rates = |mp: &MaterialPoint, e: &PointEval| {
            [mp.gamma * e.alpha_s, -mp.gamma * e.alpha_s * e.sin_theta]
        };
        let mut q = Quadratures {
            s: vec![0.0; m],
            z: vec![0.0; m],
            slope_left: Vec::with_capacity(m - 1),
            slope_right: Vec::with_capacity(m - 1),
            dz: vec![0.0; m - 1],
        };
        q.s[0] = data.above[0].sigma * ev.left(0).alpha_s;
        for i in 0..m - 1 {
            let h = self.mesh.step(i);
            let a = rates(&data.above[i], ev.left(i));
            let b = rates(&data.below[i + 1], ev.right(i));
            let step = match self.scheme {
                Scheme::HermiteSimpson => {
                    let c = rates(&data.mid[i], ev.mid(i));
                    [
                        h / 6.0 * (a[0] + 4.0 * c[0] + b[0]),
                        h / 6.0 * (a[1] + 4.0 * c[1] + b[1]),
                    ]
                }
                Scheme::Trapezoid => [0.5 * h * (a[0] + b[0]), 0.5 * h * (a[1] + b[1])],
            };
            q.s[i + 1] = q.s[i] + step[0];
            q.dz[i] = step[1];
            q.slope_left.push(a);
            q.slope_right.push(b);
        }
        q.z[m - 1] = self.edge.z;
        for i in (0..m - 1).rev() {
            q.z[i] = q.z[i + 1] - q.dz[i];
        }
        Ok(q)
    }

    /// z(Σ_{i+1}) − z(Σ_i) interval by interval, as [`Discretisation::quadratures`] has it,
    /// into `dz` (length M − 1), without the rest of the quadratures.
    pub fn z_steps(&mut self, u: &[f64], dz: &mut [f64]) -> Result<(), EvalFailure> {
        self.evaluate(u, Part::Values)?;
        let (ev, data) = (&self.evals, &self.data);
        let slope = |mp: &MaterialPoint, e: &PointEval| -mp.gamma * e.alpha_s * e.sin_theta;
        for (i, d) in dz.iter_mut().enumerate() {
            let h = self.mesh.step(i);
            let (a, b) = (
                slope(&data.above[i], ev.left(i)),
                slope(&data.below[i + 1], ev.right(i)),
            );
            *d = match self.scheme {
                Scheme::HermiteSimpson => h / 6.0 * (a + 4.0 * slope(&data.mid[i], ev.mid(i)) + b),
                Scheme::Trapezoid => 0.5 * h * (a + b),
            };
        }
        Ok(())
    }

    /// Number of unknowns (and equations), 5 M.
    pub fn len(&self) -> usize {
        NY * self.mesh.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mesh.is_empty()
    }

    /// Evaluate at every point the scheme uses what `need` asks ([`Part::Values`] or
    /// [`Part::Full`]), unless already done at `u`, with the equations of the shell's
    /// membrane component (resolved here, once a pass). Values taken at `u` are completed
    /// with their derivatives without a new α_s solve ([`Part::Derivatives`]), so that a
    /// residual and then a Jacobian at one `u` cost one solve per point, as one full pass.
    fn evaluate(&mut self, u: &[f64], need: Part) -> Result<(), EvalFailure> {
        let part = if !self.evals.u.is_empty() && self.evals.u.as_slice() == u {
            match (need, self.evals.full) {
                (Part::Values, _) | (_, true) => return Ok(()),
                _ => Part::Derivatives,
            }
        } else {
            need
        };
        match self.shell.membrane() {
            Membrane::NeoHookean { .. } => {
                self.evaluate_with(&Equations::neo_hookean(&self.shell), u, part)
            }
            Membrane::Reinforced { d, .. } => {
                self.evaluate_with(&Equations::reinforced(&self.shell, d), u, part)
            }
        }
    }

    /// The pass over the points for one membrane component R, each evaluation written in
    /// place. Each α_s solve is seeded with the α_s of the previous evaluation at the same
    /// point (the cornea's stretch the first time).
    fn evaluate_with<Rf: Reinforcement>(
        &mut self,
        eq: &Equations<Rf>,
        u: &[f64],
        part: Part,
    ) -> Result<(), EvalFailure> {
        let ev = &mut self.evals;
        ev.u.clear(); // invalid until every point is done
        let m = self.mesh.len();
        let seed = self.edge.alpha;
        let fail = |node: usize, mp: &MaterialPoint| {
            let sigma_ref = mp.sigma_ref;
            move |why| EvalFailure {
                node,
                sigma_ref,
                why,
            }
        };
        let guess = |e: &PointEval| if e.is_set() { e.alpha_s } else { seed };
        ev.node.resize(m, PointEval::unset());
        for i in 0..m {
            let mp = if i < m - 1 {
                &self.data.above[i]
            } else {
                &self.data.below[i]
            };
            let e = &mut ev.node[i];
            eq.evaluate_part(mp, &y_at(u, i), guess(e), e, part)
                .map_err(fail(i, mp))?;
        }
        ev.below.truncate(self.jump_nodes.len());
        for (k, &i) in self.jump_nodes.iter().enumerate() {
            if k == ev.below.len() {
                ev.below.push((i, PointEval::unset()));
            }
            let mp = &self.data.below[i];
            let e = &mut ev.below[k];
            e.0 = i;
            eq.evaluate_part(mp, &y_at(u, i), guess(&e.1), &mut e.1, part)
                .map_err(fail(i, mp))?;
        }
        if self.scheme == Scheme::HermiteSimpson {
            ev.mid.resize(m - 1, PointEval::unset());
            ev.y_mid.resize(m - 1, Vec5::zeros());
            for i in 0..m - 1 {
                let h = self.mesh.step(i);
                let ym = 0.5 * (y_at(u, i) + y_at(u, i + 1))
                    + (h / 8.0) * (ev.left(i).f - ev.right(i).f);
                let mp = &self.data.mid[i];
                let e = &mut ev.mid[i];
                eq.evaluate_part(mp, &ym, guess(e), e, part)
                    .map_err(fail(i, mp))?;
                ev.y_mid[i] = ym;
            }
        }
        ev.u.extend_from_slice(u);
        ev.full = part != Part::Values;
        Ok(())
    }

    /// σ_ε, the grown arclength at the truncated pole.
    fn sigma_eps(&self) -> f64 {
        self.data.above[0].sigma
    }

    /// F(u) into `f`.
    pub fn residual(&mut self, u: &[f64], f: &mut [f64]) -> Result<(), EvalFailure> {
        self.evaluate(u, Part::Values)?;
        let ev = &self.evals;
        let m = self.mesh.len();
        // Pole (docs/MODEL.md §3): r = σ_ε α_s, θ = σ_ε α_s κ, and the first integral over r.
        let y0 = y_at(u, 0);
        let se = self.sigma_eps();
        let a0 = ev.left(0).alpha_s;
        f[0] = y0[R] - se * a0;
        f[1] = y0[THETA] - se * a0 * y0[KAPPA];
        f[2] = equations::first_integral_over_r(self.shell.dp, &y0);
        for i in 0..m - 1 {
            let h = self.mesh.step(i);
            let dy = y_at(u, i + 1) - y_at(u, i);
            let r = match self.scheme {
                Scheme::Trapezoid => dy - (0.5 * h) * (ev.left(i).f + ev.right(i).f),
                Scheme::HermiteSimpson => {
                    dy - (h / 6.0) * (ev.left(i).f + 4.0 * ev.mid(i).f + ev.right(i).f)
                }
            };
            f[POLE_ROWS + NY * i..POLE_ROWS + NY * i + NY].copy_from_slice(r.as_slice());
        }
        let yl = y_at(u, m - 1);
        let n = self.len();
        f[n - 2] = yl[R] - self.edge.r;
        f[n - 1] = yl[THETA] - self.edge.theta;
        Ok(())
    }

    /// ∂F/∂u at `u`, every structural entry written into `jac`.
    pub fn jacobian<S: MatrixSink + ?Sized>(
        &mut self,
        u: &[f64],
        jac: &mut S,
    ) -> Result<(), EvalFailure> {
        self.evaluate(u, Part::Full)?;
        let ev = &self.evals;
        let m = self.mesh.len();
        let y0 = y_at(u, 0);
        let se = self.sigma_eps();
        let e0 = ev.left(0);
        let (a0, a0_r, a0_ts) = (e0.alpha_s, e0.alpha_s_r, e0.alpha_s_ts);
        // r − σ_ε α_s
        jac.set(0, R, 1.0 - se * a0_r);
        jac.set(0, TS, -se * a0_ts);
        // θ − σ_ε α_s κ
        jac.set(1, KAPPA, -se * a0);
        jac.set(1, R, -se * a0_r * y0[KAPPA]);
        jac.set(1, THETA, 1.0);
        jac.set(1, TS, -se * a0_ts * y0[KAPPA]);
        // q_s cos θ + t_s sin θ − r ΔP / 2
        let (sn, cs) = y0[THETA].sin_cos();
        jac.set(2, R, -0.5 * self.shell.dp);
        jac.set(2, THETA, -y0[QS] * sn + y0[TS] * cs);
        jac.set(2, QS, cs);
        jac.set(2, TS, sn);
        let id = Mat5::identity();
        for i in 0..m - 1 {
            let h = self.mesh.step(i);
            let (jl, jr) = (&ev.left(i).jac, &ev.right(i).jac);
            let (dl, dr) = match self.scheme {
                Scheme::Trapezoid => (-id - (0.5 * h) * jl, id - (0.5 * h) * jr),
                Scheme::HermiteSimpson => {
                    // y_m = (y_i + y_{i+1})/2 + h/8 (f_i − f_{i+1}), so
                    // ∂R/∂y_i = −I − h/6 J_i − h/3 J_m − h²/12 J_m J_i, and likewise for y_{i+1}.
                    let jm = &ev.mid(i).jac;
                    let jm_jl = jm * jl;
                    let jm_jr = jm * jr;
                    (
                        -id - (h / 6.0) * jl - (h / 3.0) * jm - (h * h / 12.0) * jm_jl,
                        id - (h / 6.0) * jr - (h / 3.0) * jm + (h * h / 12.0) * jm_jr,
                    )
                }
            };
            // Interval i's rows as one row-major 5×10 block [∂R/∂y_i | ∂R/∂y_{i+1}]: a
            // block sink copies it whole (no per-entry index arithmetic).
            let mut block = [0.0; 2 * NY * NY];
            for a in 0..NY {
                for b in 0..NY {
                    block[2 * NY * a + b] = dl[(a, b)];
                    block[2 * NY * a + NY + b] = dr[(a, b)];
                }
            }
            jac.set_block(POLE_ROWS + NY * i, NY * i, 2 * NY, &block);
        }
        let n = self.len();
        jac.set(n - 2, n - NY + R, 1.0);
        jac.set(n - 1, n - NY + THETA, 1.0);
        Ok(())
    }

    /// The CSR pattern of the Jacobian (for sparse solvers): each row's columns are one
    /// contiguous block.
    pub fn pattern(&self) -> (Vec<usize>, Vec<usize>) {
        let n = self.len();
        let mut row_ptr = vec![0];
        let mut col_idx = Vec::new();
        for row in 0..n {
            let cols = if row < POLE_ROWS {
                0..NY
            } else if row >= n - 2 {
                n - NY..n
            } else {
                let i = (row - POLE_ROWS) / NY;
                NY * i..NY * (i + 2)
            };
            col_idx.extend(cols);
            row_ptr.push(col_idx.len());
        }
        (row_ptr, col_idx)
    }

    /// Make sure the point evaluations are those at `u`, derivatives included (see
    /// [`Self::evaluations`]).
    pub fn evaluate_at(&mut self, u: &[f64]) -> Result<(), EvalFailure> {
        self.evaluate(u, Part::Full)
    }

    /// Make sure the point evaluations' values (f, α_s, the tensions, sin θ, cos θ) are
    /// those at `u`; their derivatives may be another state's until [`Self::evaluate_at`].
    pub fn evaluate_values_at(&mut self, u: &[f64]) -> Result<(), EvalFailure> {
        self.evaluate(u, Part::Values)
    }

    /// The point evaluations of the last state evaluated.
    pub fn evaluations(&self) -> &Evaluations {
        &self.evals
    }

    /// Typical sizes of the five unknowns, for KINSOL's scaling: κ ~ 1/R, r ~ R, θ ~ 1,
    /// t_s ~ ΔP R / 2 (Laplace), q_s ~ t_s (the first integral balances them).
    pub fn typical(&self, r0: f64) -> Vec5 {
        let ts = (0.5 * self.shell.dp * r0).max(1e-3 * self.shell.law.c * self.data.above[0].zeta);
        Vec5::new(1.0 / r0, r0, 1.0, ts, ts)
    }

    /// (u_scale, f_scale): the inverse typical size of each unknown and each equation.
    pub fn scales(&self, r0: f64) -> (Vec<f64>, Vec<f64>) {
        let typ = self.typical(r0);
        let n = self.len();
        let u_scale: Vec<f64> = (0..n).map(|k| 1.0 / typ[k % NY]).collect();
        let mut f_scale = vec![0.0; n];
        f_scale[0] = 1.0 / typ[R];
        f_scale[1] = 1.0 / typ[THETA];
        f_scale[2] = 1.0 / typ[TS];
        for k in POLE_ROWS..n - 2 {
            f_scale[k] = 1.0 / typ[(k - POLE_ROWS) % NY];
        }
        f_scale[n - 2] = 1.0 / typ[R];
        f_scale[n - 1] = 1.0 / typ[THETA];
        (u_scale, f_scale)
    }

    /// The equation (row) a residual index belongs to, and the node it sits at.
    pub fn locate_row(&self, row: usize) -> (usize, &'static str) {
        let n = self.len();
        if row < POLE_ROWS {
            (
                0,
                [
                    "pole r = σ_ε α_s",
                    "pole θ = σ_ε α_s κ",
                    "pole first integral",
                ][row],
            )
        } else if row >= n - 2 {
            (
                self.mesh.len() - 1,
                ["cornea r = r*", "cornea θ = θ*"][row + 2 - n],
            )
        } else {
            let i = (row - POLE_ROWS) / NY;
            (i, equations::NAMES[(row - POLE_ROWS) % NY])
        }
    }
}

/// A dense n×n matrix that the Jacobian can be written into, for tests and diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseSink {
    pub n: usize,
    pub data: Vec<f64>,
}

impl DenseSink {
    pub fn new(n: usize) -> Self {
        DenseSink {
            n,
            data: vec![0.0; n * n],
        }
    }
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.n + j]
    }
}

impl MatrixSink for DenseSink {
    fn nrows(&self) -> usize {
        self.n
    }
    fn set(&mut self, i: usize, j: usize, v: f64) {
        self.data[i * self.n + j] = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::settings::SolverSettings;
    use crate::bvp::solve::{discretise, sphere_guess};
    use crate::model::params::{Params, Thickness};

    /// The residual and Jacobian of a fibre-free scene, built from `Equations<NoFibres>`,
    /// against the same scene forced through the fibre component with D = 0: the two
    /// assemblies share no constitutive code path, and agree to round-off.
    #[test]
    fn fibre_free_assembly_matches_the_fibre_component_with_zero_stiffness() {
        let p = Params {
            thickness: Thickness::NonUniform,
            d: 0.0,
            ..Params::default()
        };
        let s = SolverSettings {
            nodes: 41,
            ..SolverSettings::default()
        };
        let mut plain = discretise(&p, &s).unwrap();
        let mut forced = discretise(&p, &s).unwrap();
        forced.shell.law.d = Some(0.0);
        assert_eq!(plain.shell.membrane(), Membrane::NeoHookean { c: p.c });
        assert_eq!(
            forced.shell.membrane(),
            Membrane::Reinforced { c: p.c, d: 0.0 }
        );
        let mut u = sphere_guess(&plain, p.r0);
        for (k, v) in u.iter_mut().enumerate() {
            *v *= 1.0 + 1e-3 * ((k % 7) as f64 - 3.0); // off the sphere, so every term counts
        }
        let n = plain.len();
        let (mut fa, mut fb) = (vec![0.0; n], vec![0.0; n]);
        plain.residual(&u, &mut fa).unwrap();
        forced.residual(&u, &mut fb).unwrap();
        let scale = fa.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (a, b) in fa.iter().zip(&fb) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
        }
        let (mut ja, mut jb) = (DenseSink::new(n), DenseSink::new(n));
        plain.jacobian(&u, &mut ja).unwrap();
        forced.jacobian(&u, &mut jb).unwrap();
        for (a, b) in ja.data.iter().zip(&jb.data) {
            assert!((a - b).abs() <= 1e-11 * (1.0 + a.abs()), "{a} vs {b}");
        }
    }

    /// A residual's values at u, completed by a Jacobian at the same u, and a values-only
    /// pass that finds the full one already there, give every number a fresh full
    /// evaluation gives, with and without fibres; a Jacobian at a state evaluated for its
    /// values only at another state is that state's own.
    #[test]
    fn values_completed_later_are_a_full_evaluation() {
        for d in [0.0, 150.0] {
            let p = Params {
                thickness: Thickness::NonUniform,
                d,
                ..Params::default()
            };
            let s = SolverSettings {
                nodes: 41,
                ..SolverSettings::default()
            };
            let fresh = discretise(&p, &s).unwrap();
            let mut u = sphere_guess(&fresh, p.r0);
            for (k, v) in u.iter_mut().enumerate() {
                *v *= 1.0 + 1e-3 * ((k % 7) as f64 - 3.0);
            }
            let mut v = u.clone();
            v[7] *= 1.0 + 1e-4;
            let n = fresh.len();
            let jacobian_of = |disc: &mut Discretisation, at: &[f64]| {
                let mut j = DenseSink::new(n);
                disc.jacobian(at, &mut j).unwrap();
                j.data
            };
            let residual_of = |disc: &mut Discretisation, at: &[f64]| {
                let mut f = vec![0.0; n];
                disc.residual(at, &mut f).unwrap();
                f
            };
            // Each path starts from the same previous evaluation (v's), as α_s is seeded
            // from it.
            let mut full = discretise(&p, &s).unwrap();
            residual_of(&mut full, &v);
            let j_full = jacobian_of(&mut full, &u);
            let f_full = residual_of(&mut full, &u);
            let mut split = discretise(&p, &s).unwrap();
            residual_of(&mut split, &v);
            let f_split = residual_of(&mut split, &u);
            let j_split = jacobian_of(&mut split, &u);
            assert_eq!(f_split, f_full);
            assert_eq!(j_split, j_full);
            // A values-only pass at u after v's, then the Jacobian at v: v's, recomputed.
            let mut back = discretise(&p, &s).unwrap();
            residual_of(&mut back, &u);
            let j_u = jacobian_of(&mut back, &u);
            residual_of(&mut back, &v);
            let j_v = jacobian_of(&mut back, &v);
            assert_ne!(j_u, j_v);
            let mut only_v = discretise(&p, &s).unwrap();
            residual_of(&mut only_v, &u);
            assert_eq!(jacobian_of(&mut only_v, &v), j_v);
        }
    }
}
