//! Measurements of the trade of speed for accuracy: convergence ladders (in N, ε and the
//! tolerances), work-precision diagrams, and the paper's own refinement check. Each study
//! returns plain tables; `write_csv` and the plot module turn them into files.

pub mod converge;
pub mod extremes;
pub mod figures;
pub mod refinement;
pub mod report;
pub mod wpd;

use eyeshell::bvp::settings::SolverSettings;
use eyeshell::bvp::{BvpError, FieldRow, Solution};
use eyeshell::growth::{GrowthError, GrowthParams, GrowthSettings, GrowthStats};
use eyeshell::model::params::Params;
use eyeshell::rundir::table::{csv_bytes, QuoteStyle};
use std::path::Path;
use std::time::Instant;

/// The fields compared: bvp4c's y = (κ, α_s, r, θ, Q).
pub const FIELDS: [&str; 5] = ["kappa", "alpha_s", "r", "theta", "Q"];

/// The compared fields of one row.
pub fn five(row: &FieldRow) -> [f64; 5] {
    [row.kappa, row.alpha_s, row.r, row.theta, row.q]
}

/// Why a study could not be completed.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{what}: {source}")]
    Elastic { what: String, source: BvpError },
    #[error("{what}: {source}")]
    Growth {
        what: String,
        source: Box<GrowthError>,
    },
    #[error("{what}: {source}")]
    Problem {
        what: String,
        source: eyeshell::problem::ProblemError,
    },
    #[error("{0}")]
    Invalid(String),
    #[error("{}: {source}", path.display())]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}

impl From<StudyError> for eyeshell::Error {
    /// An invalid study set-up is the user's; a solve or a write that failed is not.
    fn from(e: StudyError) -> Self {
        match e {
            StudyError::Invalid(m) => eyeshell::Error::input_about_nothing(m),
            other => eyeshell::Error::failed_by(eyeshell::Stage::Study, other),
        }
    }
}

/// One solve, or one growth run to t_end, with what it cost.
pub struct Run {
    /// The elastic state (at t_end for growth).
    pub solution: Solution,
    /// (t, axial length) at each of the scene's output times and t_end (growth only).
    pub axial_series: Vec<(f64, f64)>,
    pub seconds: f64,
    pub growth: Option<GrowthStats>,
}

impl Run {
    /// Axial length at t_end (growth only).
    pub fn axial_length(&self) -> Option<f64> {
        self.axial_series.last().map(|&(_, a)| a)
    }
}

/// The checked growth problem of a study's parameters and settings.
pub fn growth_problem(
    params: &Params,
    solver: &SolverSettings,
    growth: &GrowthParams,
    settings: &GrowthSettings,
) -> Result<eyeshell::problem::GrowthProblem, eyeshell::problem::ProblemError> {
    let elastic = (eyeshell::problem::ElasticProblem::builder())
        .params(*params)
        .solver(*solver)
        .build()?;
    eyeshell::problem::GrowthProblem::builder(elastic)
        .growth(growth.clone())
        .settings(settings.clone())
        .build()
}

/// Solve the elastic problem, or run the growth when `growth` is given, and time it.
pub fn run(
    params: &Params,
    solver: &SolverSettings,
    growth: Option<(&GrowthParams, &GrowthSettings)>,
    what: &str,
) -> Result<Run, StudyError> {
    let start = Instant::now();
    match growth {
        None => {
            let solution = eyeshell::bvp::solve(params, solver, None).map_err(|source| {
                StudyError::Elastic {
                    what: what.into(),
                    source,
                }
            })?;
            Ok(Run {
                solution,
                axial_series: vec![],
                seconds: start.elapsed().as_secs_f64(),
                growth: None,
            })
        }
        Some((g, s)) => {
            let t_end = g.t_end;
            let mut last = None;
            let mut series = vec![];
            // The scene's output times as well as t_end: an integrator's error in axial
            // length is not monotone in t, and one instant can flatter it.
            let settings = GrowthSettings {
                history_points: 0,
                ..s.clone()
            };
            let problem = growth_problem(params, solver, g, &settings).map_err(|source| {
                StudyError::Problem {
                    what: what.into(),
                    source,
                }
            })?;
            let stats = eyeshell::growth::run(
                &problem,
                &mut |sys, t, p| {
                    if t > 0.0 {
                        // A snapshot, as the run directory would have it (IDA's elastic
                        // state polished).
                        series.push((t, sys.snapshot(t, p)?.series.axial_length));
                    }
                    if t == t_end {
                        last = Some(
                            sys.elastic
                                .solution()
                                .map_err(eyeshell::growth::system::RhsError::from)?,
                        );
                    }
                    Ok(())
                },
                &mut |_| Ok(()),
            )
            .map_err(|source| StudyError::Growth {
                what: what.into(),
                source: Box::new(source),
            })?;
            let seconds = start.elapsed().as_secs_f64();
            let solution = last.ok_or_else(|| {
                StudyError::Invalid(format!("{what}: the run gave no state at t_end"))
            })?;
            Ok(Run {
                solution,
                axial_series: series,
                seconds,
                growth: Some(stats),
            })
        }
    }
}

/// The compared fields of `sol` at the material points `points`.
pub fn sample(sol: &Solution, points: &[f64], what: &str) -> Result<Vec<[f64; 5]>, StudyError> {
    points
        .iter()
        .map(|&x| {
            sol.at(x)
                .map(|r| five(&r))
                .map_err(|source| StudyError::Elastic {
                    what: what.into(),
                    source,
                })
        })
        .collect()
}

/// The largest absolute difference of each field between two samples.
pub fn max_diff(a: &[[f64; 5]], b: &[[f64; 5]]) -> [f64; 5] {
    let mut d = [0.0f64; 5];
    for (x, y) in a.iter().zip(b) {
        for c in 0..5 {
            d[c] = d[c].max((x[c] - y[c]).abs());
        }
    }
    d
}

/// The largest of the five.
pub fn worst(e: &[f64; 5]) -> f64 {
    e.iter().cloned().fold(0.0, f64::max)
}

/// `count` evenly spaced material points on [lo, hi].
pub fn points(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    (0..count)
        .map(|k| {
            if k + 1 == count {
                hi
            } else {
                lo + (hi - lo) * k as f64 / (count - 1) as f64
            }
        })
        .collect()
}

/// Write a CSV table (header, then rows of already formatted cells) atomically.
pub fn write_csv(path: &Path, header: &[String], rows: &[Vec<String>]) -> Result<(), StudyError> {
    // Never quoted, as the study tables have always been written (see rundir::table).
    csv_bytes(header, rows, QuoteStyle::Never)
        .and_then(|text| eyeshell::rundir::write_atomic(path, &text))
        .map_err(|source| StudyError::Io {
            path: path.to_path_buf(),
            source,
        })
}

/// A number for a CSV cell (shortest round-trip form; empty for NaN).
pub fn cell(x: f64) -> String {
    if x.is_nan() {
        String::new()
    } else {
        eyeshell::rundir::format_value(x)
    }
}
