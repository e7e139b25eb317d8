//! `solver.max_seconds`: a wall-clock bound on each elastic solve and on each growth run as
//! a whole, so that no call into SUNDIALS can run for minutes on a hopeless problem.
//!
//! A [`Deadline`] is set when a solver is made ([`crate::bvp::solve::ElasticSolver`]; a
//! growth run's elastic solver lives for the whole run, so the run has one deadline). A job
//! of several stages (an adaptive solve's passes; a growth run with `solver.tol`: the
//! adaptation at t = 0, the test runs and their estimates, then the run) starts the clock
//! once (`SolverSettings::clock_start`), so that the bound is on the job as a whole. The
//! SUNDIALS callbacks check it (KINSOL's residual, CVODE's right side, IDA's residual, and
//! Euler between steps): once it has passed, the callback returns a fatal flag, the solver
//! stops, and the error is an [`OutOfTime`] saying where. A callback never panics for it:
//! the flag is how a callback stops SUNDIALS.
//!
//! The check is a clock read per callback (tens of nanoseconds against microseconds for a
//! residual), and changes nothing else: a run that ends within its bound is bit-for-bit
//! the run without one.

use std::time::{Duration, Instant};

use crate::text::number;

/// When a solve (or a growth run) must stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deadline {
    /// None: no bound (or one so far away that the clock cannot hold it).
    at: Option<Instant>,
    /// The bound as given, for the message.
    seconds: f64,
}

impl Deadline {
    /// No bound.
    pub const NONE: Deadline = Deadline {
        at: None,
        seconds: f64::INFINITY,
    };

    /// `seconds` from now; None (no `solver.max_seconds`) is no bound.
    pub fn after(seconds: Option<f64>) -> Deadline {
        Deadline::since(None, seconds)
    }

    /// `seconds` from `start` (None: now), the clock a job's stages share
    /// (`SolverSettings::clock_start`); None is no bound.
    pub fn since(start: Option<Instant>, seconds: Option<f64>) -> Deadline {
        let Some(seconds) = seconds else {
            return Deadline::NONE;
        };
        let start = start.unwrap_or_else(Instant::now);
        let at = Duration::try_from_secs_f64(seconds)
            .ok()
            .and_then(|d| start.checked_add(d));
        Deadline { at, seconds }
    }

    /// Has the deadline passed?
    pub fn passed(&self) -> bool {
        self.at.is_some_and(|at| Instant::now() >= at)
    }

    /// Ok while there is time; then the error saying that the bound was reached `place`
    /// ("in IDA's residual at t = 0.25").
    pub fn check(&self, place: impl FnOnce() -> String) -> Result<(), OutOfTime> {
        if self.passed() {
            return Err(self.reached(place()));
        }
        Ok(())
    }

    /// The error of this deadline, reached `place`.
    pub fn reached(&self, place: String) -> OutOfTime {
        OutOfTime {
            seconds: self.seconds,
            place,
        }
    }
}

/// A solve or growth run stopped by `solver.max_seconds`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{} = {} s reached {place}", crate::names::Quantity::MaxSeconds, number(*seconds))]
pub struct OutOfTime {
    pub seconds: f64,
    /// Where it was reached: which solve, stage, time or iteration.
    pub place: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_deadline_passes_once_and_says_where() {
        assert!(!Deadline::NONE.passed());
        assert!(!Deadline::after(None).passed());
        assert!(!Deadline::after(Some(3600.0)).passed());
        // Beyond what the clock can hold: never.
        assert!(!Deadline::after(Some(1e300)).passed());
        let d = Deadline::after(Some(1e-9));
        std::thread::sleep(Duration::from_millis(1));
        assert!(d.passed());
        let e = d.check(|| "in the elastic solve".into()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "max_seconds = 1e-9 s reached in the elastic solve"
        );
        assert!(Deadline::after(Some(60.0)).check(|| unreachable!()).is_ok());
    }
}
