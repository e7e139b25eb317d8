//! A continuous interpolant of the discrete solution, like bvp4c's deval: on each interval
//! the cubic Hermite polynomial through the node values and the slopes f(Σ, y) the scheme
//! used at the interval's ends (one-sided at breakpoints). It is C⁰ everywhere, C¹ where the
//! data are smooth, and O(h⁴) accurate, so it does not spoil Hermite–Simpson's order.

use crate::mesh::Mesh;

/// Quantities interpolated: κ, r, θ, q_s, t_s and the quadratures s, z.
pub const NQ: usize = 7;

#[derive(Clone, Debug, PartialEq)]
pub struct Interpolant {
    /// Values at the nodes.
    pub values: Vec<[f64; NQ]>,
    /// d/dΣ at interval i's left end, from inside the interval.
    pub slope_left: Vec<[f64; NQ]>,
    /// d/dΣ at interval i's right end, from inside the interval.
    pub slope_right: Vec<[f64; NQ]>,
}

impl Interpolant {
    /// The interpolated quantities at Σ = `x` inside interval `i` of `mesh`.
    pub fn eval(&self, mesh: &Mesh, i: usize, x: f64) -> [f64; NQ] {
        let (x0, h) = (mesh.nodes[i], mesh.step(i));
        let t = (x - x0) / h;
        let t2 = t * t;
        let t3 = t2 * t;
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + t;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        let (v0, v1) = (&self.values[i], &self.values[i + 1]);
        let (m0, m1) = (&self.slope_left[i], &self.slope_right[i]);
        std::array::from_fn(|k| h00 * v0[k] + h10 * h * m0[k] + h01 * v1[k] + h11 * h * m1[k])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic is reproduced exactly.
    #[test]
    fn reproduces_cubics() {
        let mesh = Mesh::new(0.0 + 1e-3, 2.0, 5, &[], false).unwrap();
        let p = |x: f64| 1.0 - 2.0 * x + 0.5 * x * x * x;
        let dp = |x: f64| -2.0 + 1.5 * x * x;
        let values = mesh.nodes.iter().map(|&x| [p(x); NQ]).collect();
        let slope_left = mesh.nodes.windows(2).map(|w| [dp(w[0]); NQ]).collect();
        let slope_right = mesh.nodes.windows(2).map(|w| [dp(w[1]); NQ]).collect();
        let it = Interpolant {
            values,
            slope_left,
            slope_right,
        };
        for k in 0..40 {
            let x = 1e-3 + (2.0 - 1e-3) * k as f64 / 39.0;
            let i = mesh.locate(x).unwrap();
            assert!((it.eval(&mesh, i, x)[3] - p(x)).abs() < 1e-14);
        }
    }
}
