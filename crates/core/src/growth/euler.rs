//! The published method (docs/MODEL.md §8): explicit Euler with a fixed number of steps,
//! p_{n+1} = p_n + Δt G(p_n), kept for comparison and reproduction. An output time that
//! falls inside a step is reached by a partial Euler step from the step's start.

use super::system::{GrowthSystem, RhsError};

/// Integrate from t = 0 to `span.t_end` in `span.settings.steps` equal steps; `output(t, p)`
/// is called at each of `span.times` (increasing, in (0, t_end]) and `progress(t)` after
/// each step. Returns the state at t_end, or the time and error where a right-hand side
/// failed.
pub fn integrate(
    sys: &mut GrowthSystem,
    p0: &[f64],
    span: &super::Span<'_>,
    output: &mut super::OutputFn<'_>,
    progress: &mut super::ProgressFn<'_>,
) -> Result<Vec<f64>, (f64, EulerError)> {
    let (t_end, steps, times) = (span.t_end, span.settings.steps, span.times);
    let dt = t_end / steps as f64;
    let mut p = p0.to_vec();
    let mut rate = vec![0.0; p.len()];
    let mut next = times.iter().peekable();
    for n in 0..steps {
        let t = n as f64 * dt;
        let t1 = if n + 1 == steps {
            t_end
        } else {
            (n + 1) as f64 * dt
        };
        sys.check_deadline(|| format!("in Euler step {} of {steps}", n + 1))
            .and_then(|_| sys.set_time(t))
            .and_then(|_| sys.rhs(&p, &mut rate))
            .map_err(|e| (t, EulerError::Rhs(e)))?;
        while let Some(&&tout) = next.peek() {
            if tout > t1 * (1.0 + 1e-12) {
                break;
            }
            let q: Vec<f64> = p
                .iter()
                .zip(&rate)
                .map(|(a, r)| a + (tout - t) * r)
                .collect();
            output(sys, tout, &q).map_err(|e| (tout, EulerError::Output(e)))?;
            next.next();
        }
        for (a, r) in p.iter_mut().zip(&rate) {
            *a += (t1 - t) * r;
        }
        progress(t1).map_err(|e| (t1, EulerError::Output(e)))?;
    }
    Ok(p)
}

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EulerError {
    #[error(transparent)]
    Rhs(RhsError),
    #[error(transparent)]
    Output(super::ObserverError),
}
