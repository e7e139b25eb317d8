//! Growth rules written in Python (docs/MODEL.md §6, "Growth rules"; docs/guide/python.md,
//! "Rules in Python"): a Python callable as a [`GrowthRule`].
//!
//! The integrators run with the GIL released ([`Python::detach`] in grow.rs) and call the
//! rule from Rust; each call takes the GIL back, hands the view to
//! `eyeshell._rule.evaluate` (which calls the function, checks its answer and takes the
//! central differences) and copies the drives out. A rule reads every quantity a point
//! sees, so [`GrowthRule::reads`] is all true.
//!
//! A failure is kept (the Python exception itself: the rule's own raised one chained to an
//! `InputError` naming the rule, or a KeyboardInterrupt) and every later call fails at
//! once without calling Python: the integrators take a failed evaluation as recoverable and
//! try smaller steps, which a rule that raised would only fail again, slowly. The growth
//! call then raises the kept exception instead of the integrator's. `solver.max_seconds` is
//! checked after every call, so a slow rule stops the run with a message that names it.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use eyeshell::model::rule::{Drive, GrowthRule, Reads, RuleError, Seen};
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use super::errors::SolverError;

/// A Python callable `f(view) -> g_v` as a growth rule.
#[derive(Debug)]
pub(super) struct PyRule {
    /// `python:` and the callable's qualified name, as messages name it.
    name: String,
    function: Py<PyAny>,
    /// `eyeshell._rule.evaluate`.
    evaluate: Py<PyAny>,
    /// When the run started and `solver.max_seconds`.
    started: Instant,
    max_seconds: Option<f64>,
    state: Mutex<State>,
}

#[derive(Debug, Default)]
struct State {
    /// The exception that stopped the rule.
    failure: Option<PyErr>,
    /// Evaluations (one call of the function, and two more per quantity differenced when
    /// the partials are asked for) and the time spent in them.
    calls: u64,
    spent: Duration,
}

/// The view's quantities, in the order of `eyeshell._rule.QUANTITIES`.
const QUANTITIES: [fn(&Seen) -> f64; 7] = [
    |s| s.sigma,
    |s| s.z,
    |s| s.r,
    |s| s.angle,
    |s| s.depth,
    |s| s.depth_red,
    |s| s.defocus,
];

impl PyRule {
    /// The rule running `function` in a run that started now, under `max_seconds`.
    pub(super) fn new(
        py: Python<'_>,
        function: Py<PyAny>,
        max_seconds: Option<f64>,
    ) -> PyResult<Self> {
        let f = function.bind(py);
        if !f.is_callable() {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "stimulus must be a growth rule, a callable f(s) returning g_v (mm), not {}",
                f.get_type().name()?
            )));
        }
        // The qualified name without the enclosing functions (`<locals>`): `python:rule`,
        // `python:<lambda>`, `python:Model.drive`; an instance's, its class's.
        let qualname = match f.getattr("__qualname__") {
            Ok(q) => q.extract::<String>()?,
            Err(_) => f.get_type().qualname()?.to_string(),
        };
        let qualname = qualname.rsplit("<locals>.").next().unwrap_or_default();
        let evaluate = py.import("eyeshell._rule")?.getattr("evaluate")?.unbind();
        Ok(PyRule {
            name: format!("python:{qualname}"),
            function,
            evaluate,
            started: Instant::now(),
            max_seconds,
            state: Mutex::new(State::default()),
        })
    }

    /// The exception that stopped the rule, if one did (taken: once).
    pub(super) fn take_failure(&self) -> Option<PyErr> {
        self.state.lock().ok().and_then(|mut s| s.failure.take())
    }

    /// Evaluations made and the seconds spent in them.
    pub(super) fn cost(&self) -> (u64, f64) {
        self.state
            .lock()
            .map_or((0, 0.0), |s| (s.calls, s.spent.as_secs_f64()))
    }

    /// One call of `evaluate`: the values (and the partials' (6, n) array) as vectors.
    fn call(
        &self,
        py: Python<'_>,
        seen: &[Seen],
        partials: bool,
    ) -> PyResult<(Vec<f64>, Option<Vec<f64>>)> {
        let arrays: Vec<Bound<'_, PyArray1<f64>>> = QUANTITIES
            .iter()
            .map(|q| PyArray1::from_vec(py, seen.iter().map(q).collect()))
            .collect();
        let q = pyo3::types::PyTuple::new(py, arrays)?;
        let t = seen.first().map_or(f64::NAN, |s| s.t);
        let out = self.evaluate.bind(py).call1((
            self.function.bind(py),
            self.name.as_str(),
            q,
            t,
            partials,
        ))?;
        let (g, d): (PyReadonlyArray1<'_, f64>, Option<PyReadonlyArray2<'_, f64>>) =
            out.extract()?;
        let g = g.as_slice()?.to_vec();
        let d = match d {
            Some(d) => Some(d.as_slice()?.to_vec()),
            None => None,
        };
        Ok((g, d))
    }

    /// Fail the rule with `e` (kept) and say so in the core's terms.
    fn fail(&self, state: &mut State, e: PyErr) -> RuleError {
        let why = Python::attach(|py| e.value(py).to_string());
        state.failure = Some(e);
        RuleError::Failed {
            rule: self.name.clone(),
            why,
        }
    }
}

impl GrowthRule for PyRule {
    fn name(&self) -> &str {
        &self.name
    }

    fn reads(&self) -> Reads {
        Reads {
            red: true,
            defocus: true,
        }
    }

    fn drive(&self, seen: &[Seen], partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        let failed = |why: &str| RuleError::Failed {
            rule: self.name.clone(),
            why: why.to_string(),
        };
        let mut state = self.state.lock().map_err(|_| failed("poisoned"))?;
        if state.failure.is_some() {
            return Err(failed("it failed before"));
        }
        let began = Instant::now();
        let result = Python::attach(|py| self.call(py, seen, partials));
        let took = began.elapsed();
        state.calls += 1;
        state.spent += took;
        let (g, d) = match result {
            Ok(v) => v,
            Err(e) => return Err(self.fail(&mut state, e)),
        };
        if let Some(max) = self.max_seconds {
            if self.started.elapsed().as_secs_f64() > max {
                let e = SolverError::new_err(format!(
                    "solver.max_seconds = {max} s reached in the growth rule {}: its last call took {:.3} s, {} calls {:.3} s in all",
                    self.name,
                    took.as_secs_f64(),
                    state.calls,
                    state.spent.as_secs_f64()
                ));
                return Err(self.fail(&mut state, e));
            }
        }
        let n = seen.len();
        if g.len() != n || d.as_ref().is_some_and(|d| d.len() != 6 * n) {
            return Err(failed("the drive's arrays are not one per point"));
        }
        for (k, o) in out.iter_mut().enumerate().take(n) {
            *o = Drive {
                value: g[k],
                ..Drive::default()
            };
            if let Some(d) = &d {
                // Rows in the order of eyeshell._rule.PARTIALS; the angle's partial goes into
                // the place's through the angle's own gradient.
                let [dd, dr, df, dz, drr, da] = std::array::from_fn(|j| d[j * n + k]);
                let ag = seen[k].angle_grad;
                o.d_depth = dd;
                o.d_depth_red = dr;
                o.d_defocus = df;
                o.d_z = dz + da * ag[0];
                o.d_r = drr + da * ag[1];
            }
        }
        Ok(())
    }
}
