//! The reinforced neo-Hookean membrane law and its exact partial derivatives (docs/MODEL.md §2).
//!
//!   t_s = 2ζ [ C(α_s/α_φ − (α_s α_φ)⁻³) + D [I4−1]⁺ (α_s/α_φ) sin²ψ ]
//!   t_φ = 2ζ [ C(α_φ/α_s − (α_s α_φ)⁻³) + D [I4−1]⁺ (α_φ/α_s) cos²ψ ]
//! with I4 = α_s² sin²ψ + α_φ² cos²ψ. Fibres resist extension only ([·]⁺).
//!
//! The fibres are a component of the law, chosen at compile time: [`MembraneLaw<R>`] is
//! generic over a [`Reinforcement`], either [`NoFibres`] (zero-sized: no D, no ψ, not a
//! single fibre operation or branch) or [`Fibres`]. The scene picks one once
//! (`model::components::Membrane`), and the point evaluation and the assembly loop are
//! monomorphised for it. [`Law`] keeps the run-time form (`d: Option<f64>`) for code that
//! holds one law of either kind; its methods dispatch once per call.
//!
//! The discretisation carries t_s as an unknown, so it needs α_s from (t_s, α_φ): t_s is
//! strictly increasing in α_s (∂t_s/∂α_s > 0 for every α_s, α_φ > 0), so the inverse is
//! unique. Each reinforcement inverts in its own way (see [`Reinforcement::alpha_s`]):
//! without fibres t_s is smooth and concave in α_s and Halley's method needs no bracket;
//! with fibres a safeguarded Newton iteration copes with the kink at I4 = 1.

use std::fmt::Debug;

/// The fibre direction at a material point: sin²ψ and cos²ψ (ψ measured from e_φ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FibreDirection {
    pub sin2: f64,
    pub cos2: f64,
}

impl FibreDirection {
    /// A point that has no fibre direction: I4 − 1 = −1 < 0, so the fibres are slack there
    /// and add exactly nothing (the [`Fibres`] component's stand-in for "no ψ here").
    pub const SLACK: FibreDirection = FibreDirection {
        sin2: 0.0,
        cos2: 0.0,
    };

    pub fn from_angle(psi: f64) -> Self {
        let s = psi.sin();
        let c = psi.cos();
        FibreDirection {
            sin2: s * s,
            cos2: c * c,
        }
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

/// The stretches at a point and their reciprocals, shared by the law's parts.
#[derive(Clone, Copy, Debug)]
pub struct Stretches {
    pub a: f64,
    pub phi: f64,
    pub inv_a: f64,
    pub inv_phi: f64,
}

/// What reinforces the neo-Hookean matrix (docs/MODEL.md §2): nothing, or one family of fibres.
pub trait Reinforcement: Copy + Debug {
    /// What the reinforcement reads at a material point: `()` without fibres.
    type Direction: Copy + Debug;

    /// The direction at a point from its stored fibre data (never read without fibres).
    fn direction(fibre: &Option<FibreDirection>) -> Self::Direction;

    /// Add the reinforcement's part of the tensions, before the common factor 2ζ.
    fn add_tensions(&self, dir: Self::Direction, s: &Stretches, t: &mut Tensions);

    /// α_s such that t_s(α_s, α_φ) = `ts`, with the tensions there (`guess` > 0 seeds the
    /// iteration). `None` for non-finite input or when the iteration does not converge.
    fn alpha_s(
        law: &MembraneLaw<Self>,
        zeta: f64,
        dir: Self::Direction,
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)>;
}

/// The neo-Hookean membrane alone (D = 0): ψ is not part of the model.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoFibres;

/// One family of fibres of stiffness D along ψ(Σ), resisting extension only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fibres {
    pub d: f64,
}

/// The membrane law C with the reinforcement R, fixed at compile time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneLaw<R: Reinforcement> {
    pub c: f64,
    pub reinforcement: R,
}

/// The most iterations of an α_s inversion before it gives up.
const MAX_ITERATIONS: usize = 100;

impl Reinforcement for NoFibres {
    type Direction = ();

    #[inline(always)]
    fn direction(_: &Option<FibreDirection>) {}

    #[inline(always)]
    fn add_tensions(&self, _: (), _: &Stretches, _: &mut Tensions) {}

    /// Halley's method on g(a) = a/φ − (aφ)⁻³ − τ, τ = t_s / (2ζC), with only g, g', g''
    /// computed per step (one division for (aφ)⁻¹, one for the step) and the full
    /// [`Tensions`] once, at the root.
    ///
    /// g is increasing and concave (g' = 1/φ + 3(aφ)⁻³/a > 0, g'' = −12(aφ)⁻³/a² < 0), so no
    /// bracket is needed: Newton's step from the left of the root never overshoots it, and
    /// from the right it can only fall short of 0 (then a is halved instead). Halley's step
    /// g/g' · 1/(1 − ℓ), ℓ = g g''/(2g'²), is taken while |ℓ| < 1/2 (it damps the step right
    /// of the root and lengthens it left of it), else Newton's. Convergence is cubic, and the
    /// iteration stops as soon as even a Newton step from the new point, of error
    /// |g''|/(2g') δ², would change nothing above round-off: a guess 1e-9 away takes one
    /// step, 1e-6 to 1e-3 away two, 1e-2 to 1e-1 away three, where the safeguarded Newton
    /// iteration (with its test on the step) took 2, 3–4 and 5–6 full evaluations. The
    /// roots agree to 1 ulp.
    fn alpha_s(
        law: &MembraneLaw<Self>,
        zeta: f64,
        _: (),
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)> {
        if !(ts.is_finite() && phi.is_finite() && phi > 0.0) {
            return None;
        }
        let tau = ts / (2.0 * zeta * law.c);
        if !tau.is_finite() {
            return None;
        }
        let inv_phi = 1.0 / phi;
        let mut a = if guess.is_finite() && guess > 0.0 {
            guess
        } else {
            1.0
        };
        for _ in 0..MAX_ITERATIONS {
            let j = (a * phi).recip(); // (aφ)⁻¹
            let inv_a = j * phi;
            let j3 = j * j * j;
            let g = a * inv_phi - j3 - tau;
            let g1 = inv_phi + 3.0 * j3 * inv_a;
            let g2 = -12.0 * j3 * inv_a * inv_a;
            let step = if (g * g2).abs() < g1 * g1 {
                2.0 * g * g1 / (2.0 * g1 * g1 - g * g2)
            } else {
                g / g1
            };
            let next = a - step;
            // |g''|/(2g') δ² ≤ ε a / 4, without a division.
            if g2.abs() * step * step <= 0.5 * f64::EPSILON * a * g1
                || step.abs() <= 2.0 * f64::EPSILON * a
            {
                return Some((next, law.tensions(zeta, (), next, phi)));
            }
            a = if next > 0.0 && next.is_finite() {
                next
            } else {
                0.5 * a
            };
        }
        None
    }
}

impl Reinforcement for Fibres {
    type Direction = FibreDirection;

    /// A point without a stored direction gets [`FibreDirection::SLACK`]: no fibre terms.
    #[inline(always)]
    fn direction(fibre: &Option<FibreDirection>) -> FibreDirection {
        fibre.unwrap_or(FibreDirection::SLACK)
    }

    #[inline(always)]
    fn add_tensions(&self, f: FibreDirection, s: &Stretches, t: &mut Tensions) {
        let Stretches {
            a,
            phi,
            inv_a,
            inv_phi,
        } = *s;
        let d = self.d;
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

    /// Safeguarded Newton: the fibres' kink at I4 = 1 makes t_s convex on one side and
    /// concave on the other, so a bracket [lo, hi] keeps every step inside the interval
    /// known to hold the root, bisecting when Newton's step would leave it.
    fn alpha_s(
        law: &MembraneLaw<Self>,
        zeta: f64,
        dir: FibreDirection,
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)> {
        if !(ts.is_finite() && phi.is_finite() && phi > 0.0) {
            return None;
        }
        let mut a = if guess.is_finite() && guess > 0.0 {
            guess
        } else {
            1.0
        };
        let (mut lo, mut hi) = (0.0_f64, f64::INFINITY);
        for _ in 0..MAX_ITERATIONS {
            // t_s and ∂t_s/∂α_s alone: the full tensions are needed only at the root.
            let (t_s, t_s_a) = law.ts_and_slope(zeta, dir, a, phi);
            let g = t_s - ts;
            if g > 0.0 {
                hi = hi.min(a);
            } else {
                lo = lo.max(a);
            }
            let step = g / t_s_a;
            if g == 0.0 || step.abs() <= 2.0 * f64::EPSILON * a {
                let a = a - step;
                return Some((a, law.tensions(zeta, dir, a, phi)));
            }
            // A root on the fibres' kink (I4 = 1) can leave Newton's step from the soft side
            // above the tolerance while the bracket has shrunk to adjacent doubles.
            if hi.is_finite() && hi - lo <= 2.0 * f64::EPSILON * hi {
                return Some((a, law.tensions(zeta, dir, a, phi)));
            }
            let mut next = a - step;
            if !(next > lo && next < hi) {
                next = if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * a.max(lo)
                };
            }
            a = next;
        }
        None
    }
}

impl MembraneLaw<NoFibres> {
    /// The neo-Hookean membrane of modulus C.
    pub fn neo_hookean(c: f64) -> Self {
        MembraneLaw {
            c,
            reinforcement: NoFibres,
        }
    }
}

impl MembraneLaw<Fibres> {
    /// The neo-Hookean membrane of modulus C reinforced by fibres of stiffness D.
    pub fn reinforced(c: f64, d: f64) -> Self {
        MembraneLaw {
            c,
            reinforcement: Fibres { d },
        }
    }
}

impl MembraneLaw<Fibres> {
    /// t_s and ∂t_s/∂α_s of [`MembraneLaw::tensions`], by the same operations in the same
    /// order (so equal to the last bit, which keeps the α_s inversion's iterates and root
    /// exactly those of the full law), without the other four numbers: the inversion's
    /// Newton steps read only these, and they are most of its cost.
    #[inline(always)]
    fn ts_and_slope(&self, zeta: f64, f: FibreDirection, a: f64, phi: f64) -> (f64, f64) {
        let k = 2.0 * zeta;
        let c = self.c;
        let j = (a * phi).recip();
        let inv_a = j * phi;
        let inv_phi = j * a;
        let j3 = j * j * j;
        let mut ts = c * (a * inv_phi - j3);
        let mut ts_a = c * (inv_phi + 3.0 * j3 * inv_a);
        let d = self.reinforcement.d;
        let i4m1 = a * a * f.sin2 + phi * phi * f.cos2 - 1.0;
        if i4m1 > 0.0 {
            let e_a = 2.0 * a * f.sin2;
            let rs = a * inv_phi * f.sin2;
            ts += d * i4m1 * rs;
            ts_a += d * (e_a * rs + i4m1 * inv_phi * f.sin2);
        }
        (ts * k, ts_a * k)
    }
}

impl<R: Reinforcement> MembraneLaw<R> {
    /// t_s, t_φ and their exact derivatives at stretches (a, phi) = (α_s, α_φ), thickness ζ.
    #[inline]
    pub fn tensions(&self, zeta: f64, dir: R::Direction, a: f64, phi: f64) -> Tensions {
        let k = 2.0 * zeta;
        let c = self.c;
        // One division: 1/a = φ/(aφ), 1/φ = a/(aφ).
        let j = (a * phi).recip(); // (α_s α_φ)⁻¹
        let s = Stretches {
            a,
            phi,
            inv_a: j * phi,
            inv_phi: j * a,
        };
        let (inv_a, inv_phi) = (s.inv_a, s.inv_phi);
        let j3 = j * j * j; // (α_s α_φ)⁻³
        let mut t = Tensions {
            ts: c * (a * inv_phi - j3),
            tphi: c * (phi * inv_a - j3),
            ts_a: c * (inv_phi + 3.0 * j3 * inv_a),
            ts_phi: c * (-a * inv_phi * inv_phi + 3.0 * j3 * inv_phi),
            tphi_a: c * (-phi * inv_a * inv_a + 3.0 * j3 * inv_a),
            tphi_phi: c * (inv_a + 3.0 * j3 * inv_phi),
        };
        self.reinforcement.add_tensions(dir, &s, &mut t);
        t.ts *= k;
        t.tphi *= k;
        t.ts_a *= k;
        t.ts_phi *= k;
        t.tphi_a *= k;
        t.tphi_phi *= k;
        t
    }

    /// α_s such that t_s(α_s, α_φ) = `ts`, with the tensions there (see [`Reinforcement::alpha_s`]).
    #[inline]
    pub fn alpha_s_from_ts(
        &self,
        zeta: f64,
        dir: R::Direction,
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)> {
        R::alpha_s(self, zeta, dir, ts, phi, guess)
    }
}

impl Law {
    /// t_s, t_φ and their exact derivatives at stretches (a, phi) = (α_s, α_φ), thickness ζ.
    /// Fibre terms only when both D and the direction are given.
    #[inline]
    pub fn tensions(&self, zeta: f64, fibre: Option<FibreDirection>, a: f64, phi: f64) -> Tensions {
        match (self.d, fibre) {
            (Some(d), Some(f)) => MembraneLaw::reinforced(self.c, d).tensions(zeta, f, a, phi),
            _ => MembraneLaw::neo_hookean(self.c).tensions(zeta, (), a, phi),
        }
    }

    /// α_s such that t_s(α_s, α_φ) = `ts`, with the tensions there. `guess` > 0 seeds the
    /// iteration of the law's component (see [`Reinforcement::alpha_s`]). Returns `None`
    /// for non-finite input, or if 100 steps do not converge.
    pub fn alpha_s_from_ts(
        &self,
        zeta: f64,
        fibre: Option<FibreDirection>,
        ts: f64,
        phi: f64,
        guess: f64,
    ) -> Option<(f64, Tensions)> {
        match (self.d, fibre) {
            (Some(d), Some(f)) => {
                MembraneLaw::reinforced(self.c, d).alpha_s_from_ts(zeta, f, ts, phi, guess)
            }
            _ => MembraneLaw::neo_hookean(self.c).alpha_s_from_ts(zeta, (), ts, phi, guess),
        }
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
            assert!(
                (exact - approx).abs() < 1e-6 * (1.0 + exact.abs()),
                "{exact} vs {approx}"
            );
        }
    }

    #[test]
    fn the_inversions_slope_is_the_full_laws_to_the_bit() {
        // The α_s inversion's Newton steps read t_s and ∂t_s/∂α_s from ts_and_slope: they
        // must be the full law's to the last bit, or the inversion's roots (and every run
        // with fibres) would move. Both sides of the fibres' kink, on it, and far out.
        let mut checked = 0;
        for d in [1.0, 100.0, 400.0, 1e6] {
            let law = MembraneLaw::reinforced(100.0, d);
            for psi in [
                0.0,
                0.3,
                std::f64::consts::FRAC_PI_4,
                1.2,
                std::f64::consts::FRAC_PI_2,
            ] {
                let f = FibreDirection::from_angle(psi);
                for a in [1e-3, 0.5, 0.9, 0.999_999, 1.0, 1.000_001, 1.1, 1.7, 30.0] {
                    for phi in [0.2, 0.95, 1.0, 1.05, 2.0] {
                        for zeta in [0.3, 0.65, 1.0] {
                            let t = law.tensions(zeta, f, a, phi);
                            let (ts, ts_a) = law.ts_and_slope(zeta, f, a, phi);
                            assert_eq!(
                                ts.to_bits(),
                                t.ts.to_bits(),
                                "t_s at D {d} ψ {psi} a {a} φ {phi}"
                            );
                            assert_eq!(
                                ts_a.to_bits(),
                                t.ts_a.to_bits(),
                                "∂t_s/∂α_s at D {d} ψ {psi} a {a} φ {phi}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 4 * 5 * 9 * 5 * 3);
    }

    #[test]
    fn derivatives_match_central_differences() {
        let f = Some(FibreDirection::from_angle(0.9));
        for (a, phi) in [(1.01, 1.02), (1.2, 0.95), (0.9, 1.3), (1.05, 1.05)] {
            fd_check(Law { c: 100.0, d: None }, None, a, phi);
            fd_check(
                Law {
                    c: 100.0,
                    d: Some(200.0),
                },
                f,
                a,
                phi,
            );
        }
    }

    #[test]
    fn inverse_recovers_the_stretch() {
        let f = Some(FibreDirection::from_angle(1.2));
        for law in [
            Law { c: 100.0, d: None },
            Law {
                c: 100.0,
                d: Some(400.0),
            },
        ] {
            for a in [0.3, 0.97, 1.0137, 1.4, 3.0] {
                let ts = law.tensions(0.65, f, a, 1.02).ts;
                for guess in [0.1, 1.0, 10.0] {
                    let (b, _) = law.alpha_s_from_ts(0.65, f, ts, 1.02, guess).unwrap();
                    assert!((a - b).abs() < 1e-13 * a, "{a} vs {b} from {guess}");
                }
            }
        }
    }

    /// The fibre-free inverse (Halley, no bracket) from guesses far off on either side,
    /// over stretches from strong compression to strong extension.
    #[test]
    fn fibre_free_inverse_is_robust_and_exact() {
        let law = MembraneLaw::neo_hookean(100.0);
        for phi in [0.5, 0.97, 1.02, 1.5, 3.0] {
            for a in [0.05, 0.3, 0.8, 0.999, 1.0137, 1.2, 2.0, 7.0, 40.0] {
                let ts = law.tensions(0.65, (), a, phi).ts;
                for guess in [
                    1e-3,
                    0.1,
                    0.9,
                    a * (1.0 + 1e-3),
                    1.0,
                    5.0,
                    100.0,
                    1e4,
                    f64::NAN,
                    -1.0,
                ] {
                    let (b, t) = law
                        .alpha_s_from_ts(0.65, (), ts, phi, guess)
                        .expect("no root");
                    assert!(
                        (a - b).abs() < 2e-14 * a,
                        "φ = {phi}: {a} vs {b} from {guess}"
                    );
                    assert_eq!(t, law.tensions(0.65, (), b, phi));
                }
            }
        }
    }

    /// Without fibres the new inverse and the safeguarded Newton of the fibre component
    /// (on a slack direction, which adds nothing) agree to round-off.
    #[test]
    fn both_inverses_agree_without_fibre_tension() {
        let plain = MembraneLaw::neo_hookean(100.0);
        let slack = MembraneLaw::reinforced(100.0, 400.0);
        for (a, phi) in [(0.9, 1.1), (1.0137, 1.0137), (1.3, 0.8)] {
            let ts = plain.tensions(0.5, (), a, phi).ts;
            assert_eq!(ts, slack.tensions(0.5, FibreDirection::SLACK, a, phi).ts);
            let (x, _) = plain.alpha_s_from_ts(0.5, (), ts, phi, 1.0).unwrap();
            let (y, _) = slack
                .alpha_s_from_ts(0.5, FibreDirection::SLACK, ts, phi, 1.0)
                .unwrap();
            assert!((x - y).abs() <= 4.0 * f64::EPSILON * x, "{x} vs {y}");
        }
    }

    /// `Law` dispatches to the component its D and the point's direction call for.
    #[test]
    fn law_dispatches_to_its_component() {
        let f = FibreDirection::from_angle(0.6);
        let (a, phi) = (1.1, 1.05);
        let with = Law {
            c: 100.0,
            d: Some(300.0),
        };
        assert_eq!(
            with.tensions(0.6, Some(f), a, phi),
            MembraneLaw::reinforced(100.0, 300.0).tensions(0.6, f, a, phi)
        );
        let plain = MembraneLaw::neo_hookean(100.0).tensions(0.6, (), a, phi);
        assert_eq!(with.tensions(0.6, None, a, phi), plain);
        assert_eq!(
            Law { c: 100.0, d: None }.tensions(0.6, Some(f), a, phi),
            plain
        );
        assert_ne!(
            plain,
            MembraneLaw::reinforced(100.0, 300.0).tensions(0.6, f, a, phi)
        );
    }

    #[test]
    fn fibres_do_not_resist_compression() {
        let law = Law {
            c: 100.0,
            d: Some(400.0),
        };
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
        let law = Law {
            c: 100.0,
            d: Some(1e5),
        };
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
                    let (b, _) = law
                        .alpha_s_from_ts(0.5, f, ts, phi, guess)
                        .expect("no root found");
                    assert!((a - b).abs() < 1e-12, "a = {a}, found {b}");
                }
            }
        }
    }
}
