//! `solver.max_seconds`: an elastic solve and every integrator's callback stop
//! once the deadline has passed, with the deadline's own message saying where, and a
//! growth run keeps what it had handed on; a bound that is not reached changes nothing.
//!
//! The integrators' callbacks are reached deterministically: the observer sleeps past the
//! deadline at t = 0, after the elastic solve there, so the first callback the integrator
//! makes finds it passed. With `solver.tol` the stages of a growth run share the bound.

use std::time::Duration;

use crate::common::grow;
use eyeshell_core::bvp::settings::SolverSettings;
use eyeshell_core::bvp::{self, BvpError};
use eyeshell_core::growth::*;
use eyeshell_core::model::params::Params;

fn bounded(nodes: usize, max_seconds: Option<f64>) -> SolverSettings {
    SolverSettings {
        nodes,
        max_seconds,
        ..SolverSettings::default()
    }
}

/// Keeps every snapshot; sleeps `sleep` at the first.
struct SleepAtStart {
    sleep: Duration,
    kept: Vec<Snapshot>,
}

impl Observer for SleepAtStart {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        if self.kept.is_empty() {
            std::thread::sleep(self.sleep);
        }
        self.kept.push(s.clone());
        Ok(())
    }
}

fn grow_with(
    solver: &SolverSettings,
    settings: &GrowthSettings,
    sleep: Duration,
) -> (Vec<Snapshot>, Result<GrowthStats, GrowthError>) {
    let mut obs = SleepAtStart {
        sleep,
        kept: Vec::new(),
    };
    let r = grow(
        &Params::default(),
        solver,
        &GrowthParams::default(),
        settings,
        &mut obs,
    );
    (obs.kept, r)
}

#[test]
fn every_integrator_stops_in_its_own_callback() {
    let cases = [
        (Integrator::Ida, "in IDA's residual at t = "),
        (Integrator::Cvode, "in CVODE's right-hand side at t = "),
        (Integrator::Euler, "in Euler step 1 of 200"),
    ];
    for (integrator, place) in cases {
        let settings = GrowthSettings {
            integrator,
            ..GrowthSettings::default()
        };
        // N = 21 solves at t = 0 in milliseconds, well within the bound.
        let (kept, r) = grow_with(
            &bounded(21, Some(0.3)),
            &settings,
            Duration::from_millis(400),
        );
        let e = r.expect_err("stopped");
        let expected = format!("max_seconds = 0.3 s reached {place}");
        assert!(e.reason.starts_with(&expected), "{integrator:?}: {e}");
        assert_eq!(
            kept.len(),
            1,
            "{integrator:?}: the snapshot at t = 0 is kept"
        );
        assert!(e.stats.wall_seconds < 30.0, "{integrator:?}: {:?}", e.stats);
    }
}

#[test]
fn an_elastic_solve_stops_at_its_first_residual() {
    // Laying 20,001 nodes and making KINSOL take far longer than a microsecond.
    let e = bvp::solve(&Params::default(), &bounded(20_001, Some(1e-6)), None).unwrap_err();
    assert!(matches!(e, BvpError::OutOfTime(_)), "{e:?}");
    assert_eq!(
        e.to_string(),
        "max_seconds = 1e-6 s reached in the elastic solve, after 0 Newton iterations"
    );
    // The same in a growth run, at t = 0: nothing is handed on.
    let (kept, r) = grow_with(
        &bounded(20_001, Some(1e-6)),
        &GrowthSettings::default(),
        Duration::ZERO,
    );
    let e = r.unwrap_err();
    assert_eq!(
        e.to_string(),
        "growth failed at t = 0.000000: max_seconds = 1e-6 s reached in the elastic \
         solve, after 0 Newton iterations"
    );
    assert!(kept.is_empty());
}

#[test]
fn a_bound_not_reached_changes_nothing() {
    let p = Params::default();
    let free = bvp::solve(&p, &bounded(201, None), None).unwrap();
    let bound = bvp::solve(&p, &bounded(201, Some(1e6)), None).unwrap();
    assert_eq!(free.u.len(), bound.u.len());
    assert!(free
        .u
        .iter()
        .zip(&bound.u)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(free.rows, bound.rows);
    assert_eq!(free.stats.newton_iterations, bound.stats.newton_iterations);
    for integrator in [Integrator::Ida, Integrator::Cvode] {
        let settings = GrowthSettings {
            integrator,
            rtol: 1e-4,
            atol: 1e-6,
            ..GrowthSettings::default()
        };
        let (a, ra) = grow_with(&bounded(51, None), &settings, Duration::ZERO);
        let (b, rb) = grow_with(&bounded(51, Some(1e6)), &settings, Duration::ZERO);
        let (ra, rb) = (ra.unwrap(), rb.unwrap());
        assert_eq!(ra.steps, rb.steps, "{integrator:?}");
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.fields, y.fields, "{integrator:?} at t = {}", x.t);
            // Bit for bit (defocus_D is NaN where the rule reads none, and NaN ≠ NaN).
            let bits = |s: &eyeshell_core::growth::Snapshot| -> Vec<u64> {
                s.growth
                    .iter()
                    .flat_map(|g| g.values().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(bits(x), bits(y), "{integrator:?} at t = {}", x.t);
        }
    }
}

/// Sleeps at the first progress report until `until`, and records when that report came.
struct SleepUntil {
    start: std::time::Instant,
    until: std::time::Instant,
    first_after: Option<f64>,
}

impl Observer for SleepUntil {
    fn snapshot(&mut self, _: &Snapshot) -> Result<(), ObserverError> {
        Ok(())
    }

    fn progress(&mut self, _t: f64, _t_end: f64) -> Result<(), ObserverError> {
        if self.first_after.is_none() {
            self.first_after = Some(self.start.elapsed().as_secs_f64());
            std::thread::sleep(
                self.until
                    .saturating_duration_since(std::time::Instant::now()),
            );
        }
        Ok(())
    }
}

/// With `solver.tol`, the runs of the choice share one bound: progress is reported by the
/// delivered run of a round only, and the observer, at its first report, sleeps until the
/// bound counted from the start of `grow` has passed; the run then stops at IDA's next
/// residual. On one core the delivered run goes first and on two it starts with the
/// others, so this shows the bound reaching the delivered run, not on its own that the
/// clock is the job's (`a_bound_counted_from_an_earlier_start_stops_the_first_stage` does).
#[test]
fn with_tol_the_runs_of_the_choice_share_one_bound() {
    // At tol 1e-4 the first two runs take a few hundredths of a second.
    let solver = SolverSettings {
        tol: Some(1e-4),
        max_seconds: Some(2.0),
        ..SolverSettings::default()
    };
    let start = std::time::Instant::now();
    let mut obs = SleepUntil {
        start,
        until: start + Duration::from_secs_f64(2.05),
        first_after: None,
    };
    let r = grow(
        &Params::default(),
        &solver,
        &GrowthParams::default(),
        &GrowthSettings::default(),
        &mut obs,
    );
    let first = obs.first_after.expect("the third run reported progress");
    let e = r.expect_err("the bound has passed");
    assert!(
        e.reason
            .starts_with("max_seconds = 2 s reached in IDA's residual at t = "),
        "{e} (the first progress report came after {first:.3} s)"
    );
    let accuracy = e.stats.accuracy.expect("the choice is recorded");
    assert!(accuracy.rounds.is_empty(), "{accuracy:?}");
}

/// A job's clock started earlier (`clock_start`) counts: a growth run with `solver.tol`
/// whose bound passed before it began stops in its first elastic solve, with the
/// bound as given, and hands nothing on.
#[test]
fn a_bound_counted_from_an_earlier_start_stops_the_first_stage() {
    let solver = SolverSettings {
        tol: Some(1e-4),
        max_seconds: Some(1.0),
        clock_start: std::time::Instant::now().checked_sub(Duration::from_secs(5)),
        ..SolverSettings::default()
    };
    let (kept, r) = grow_with(&solver, &GrowthSettings::default(), Duration::ZERO);
    let e = r.expect_err("the bound had passed");
    assert_eq!(
        e.reason,
        "max_seconds = 1 s reached in the elastic solve, after 0 Newton iterations"
    );
    assert_eq!(e.t, 0.0);
    assert!(kept.is_empty());
}

/// Refuses the first progress report.
struct RefuseProgress;

impl Observer for RefuseProgress {
    fn snapshot(&mut self, _: &Snapshot) -> Result<(), ObserverError> {
        Ok(())
    }

    fn progress(&mut self, _t: f64, _t_end: f64) -> Result<(), ObserverError> {
        Err("enough (the observer's own error)".into())
    }
}

/// With `solver.tol` a round's runs go side by side: the observer's error at the delivered
/// run's first step is the run's error, and it stops the round's other runs too (at tol
/// 1e-6 those two take seconds; stopped, the whole run ends within the first steps).
#[test]
fn with_tol_an_observer_error_stops_every_run_of_the_round() {
    let solver = SolverSettings {
        tol: Some(1e-6),
        ..SolverSettings::default()
    };
    let start = std::time::Instant::now();
    let r = grow(
        &Params::default(),
        &solver,
        &GrowthParams::default(),
        &GrowthSettings::default(),
        &mut RefuseProgress,
    );
    let seconds = start.elapsed().as_secs_f64();
    let e = r.expect_err("the observer refused");
    assert!(
        e.reason.contains("enough (the observer's own error)"),
        "{e}"
    );
    assert!(
        seconds < 1.0,
        "the round took {seconds:.3} s after the refusal"
    );
    let accuracy = e.stats.accuracy.expect("the choice is recorded");
    assert!(accuracy.rounds.is_empty(), "{accuracy:?}");
}
