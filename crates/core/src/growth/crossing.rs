//! The blue depth where the retina crosses the polar angle φ_max (docs/MODEL.md §6): beyond
//! φ_max every point's visual stimulus is this one value, interpolated in φ from the growth
//! points that straddle the crossing, so that the rule does not hang on where the nodes fall.
//!
//! The interpolant is the cubic through the four points (in Σ order) around the crossing,
//! two on each side (fewer at the ends of the shell). Why not the line through the two
//! straddling points: as the shell grows the crossing passes from one pair of points to the
//! next, and there the interpolated depth's rate of change jumps by the change of the
//! chord's slope, O(Δφ) of d''. That jump reaches the growth rate of every point beyond
//! φ_max at once: a kink that the time integrators see as a local error far above the
//! tolerance at tight settings (measured on the const scene at rtol 1e-9: an error-test
//! failure at nearly every change of pair, the order falling to 1 and steps of 2e-5, and
//! an error in axial length stuck near 1e-7 whatever the tolerance). With the cubic the
//! jump is O(Δφ³) of d'''' and the kinks left are the model's own ([·]⁺).

/// At most this many points enter the interpolant.
pub const STENCIL: usize = 4;

/// The interpolated depth and, for its derivatives, the points it reads: each with its
/// Lagrange weight L_i(φ_max) and the interpolant's slope p'(φ_i) there, so that
/// ∂D* = Σ_i L_i (∂d_i − p'(φ_i) ∂φ_i) (moving a node φ_i with its value fixed changes the
/// interpolant by −p'(φ_i) L_i per unit).
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    pub value: f64,
    /// (point, weight, slope); the first `len` are used.
    pub stencil: [(usize, f64, f64); STENCIL],
    pub len: usize,
}

impl Crossing {
    pub fn points(&self) -> &[(usize, f64, f64)] {
        &self.stencil[..self.len]
    }
}

/// The crossing of φ_max along the points `order` (in Σ order), with each point's angle
/// and depth; None if no point reaches φ_max. If the first point is already beyond it, its
/// own depth. Where the four points' angles do not increase strictly (a retina folding
/// back), the line through the two straddling points.
pub fn crossing(
    order: &[usize],
    angle: impl Fn(usize) -> f64,
    depth: impl Fn(usize) -> f64,
    phi_max: f64,
) -> Option<Crossing> {
    let j = order.iter().position(|&k| angle(k) >= phi_max)?;
    let mut c = Crossing {
        value: 0.0,
        stencil: [(0, 0.0, 0.0); STENCIL],
        len: 0,
    };
    if j == 0 {
        let k = order[0];
        c.value = depth(k);
        c.stencil[0] = (k, 1.0, 0.0);
        c.len = 1;
        return Some(c);
    }
    let wide = &order[j.saturating_sub(2)..(j + 2).min(order.len())];
    let increasing = wide
        .windows(2)
        .all(|w| angle(w[1]) > angle(w[0]) && angle(w[0]).is_finite());
    let points = if increasing { wide } else { &order[j - 1..=j] };
    let n = points.len();
    let mut x = [0.0; STENCIL];
    let mut y = [0.0; STENCIL];
    for (i, &k) in points.iter().enumerate() {
        (x[i], y[i]) = (angle(k), depth(k));
    }
    let (x, y) = (&x[..n], &y[..n]);
    let weights: Vec<f64> = (0..n).map(|m| lagrange(x, m, phi_max)).collect();
    c.value = weights.iter().zip(y).map(|(w, v)| w * v).sum();
    for (i, &k) in points.iter().enumerate() {
        let slope: f64 = (0..n).map(|m| y[m] * lagrange_slope(x, m, x[i])).sum();
        c.stencil[i] = (k, weights[i], slope);
    }
    c.len = n;
    Some(c)
}

/// L_m(t) = Π_{l≠m} (t − x_l)/(x_m − x_l).
fn lagrange(x: &[f64], m: usize, t: f64) -> f64 {
    (0..x.len())
        .filter(|&l| l != m)
        .map(|l| (t - x[l]) / (x[m] - x[l]))
        .product()
}

/// L_m'(t) = Σ_{q≠m} 1/(x_m − x_q) Π_{l≠m,q} (t − x_l)/(x_m − x_l).
fn lagrange_slope(x: &[f64], m: usize, t: f64) -> f64 {
    (0..x.len())
        .filter(|&q| q != m)
        .map(|q| {
            let rest: f64 = (0..x.len())
                .filter(|&l| l != m && l != q)
                .map(|l| (t - x[l]) / (x[m] - x[l]))
                .product();
            rest / (x[m] - x[q])
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic is reproduced exactly, with its slope at the nodes; the derivative rule
    /// ∂D* = Σ L_i (∂d_i − p'(φ_i) ∂φ_i) matches differences of the interpolated value.
    #[test]
    fn the_cubic_is_exact_and_its_derivatives_match_differences() {
        let f = |t: f64| 1.0 + 2.0 * t - 3.0 * t * t + 0.5 * t * t * t;
        let df = |t: f64| 2.0 - 6.0 * t + 1.5 * t * t;
        let angles = [0.1, 0.25, 0.33, 0.5, 0.61, 0.8];
        let order: Vec<usize> = (0..angles.len()).collect();
        let phi_max = 0.45;
        let c = crossing(&order, |k| angles[k], |k| f(angles[k]), phi_max).unwrap();
        assert_eq!(c.len, 4);
        assert_eq!(
            c.points().iter().map(|p| p.0).collect::<Vec<_>>(),
            [1, 2, 3, 4]
        );
        assert!((c.value - f(phi_max)).abs() < 1e-14, "{}", c.value);
        for &(k, _, s) in c.points() {
            assert!((s - df(angles[k])).abs() < 1e-12, "{k}: {s}");
        }
        // Perturb each node's angle and value: the first-order change is the rule's.
        let depths: Vec<f64> = angles
            .iter()
            .map(|&a| f(a) + 0.01 * (7.0 * a).sin())
            .collect();
        let base = crossing(&order, |k| angles[k], |k| depths[k], phi_max).unwrap();
        let h = 1e-7;
        for &(k, w, s) in base.points() {
            let mut a2 = angles;
            a2[k] += h;
            let moved = crossing(&order, |i| a2[i], |i| depths[i], phi_max).unwrap();
            let da = (moved.value - base.value) / h;
            assert!((da - (-w * s)).abs() < 1e-5, "∂/∂φ_{k}: {da} vs {}", -w * s);
            let mut d2 = depths.clone();
            d2[k] += h;
            let moved = crossing(&order, |i| angles[i], |i| d2[i], phi_max).unwrap();
            let dd = (moved.value - base.value) / h;
            assert!((dd - w).abs() < 1e-6, "∂/∂d_{k}: {dd} vs {w}");
        }
    }

    /// At the ends of the shell fewer points enter; a fold or a NaN angle falls back to the
    /// chord; no point at φ_max gives None, and a first point beyond it gives its own depth.
    #[test]
    fn ends_folds_and_absent_crossings() {
        let order = [0, 1, 2];
        let c = crossing(&order, |k| [0.1, 0.2, 0.3][k], |k| k as f64, 0.25).unwrap();
        assert_eq!(c.len, 3);
        assert!((c.value - 1.5).abs() < 1e-14);
        // Angles 0.1, 0.4, 0.2, 0.5: not increasing, so the chord between 0.2 and 0.5.
        let order = [0, 1, 2, 3];
        let ang = [0.1, 0.4, 0.2, 0.5];
        let c = crossing(&order, |k| ang[k], |k| 10.0 * ang[k], 0.35).unwrap();
        assert_eq!(c.len, 2);
        assert_eq!((c.stencil[0].0, c.stencil[1].0), (0, 1));
        assert!((c.value - 3.5).abs() < 1e-14);
        assert!(crossing(&order, |k| ang[k], |k| k as f64, 0.9).is_none());
        let c = crossing(&order, |k| ang[k], |k| 1.0 + k as f64, 0.05).unwrap();
        assert_eq!((c.len, c.value), (1, 1.0));
        // A NaN angle beside the straddling pair: the chord, still finite.
        let with_nan = [f64::NAN, 0.2, 0.4, 0.5];
        let c = crossing(&order, |k| with_nan[k], |k| 10.0 * with_nan[k], 0.3).unwrap();
        assert_eq!((c.len, c.stencil[0].0, c.stencil[1].0), (2, 1, 2));
        assert!((c.value - 3.0).abs() < 1e-14);
    }
}
