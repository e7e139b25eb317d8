//! The reinforced neo-Hookean membrane law and its exact partial derivatives (MODEL.md §2).
//!
//!   t_s = 2ζ [ C(α_s/α_φ − (α_s α_φ)⁻³) + D [I4−1]⁺ (α_s/α_φ) sin²ψ ]
//!   t_φ = 2ζ [ C(α_φ/α_s − (α_s α_φ)⁻³) + D [I4−1]⁺ (α_φ/α_s) cos²ψ ]
//! with I4 = α_s² sin²ψ + α_φ² cos²ψ. Fibres resist extension only ([·]⁺).
//!
//! The discretisation carries t_s as an unknown, so it needs α_s from (t_s, α_φ): t_s is
//! strictly increasing in α_s (∂t_s/∂α_s > 0 for every α_s, α_φ > 0), so the inverse is
//! unique and [`alpha_s_from_ts`] finds it by a safeguarded Newton iteration.

/// The fibre direction at a material point: sin²ψ and cos²ψ (ψ measured from e_φ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FibreDirection {
    pub sin2: f64,
    pub cos2: f64,
}

impl FibreDirection {
    pub fn from_angle(psi: f64) -> Self {
        let s = psi.sin();
        let c = psi.cos();
        FibreDirection { sin2: s * s, cos2: c * c }
    }
}

/// The constitutive constants: C and, when the scene has fibres, D.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Law {
    pub c: f64,
    /// D; the fibre terms are skipped entirely when `None`.
    pub d: Option<f64>,
}

/// The membrane tensions at a point and their partial derivatives in (α_s, α_φ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tensions {
    pub ts: f64,
    pub tphi: f64,
    pub ts_a: f64,
    pub ts_phi: f64,
    pub tphi_a: f64,
    pub tphi_phi: f64,
}

impl Law {
    /// t_s, t_φ and their exact derivatives at stretches (a, phi) = (α_s, α_φ), thickness ζ.
    #[inline]
    pub fn tensions(&self, zeta: f64, fibre: Option<FibreDirection>, a: f64, phi: f64) -> Tensions {
        let k = 2.0 * zeta;
        let c = self.c;
        let inv_a = 1.0 / a;
        let inv_phi = 1.0 / phi;
        let j3 = (a * phi).powi(-3); // (α_s α_φ)⁻³
        let mut t = Tensions {
            ts: c * (a * inv_phi - j3),
            tphi: c * (phi * inv_a - j3),
            ts_a: c * (inv_phi + 3.0 * j3 * inv_a),
            ts_phi: c * (-a * inv_phi * inv_phi + 3.0 * j3 * inv_phi),
            tphi_a: c * (-phi * inv_a * inv_a + 3.0 * j3 * inv_a),
            tphi_phi: c * (inv_a + 3.0 * j3 * inv_phi),
        };
        if let (Some(d), Some(f)) = (self.d, fibre) {
            let i4m1 = a * a * f.sin2 + phi * phi * f.cos2 - 1.0;
            if i4m1 > 0.0 {
                // t_s fibre part: D e (a/φ) s², e = I4 − 1, ∂e/∂a = 2 a s², ∂e/∂φ = 2 φ c².
                let (e_a, e_phi) = (2.0 * a * f.sin2, 2.0 * phi * f.cos2);
                let rs = a * inv_phi * f.sin2; // (a/φ) s²
                let rp = phi * inv_a * f.cos2; // (φ/a) c²
                t.ts += d * i4m1 * rs;
                t.tphi += d * i4m1 * rp;
                t.ts_a += d * (e_a * rs + i4m1 * inv_phi * f.sin2);
                t.ts_phi += d * (e_phi * rs - i4m1 * a * inv_phi * inv_phi * f.sin2);
                t.tphi_a += d * (e_a * rp - i4m1 * phi * inv_a * inv_a * f.cos2);
                t.tphi_phi += d * (e_phi * rp + i4m1 * inv_a * f.cos2);
            }
        }
        t.ts *= k;
        t.tphi *= k;
        t.ts_a *= k;
        t.ts_phi *= k;
        t.tphi_a *= k;
        t.tphi_phi *= k;
        t
    }

    /// α_s such that t_s(α_s, α_φ) = `ts`, with the tensions there. `guess` > 0 seeds Newton.
    ///
    /// t_s is increasing and, without fibres, concave in α_s, so Newton from any point lands
    /// right of the root and then falls monotonically; a bracket guards the fibre case.
    /// Returns `None` for non-finite input, or if 100 safeguarded steps do not converge.
    pub fn alpha_s_from_ts(
        &self,
        zeta: f64,
        fibre: Option<FibreDirection>,
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)> {
        if !(ts.is_finite() && phi.is_finite() && phi > 0.0) {
            return None;
        }
        let mut a = if guess.is_finite() && guess > 0.0 { guess } else { 1.0 };
        let (mut lo, mut hi) = (0.0_f64, f64::INFINITY);
        for _ in 0..100 {
            let t = self.tensions(zeta, fibre, a, phi);
            let g = t.ts - ts;
            if g > 0.0 {
                hi = hi.min(a);
            } else {
                lo = lo.max(a);
            }
            let step = g / t.ts_a;
            if g == 0.0 || step.abs() <= 2.0 * f64::EPSILON * a {
                let a = a - step;
                return Some((a, self.tensions(zeta, fibre, a, phi)));
            }
            // A root on the fibres' kink (I4 = 1) can leave Newton's step from the soft side
            // above the tolerance while the bracket has shrunk to adjacent doubles.
            if hi.is_finite() && hi - lo <= 2.0 * f64::EPSILON * hi {
                return Some((a, t));
            }
            let mut next = a - step;
            if !(next > lo && next < hi) {
                next = if hi.is_finite() { 0.5 * (lo + hi) } else { 2.0 * a.max(lo) };
            }
            a = next;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check(law: Law, fibre: Option<FibreDirection>, a: f64, phi: f64) {
        let h = 1e-6;
        let t = law.tensions(0.6, fibre, a, phi);
        let dp = |f: &dyn Fn(f64, f64) -> f64, da: f64, dphi: f64| {
            (f(a + da, phi + dphi) - f(a - da, phi - dphi)) / (2.0 * h)
        };
        let ts = |x: f64, y: f64| law.tensions(0.6, fibre, x, y).ts;
        let tp = |x: f64, y: f64| law.tensions(0.6, fibre, x, y).tphi;
        for (exact, approx) in [
            (t.ts_a, dp(&ts, h, 0.0)),
            (t.ts_phi, dp(&ts, 0.0, h)),
            (t.tphi_a, dp(&tp, h, 0.0)),
            (t.tphi_phi, dp(&tp, 0.0, h)),
        ] {
            assert!((exact - approx).abs() < 1e-6 * (1.0 + exact.abs()), "{exact} vs {approx}");
        }
    }

    #[test]
    fn derivatives_match_central_differences() {
        let f = Some(FibreDirection::from_angle(0.9));
        for (a, phi) in [(1.01, 1.02), (1.2, 0.95), (0.9, 1.3), (1.05, 1.05)] {
            fd_check(Law { c: 100.0, d: None }, None, a, phi);
            fd_check(Law { c: 100.0, d: Some(200.0) }, f, a, phi);
        }
    }

    #[test]
    fn inverse_recovers_the_stretch() {
        let f = Some(FibreDirection::from_angle(1.2));
        for law in [Law { c: 100.0, d: None }, Law { c: 100.0, d: Some(400.0) }] {
            for a in [0.3, 0.97, 1.0137, 1.4, 3.0] {
                let ts = law.tensions(0.65, f, a, 1.02).ts;
                for guess in [0.1, 1.0, 10.0] {
                    let (b, _) = law.alpha_s_from_ts(0.65, f, ts, 1.02, guess).unwrap();
                    assert!((a - b).abs() < 1e-13 * a, "{a} vs {b} from {guess}");
                }
            }
        }
    }

    #[test]
    fn fibres_do_not_resist_compression() {
        let law = Law { c: 100.0, d: Some(400.0) };
        let f = Some(FibreDirection::from_angle(0.7));
        let with = law.tensions(0.65, f, 0.95, 0.97);
        let without = Law { d: None, ..law }.tensions(0.65, None, 0.95, 0.97);
        assert_eq!(with, without);
    }
}
#[cfg(test)]
mod stiff_fibres {
    use super::*;

    /// Stiff fibres (D = 1e5 ≫ C) put roots on the kink I4 = 1; the inverse must still
    /// find them, to the last bit the kink allows.
    #[test]
    fn inverse_finds_roots_on_the_fibre_kink() {
        let law = Law { c: 100.0, d: Some(1e5) };
        for k in 0..400 {
            let dir = FibreDirection::from_angle(0.2 + 1.2 * (k % 20) as f64 / 20.0);
            let f = Some(dir);
            let phi = 0.95 + 0.1 * (k / 20) as f64 / 20.0;
            // The stretch at which the fibres come taut, and points around it.
            let kink = ((1.0 - phi * phi * dir.cos2) / dir.sin2).max(0.0).sqrt();
            for a in [0.9, kink * (1.0 - 1e-12), kink, kink * (1.0 + 1e-12), 1.05] {
                if !(a > 0.0) {
                    continue;
                }
                let ts = law.tensions(0.5, f, a, phi).ts;
                for guess in [0.5, 1.0, 2.0] {
                    let (b, _) = law.alpha_s_from_ts(0.5, f, ts, phi, guess).expect("no root found");
                    assert!((a - b).abs() < 1e-12, "a = {a}, found {b}");
                }
            }
        }
    }
}
