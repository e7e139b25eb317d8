//! `solver.max_seconds` (issue 13): an elastic solve and every integrator's callback stop
//! once the deadline has passed, with the deadline's own message saying where, and a
//! growth run keeps what it had handed on; a bound that is not reached changes nothing.
//!
//! The integrators' callbacks are reached deterministically: the observer sleeps past the
//! deadline at t = 0, after the elastic solve there, so the first callback the integrator
//! makes finds it passed.

use std::time::Duration;

use eyeshell::bvp::settings::SolverSettings;
use eyeshell::bvp::{self, BvpError};
use eyeshell::growth::*;
use eyeshell::model::params::Params;

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
        let expected = format!("solver.max_seconds = 0.3 s reached {place}");
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
        "solver.max_seconds = 1e-6 s reached in the elastic solve, after 0 Newton iterations"
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
        "growth failed at t = 0.000000: solver.max_seconds = 1e-6 s reached in the elastic \
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
            assert_eq!(x.growth, y.growth, "{integrator:?} at t = {}", x.t);
        }
    }
}
