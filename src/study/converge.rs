//! Convergence ladders (the trade of speed for accuracy). On a ladder of
//! meshes, pole truncations ε, or solver tolerances, each rung's fields are compared with
//! the finest rung and, for elastic meshes, with the Richardson extrapolation of the two
//! finest at the scheme's order; the observed order between rungs is
//! log(e_k / e_{k+1}) / log(h_k / h_{k+1}).

use super::{max_diff, points, run, sample, worst, StudyError, FIELDS};
use eyeshell::bvp::settings::SolverSettings;
use eyeshell::growth::{GrowthParams, GrowthSettings};
use eyeshell::model::params::Params;

/// What a ladder varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    /// solver.nodes: the uniform nodes N (the spacing h is what the order is measured in).
    Nodes,
    /// solver.epsilon: the pole truncation ε.
    Epsilon,
    /// The tolerance: solver.newton_tol for an elastic scene, solver.rtol for growth.
    Tolerance,
    /// solver.steps: the explicit Euler's step count (growth; the order is measured in the
    /// step t_end / steps).
    Steps,
}

impl Knob {
    pub fn name(self) -> &'static str {
        match self {
            Knob::Nodes => "nodes",
            Knob::Epsilon => "epsilon",
            Knob::Tolerance => "tolerance",
            Knob::Steps => "steps",
        }
    }
}

/// One ladder's measurements.
#[derive(Clone, Debug)]
pub struct Ladder {
    pub knob: Knob,
    /// The knob's values, coarse to fine.
    pub values: Vec<f64>,
    /// The measure the order is taken in: h for nodes, ε, or the tolerance.
    pub scale: Vec<f64>,
    pub seconds: Vec<f64>,
    /// Largest error of each field against the finest rung (zero on the finest).
    pub err_finest: Vec<[f64; 5]>,
    /// Against the Richardson extrapolation of the two finest (meshes only).
    pub err_richardson: Option<Vec<[f64; 5]>>,
    /// Axial length at t_end per rung, for growth ladders.
    pub axial: Option<Vec<f64>>,
}

impl Ladder {
    /// The errors the orders are measured from: Richardson's when there is one.
    pub fn errors(&self) -> &[[f64; 5]] {
        self.err_richardson.as_deref().unwrap_or(&self.err_finest)
    }

    /// Observed order of each field between consecutive rungs (NaN where an error is zero).
    pub fn orders(&self) -> Vec<[f64; 5]> {
        let e = self.errors();
        let n = if self.err_richardson.is_some() {
            e.len()
        } else {
            e.len() - 1
        };
        (1..n)
            .map(|k| {
                let ratio = (self.scale[k - 1] / self.scale[k]).ln();
                std::array::from_fn(|c| {
                    let (a, b) = (e[k - 1][c], e[k][c]);
                    if a > 0.0 && b > 0.0 {
                        (a / b).ln() / ratio
                    } else {
                        f64::NAN
                    }
                })
            })
            .collect()
    }

    /// Observed order of the largest error over all fields, between consecutive rungs.
    pub fn worst_orders(&self) -> Vec<f64> {
        let e = self.errors();
        let n = if self.err_richardson.is_some() {
            e.len()
        } else {
            e.len() - 1
        };
        (1..n)
            .map(|k| {
                (worst(&e[k - 1]) / worst(&e[k])).ln() / (self.scale[k - 1] / self.scale[k]).ln()
            })
            .collect()
    }
}

/// Run a ladder on a scene (growth when `growth` is given). Values are sorted coarse to fine.
pub fn ladder(
    params: &Params,
    solver: &SolverSettings,
    growth: Option<(&GrowthParams, &GrowthSettings)>,
    knob: Knob,
    values: &[f64],
) -> Result<Ladder, StudyError> {
    if values.len() < 2 {
        return Err(StudyError::Invalid(format!(
            "a {} ladder needs at least two values",
            knob.name()
        )));
    }
    let mut values = values.to_vec();
    match knob {
        Knob::Nodes | Knob::Steps => values.sort_by(|a, b| a.partial_cmp(b).unwrap()),
        _ => values.sort_by(|a, b| b.partial_cmp(a).unwrap()),
    }
    let l = params.length();
    let mut runs = vec![];
    for &v in &values {
        let mut s = *solver;
        let mut gs = growth.map(|(_, s)| s.clone());
        match knob {
            Knob::Nodes => s.nodes = v as usize,
            Knob::Epsilon => s.epsilon = v,
            Knob::Tolerance => match gs.as_mut() {
                Some(g) => {
                    g.rtol = v;
                    g.atol = v * 1e-2;
                }
                None => s.newton_tol = v,
            },
            Knob::Steps => match gs.as_mut() {
                Some(g) => {
                    g.integrator = eyeshell::growth::Integrator::Euler;
                    g.steps = v as usize;
                }
                None => {
                    return Err(StudyError::Invalid(
                        "a steps ladder needs a growth scene".into(),
                    ))
                }
            },
        }
        let what = format!("{} = {v}", knob.name());
        runs.push(run(
            params,
            &s,
            growth.map(|(g, _)| g).zip(gs.as_ref()),
            &what,
        )?);
    }
    // Compare at the coarsest run's uniform nodes (nodes of every finer, nested rung), or,
    // for ε, at points inside the largest truncation.
    let eps_max = values.iter().cloned().fold(solver.epsilon, f64::max);
    let count = match knob {
        Knob::Nodes => values[0] as usize,
        _ => solver.nodes.min(401),
    };
    let lo = if knob == Knob::Epsilon {
        eps_max
    } else {
        solver.epsilon
    };
    let pts = points(lo, l, count);
    let samples: Vec<Vec<[f64; 5]>> = runs
        .iter()
        .zip(&values)
        .map(|(r, v)| sample(&r.solution, &pts, &format!("{} = {v}", knob.name())))
        .collect::<Result<_, _>>()?;
    let finest = samples.last().unwrap();
    let err_finest = samples.iter().map(|s| max_diff(s, finest)).collect();
    let scale: Vec<f64> = match knob {
        Knob::Nodes => values
            .iter()
            .map(|&n| (l - solver.epsilon) / (n - 1.0))
            .collect(),
        Knob::Steps => values
            .iter()
            .map(|&n| growth.map_or(1.0, |(g, _)| g.t_end) / n)
            .collect(),
        _ => values.clone(),
    };
    // Richardson at the scheme's order suits the elastic problem only: a grown shell's data
    // carry kinks (where points stopped growing) that pull the spatial order down to ~2.
    let err_richardson = (knob == Knob::Nodes && growth.is_none()).then(|| {
        let k = samples.len();
        let p = solver.scheme.order() as i32;
        let q = (scale[k - 2] / scale[k - 1]).powi(p);
        let reference: Vec<[f64; 5]> = samples[k - 2]
            .iter()
            .zip(&samples[k - 1])
            .map(|(c, f)| std::array::from_fn(|j| f[j] + (f[j] - c[j]) / (q - 1.0)))
            .collect();
        samples[..k - 1]
            .iter()
            .map(|s| max_diff(s, &reference))
            .collect()
    });
    Ok(Ladder {
        knob,
        values,
        scale,
        seconds: runs.iter().map(|r| r.seconds).collect(),
        err_finest,
        err_richardson,
        axial: growth.map(|_| {
            runs.iter()
                .map(|r| r.axial_length().unwrap_or(f64::NAN))
                .collect()
        }),
    })
}

/// The ladder as CSV: one row per rung, errors and orders per field.
pub fn table(l: &Ladder) -> (Vec<String>, Vec<Vec<String>>) {
    use super::cell;
    let mut header = vec![l.knob.name().to_string(), "scale".into(), "seconds".into()];
    if l.axial.is_some() {
        header.push("axial_length".into());
    }
    for f in FIELDS {
        header.push(format!("{f}_err_finest"));
        if l.err_richardson.is_some() {
            header.push(format!("{f}_err_richardson"));
        }
        header.push(format!("{f}_order"));
    }
    header.push("max_order".into());
    let orders = l.orders();
    let worst_orders = l.worst_orders();
    let rows = (0..l.values.len())
        .map(|k| {
            let mut r = vec![cell(l.values[k]), cell(l.scale[k]), cell(l.seconds[k])];
            if let Some(a) = &l.axial {
                r.push(cell(a[k]));
            }
            for c in 0..5 {
                r.push(cell(l.err_finest[k][c]));
                if let Some(rich) = &l.err_richardson {
                    r.push(rich.get(k).map_or(String::new(), |e| cell(e[c])));
                }
                // The order between rung k−1 and k is listed on rung k.
                r.push(if k >= 1 {
                    orders.get(k - 1).map_or(String::new(), |o| cell(o[c]))
                } else {
                    String::new()
                });
            }
            r.push(if k >= 1 {
                worst_orders.get(k - 1).map_or(String::new(), |&o| cell(o))
            } else {
                String::new()
            });
            r
        })
        .collect();
    (header, rows)
}
