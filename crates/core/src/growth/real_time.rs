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
//! whatever the optics are). A run beside changing optics refuses a schedule that reaches 0
//! inside its window ([`check_zeros`]): there the inverse is infinitely steep and the
//! integrator cannot pass; a flat S remains possible where s underflows.

use super::schedule::{Clock, Form, Schedule, Warp};
use crate::names::Quantity;
use crate::text::number;

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

/// Why `schedule` cannot run beside optics that change with age over the growth window
/// [0, `t_end`] of `clock`, as (key, problem): a table whose factor is 0 at one of its times
/// inside the window (only there can the interpolant reach 0: it is monotone between its
/// points). Near a zero of s the eye changes on the clock 1/s times as fast as in t and
/// S⁻¹ is infinitely steep, so the integrator's steps shrink without end (measured:
/// scenes/optics-age.toml at N = 51, factors [1, 0, 1] at t = [0, 0.5, 1] and rtol 1e-8,
/// ten minutes without reaching t = 0.5; a pause [1, 0, 0, 1] at [0, 0.3, 0.6, 1], 20 s at
/// rtol 1e-6 without passing 0.3, where the eye jumps to that of the pause's end).
pub fn check_zeros(
    schedule: &Schedule,
    clock: &Clock,
    t_end: f64,
) -> Result<(), (Quantity, String)> {
    if schedule.form != Form::Table {
        return Ok(());
    }
    let (a0, a1) = (clock.origin(), clock.origin() + t_end);
    let zero = (schedule.times.iter().zip(&schedule.factors))
        .position(|(&x, &f)| f == 0.0 && x >= a0 && x <= a1);
    match zero {
        None => Ok(()),
        Some(i) => Err((
            Quantity::ScheduleFactors,
            format!(
                "item {} is 0 (at {} in {}): beside optics that change with age (tables over time in {}) the schedule must stay above 0 over the growth window, since where it vanishes the run on the schedule's clock meets the changing eye infinitely fast and the integrator cannot step past it; give a small factor instead (1e-3 grows a thousandth as fast)",
                i + 1,
                number(schedule.times[i]),
                Quantity::ScheduleTimes,
                Quantity::Surfaces
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A table that reaches 0 inside the window is refused, naming the item; beyond the
    /// window, or small but positive, it is not.
    #[test]
    fn a_zero_inside_the_window_is_refused() {
        let table = |times: &[f64], factors: &[f64]| Schedule {
            form: Form::Table,
            times: times.to_vec(),
            factors: factors.to_vec(),
            ..Schedule::default()
        };
        let c = Clock::default();
        let pause = table(&[0.0, 0.3, 0.6, 1.0], &[1.0, 0.0, 0.0, 1.0]);
        let (key, why) = check_zeros(&pause, &c, 1.0).unwrap_err();
        assert_eq!(key, Quantity::ScheduleFactors);
        assert!(why.starts_with("item 2 is 0 (at 0.3 in "), "{why}");
        let start = table(&[0.0, 0.3, 0.4, 1.0], &[0.0, 0.0, 1.0, 1.0]);
        assert!(check_zeros(&start, &c, 1.0)
            .unwrap_err()
            .1
            .starts_with("item 1 is 0"));
        for ok in [
            table(&[0.0, 0.5, 1.0, 2.0], &[1.0, 0.5, 1.0, 0.0]),
            table(&[0.0, 0.3, 0.6, 1.0], &[1.0, 1e-6, 1e-6, 1.0]),
        ] {
            assert_eq!(check_zeros(&ok, &c, 1.0), Ok(()), "{:?}", ok.factors);
        }
        // The pause after a window that ends at 0.25 is not the run's.
        assert_eq!(check_zeros(&pause, &c, 0.25), Ok(()));
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
