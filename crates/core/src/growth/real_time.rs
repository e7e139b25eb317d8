//! The real time of the schedule's clock (docs/MODEL.md §11): a scheduled run integrates the
//! constant-rate growth on τ = S(t) = ∫₀ᵗ s dt' ([`super::schedule`]), which is exact while
//! nothing but the rates depends on t. Optics that change with age read t itself, so on τ
//! the growth is p̃' = η0 f(p̃, t(τ)): its rates are the constant-rate ones of the eye whose
//! optics are those of t = S⁻¹(τ). The growth system evaluates its surfaces there
//! ([`super::system::GrowthSystem::set_real_time`]); everything else still runs on τ.
//!
//! S is non-decreasing and flat where s = 0 over an interval (a pause): τ then stands for
//! every t of the pause, and [`RealTime::at`] takes the latest, so that after a pause the
//! growth reads the optics at its end, where growth resumes (during the pause nothing grows
//! whatever the optics are).

use super::schedule::Warp;

/// t = S⁻¹(τ) of one run: its warp on [0, t_end].
#[derive(Clone, Debug)]
pub struct RealTime {
    warp: Warp,
    t_end: f64,
    tau_end: f64,
}

impl RealTime {
    /// The inverse of `warp` over the growth window [0, `t_end`].
    pub fn new(warp: Warp, t_end: f64) -> RealTime {
        let tau_end = warp.clock(t_end);
        RealTime {
            warp,
            t_end,
            tau_end,
        }
    }

    /// The latest t in [0, t_end] with S(t) ≤ τ: S⁻¹(τ) where S increases, the end of a
    /// pause where it is flat; 0 before the run, t_end at and beyond S(t_end). By bisection
    /// on the monotone S, to the last bit (S is evaluated in closed form, so it costs a few
    /// microseconds, once per time the integrator asks about).
    pub fn at(&self, tau: f64) -> f64 {
        if tau >= self.tau_end {
            return self.t_end;
        }
        if !(tau >= 0.0) {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0, self.t_end);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.warp.clock(mid) <= tau {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// S(t_end): the end of the run on the clock.
    pub fn tau_end(&self) -> f64 {
        self.tau_end
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::growth::schedule::{Clock, Form, Schedule};

    fn real_time(schedule: Schedule, t_end: f64) -> RealTime {
        RealTime::new(Warp::new(&schedule, &Clock::default()), t_end)
    }

    /// S(S⁻¹(τ)) = τ to rounding, and S⁻¹(S(t)) = t where s > 0, for the exponential form.
    #[test]
    fn the_inverse_undoes_the_clock() {
        let rt = real_time(
            Schedule {
                form: Form::Exponential,
                tau: 0.4,
                ..Schedule::default()
            },
            1.0,
        );
        let w = Warp::new(
            &Schedule {
                form: Form::Exponential,
                tau: 0.4,
                ..Schedule::default()
            },
            &Clock::default(),
        );
        for k in 0..=100 {
            let t = k as f64 / 100.0;
            let back = rt.at(w.clock(t));
            // dt = dτ / s: the clock's rounding (1e-16) over s ≥ e^{-2.5}.
            assert!((back - t).abs() < 1e-14, "t = {t}: {back}");
        }
        assert_eq!(rt.at(rt.tau_end()), 1.0);
        assert_eq!(rt.at(0.0), 0.0);
        // The closed-form inverse t = −τ_s ln(1 − τ/τ_s).
        for tau in [1e-6, 0.05, 0.2, 0.3] {
            let exact = -0.4 * (-tau / 0.4_f64).ln_1p();
            assert!((rt.at(tau) - exact).abs() < 1e-14, "τ = {tau}");
        }
    }

    /// Where s = 0 over [0.3, 0.6], S is flat: τ = S(0.3) maps to the pause's end, 0.6.
    #[test]
    fn a_pause_reads_its_end() {
        let schedule = Schedule {
            form: Form::Table,
            times: vec![0.0, 0.2, 0.3, 0.6, 0.7, 1.0],
            factors: vec![1.0, 1.0, 0.0, 0.0, 1.0, 1.0],
            ..Schedule::default()
        };
        let w = Warp::new(&schedule, &Clock::default());
        let rt = real_time(schedule, 1.0);
        let flat = w.clock(0.3);
        assert_eq!(w.clock(0.45), flat);
        // s leaves 0 quadratically at 0.6 (the table's zero slopes), so S − S(0.6) grows as
        // (t − 0.6)³ and S's rounding (1e-17 here) leaves t within (1e-17/s″)^(1/3) ≈ 1e-6.
        let t = rt.at(flat);
        assert!(t >= 0.6 - 1e-12 && t - 0.6 < 2e-6, "{t}");
        assert!(rt.at(0.999 * flat) < 0.3, "{}", rt.at(0.999 * flat));
        // Just after the pause, S increases again and the inverse is continuous from there.
        let after = rt.at(w.clock(0.65));
        assert!((after - 0.65).abs() < 1e-9, "{after}");
    }

    /// A table of ones is S(t) = t: the inverse is the identity to rounding.
    #[test]
    fn ones_are_the_identity() {
        let rt = real_time(
            Schedule {
                form: Form::Table,
                times: vec![0.0, 0.5, 1.0],
                factors: vec![1.0, 1.0, 1.0],
                ..Schedule::default()
            },
            1.0,
        );
        for k in 0..=50 {
            let tau = k as f64 / 50.0;
            assert!((rt.at(tau) - tau).abs() <= 2.0 * f64::EPSILON, "τ = {tau}");
        }
    }
}
