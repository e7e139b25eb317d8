//! One scene run into one run directory: the workflow `eyeshell solve`, `eyeshell grow` and
//! every run of a sweep share, written once.
//!
//! - [`solve_into`]: the elastic solve, then fields.csv (at.csv for material points asked
//!   for) and summary.json last, in a directory that appears whole or not at all.
//! - [`grow_with`]: the growth run, written as its results come by a [`GrowthWriter`];
//!   on failure the results so far stay and summary.json says when and why.

use std::path::{Path, PathBuf};

use super::summary::ElasticSummary;
use super::{GrowthWriter, OutputDir, OutputError, Summary, AT_FILE, FIELDS_FILE, SUMMARY_FILE};
use crate::bvp::{FieldRow, Solution};
use crate::growth::{
    GrowthError, GrowthStats, Observer, ObserverError, SensitivityRow, SeriesRow, Snapshot,
};
use crate::scene::Scene;
use crate::Error;

/// A finished elastic solve and where it was written.
pub struct SolvedRun {
    pub solution: Solution,
    /// Every field at the material points asked for (also in at.csv).
    pub at: Vec<FieldRow>,
    /// The run directory, in place.
    pub dir: PathBuf,
}

/// Solve the loaded shell of `scene` into the run directory `target`: the target is
/// checked and locked before the computation (a foreign directory, one another process
/// is writing, or one where `inputs`, the files the scene came from, are, is refused
/// first), the files are written into a temporary sibling and renamed into place with
/// their marker.
pub fn solve_into(
    scene: &Scene,
    target: &Path,
    at: &[f64],
    inputs: &[&Path],
) -> Result<SolvedRun, Error> {
    let dir = OutputDir::create(target, "solve", inputs)?;
    let solution = scene.elastic_problem()?.solve()?;
    let at_rows = at
        .iter()
        .map(|&s| solution.at(s))
        .collect::<Result<Vec<_>, _>>()?;
    super::write_fields_csv(&dir.file(FIELDS_FILE), &solution.rows)?;
    if !at.is_empty() {
        super::write_fields_csv(&dir.file(AT_FILE), &at_rows)?;
    }
    Summary::Elastic(ElasticSummary::of_solution(scene, &solution))
        .write_to(&dir.file(SUMMARY_FILE))?;
    let dir = dir.commit()?;
    Ok(SolvedRun {
        solution,
        at: at_rows,
        dir,
    })
}

/// A growth run that ended, well or not, with what its directory holds.
pub struct GrownRun {
    /// The series row of the last snapshot written (None: none was).
    pub last: Option<SeriesRow>,
    pub outcome: Result<(GrowthStats, PathBuf), GrowthFailure>,
}

/// Why a growth run has no finished directory.
#[derive(Debug)]
pub enum GrowthFailure {
    /// The run stopped (`error` says when and why); `summary` is set when its summary.json
    /// could not say so either.
    Stopped {
        error: GrowthError,
        summary: Option<OutputError>,
    },
    /// The run reached its end, but its summary.json could not be written.
    Unwritten {
        stats: Box<GrowthStats>,
        error: OutputError,
    },
}

impl GrowthFailure {
    /// The work done until the run stopped or was written.
    pub fn stats(&self) -> &GrowthStats {
        match self {
            GrowthFailure::Stopped { error, .. } => &error.stats,
            GrowthFailure::Unwritten { stats, .. } => stats,
        }
    }
}

impl std::fmt::Display for GrowthFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GrowthFailure::Stopped {
                error,
                summary: None,
            } => write!(f, "{error}"),
            GrowthFailure::Stopped {
                error,
                summary: Some(w),
            } => write!(f, "{error} (and summary.json could not be written: {w})"),
            GrowthFailure::Unwritten { error, .. } => write!(f, "{error}"),
        }
    }
}

/// Grow the eye of `scene` (which must have a `[growth]` section) with `writer` writing
/// its run directory as results come; `watch` sees every event after the writer (a
/// progress bar: a snapshot reaches it once it is on disk).
pub fn grow_with(scene: &Scene, mut writer: GrowthWriter, watch: &mut dyn Observer) -> GrownRun {
    let problem = match scene.growth_problem() {
        Ok(Some(problem)) => Ok(problem),
        Ok(None) => Err("the scene has no [growth] section".to_string()),
        // Unreachable for a scene read as a scene is (validated when read and set).
        Err(e) => Err(e.to_string()),
    };
    let problem = match problem {
        Ok(problem) => problem,
        Err(reason) => {
            let error = GrowthError {
                t: 0.0,
                reason,
                stats: Box::default(),
            };
            let summary = writer.fail(&error).err();
            return GrownRun {
                last: None,
                outcome: Err(GrowthFailure::Stopped { error, summary }),
            };
        }
    };
    let outcome = crate::growth::grow(
        &problem,
        &mut Tee {
            writer: &mut writer,
            watch,
        },
    );
    let last = writer.last_row().copied();
    let outcome = match outcome {
        Ok(stats) => match writer.finish(&stats) {
            Ok(dir) => Ok((stats, dir)),
            Err(error) => Err(GrowthFailure::Unwritten {
                stats: Box::new(stats),
                error,
            }),
        },
        Err(error) => {
            let summary = writer.fail(&error).err();
            Err(GrowthFailure::Stopped { error, summary })
        }
    };
    GrownRun { last, outcome }
}

/// The writer first, then the watcher.
struct Tee<'a, 'b> {
    writer: &'a mut GrowthWriter,
    watch: &'b mut dyn Observer,
}

impl Observer for Tee<'_, '_> {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        self.writer.snapshot(s)?;
        self.watch.snapshot(s)
    }

    fn history(&mut self, row: &SeriesRow) -> Result<(), ObserverError> {
        self.writer.history(row)?;
        self.watch.history(row)
    }

    fn progress(&mut self, t: f64, t_end: f64) -> Result<(), ObserverError> {
        self.writer.progress(t, t_end)?;
        self.watch.progress(t, t_end)
    }

    fn sensitivities(&mut self, rows: &[SensitivityRow]) -> Result<(), ObserverError> {
        self.writer.sensitivities(rows)?;
        self.watch.sensitivities(rows)
    }
}
